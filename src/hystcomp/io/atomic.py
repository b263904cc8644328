"""Atomic outputs: checks on an output path, and writes that never leave a broken file.

Every file hystcomp writes goes through here. A command checks its output paths before
any work (:func:`check_output_path`), writes to temporary files beside them
(:func:`atomic_paths`, :func:`atomic_path`, or :func:`staging_folder` for a set of files)
and renames them into place only on success, all or none (:func:`replace_all`).

Signals (:mod:`hystcomp._signals`): every temporary is made and registered under the
signals' lock, after a check that no signal is pending, and :func:`replace_all` renames
under that lock only while none is (:func:`hystcomp._signals.commit`); a signal that ends
the command removes what is registered (:func:`remove_pending`), so an interrupted
command leaves no temporary and replaces no output, whatever the moment.

A leaf: this module imports only the standard library, :mod:`hystcomp.errors`,
:mod:`hystcomp._signals` and :mod:`hystcomp._validation`, never a model or a record
reader, so that writing a file loads nothing else.
"""

from __future__ import annotations

import contextlib
import functools
import os
import shutil
import tempfile
from pathlib import Path

from hystcomp import _signals
from hystcomp._validation import as_path
from hystcomp.errors import InvalidParameterError, OutputPathError


def check_output_path(path: str | os.PathLike, *, inputs=(), what: str = "output") -> Path:
    """Check that ``path`` can be written without harm, before any work is done.

    Parameters
    ----------
    path : str or path-like
        The file to write.
    inputs : sequence of str or path-like
        Files the same command reads: writing over one of them would destroy it.
    what : str
        What the file is, for messages (e.g. ``"model file"``).

    Returns
    -------
    Path

    Raises
    ------
    OutputPathError
        If the folder does not exist, ``path`` is a folder, a device, a pipe or a socket
        (replacing one would break what uses it), or ``path`` is one of ``inputs``. A
        symbolic link is checked as the file it names (see :func:`write_target`).
    """
    if isinstance(path, str) and not path:
        raise OutputPathError(f"Cannot write the {what}: its path is empty. Give a file name.")
    path = as_path(path, "path", "check_output_path")
    if path.is_dir():
        raise OutputPathError(
            f"Cannot write the {what} {str(path)!r}: it is a folder. Give a file name, "
            f"e.g. {str(path / 'out')!r} with a suffix."
        )
    target = write_target(path)
    # (the path itself too: /dev/stdout names a pipe through a link realpath cannot follow)
    if (target.exists() and not target.is_file()) or (path.exists() and not path.is_file()):
        raise OutputPathError(
            f"Cannot write the {what} {str(path)!r}: it is a device, a pipe or a socket, not "
            "a regular file, and replacing it would break whatever uses it. Choose a file."
        )
    if not target.parent.is_dir():
        why = "is a file, not a folder" if target.parent.exists() else "does not exist"
        raise OutputPathError(
            f"Cannot write the {what} {str(path)!r}: the folder {str(target.parent)!r} {why}. "
            "Create the folder first or choose another output path."
        )
    for source in inputs:
        if source is not None and _same_file(path, as_path(source, "inputs", "check_output_path")):
            raise OutputPathError(
                f"Cannot write the {what} {str(path)!r}: it is the input file "
                f"{str(source)!r}, which would be overwritten. Choose another output path."
            )
    return path


def write_target(path: Path) -> Path:
    """The file a write to ``path`` replaces: ``path`` itself, or the file its symlink names.

    An output path that is a symbolic link keeps the link: the new contents replace the
    file it points to (atomically, in that file's folder), as ``open(path, "w")`` would,
    and a link to a missing file creates that file.

    Parameters
    ----------
    path : pathlib.Path
        An output path, possibly a symbolic link.

    Returns
    -------
    pathlib.Path
        The file the write replaces.
    """
    return Path(os.path.realpath(path)) if path.is_symlink() else path


#: Temporary files and folders being written now (see :func:`atomic_paths`), removed by
#: :func:`remove_pending` if a signal ends the command first.
_PENDING: set[Path] = set()
#: Folders made for a command's outputs, removed (if still empty) with the temporaries.
_MADE: set[Path] = set()


def remove_pending() -> None:
    """Remove every temporary output not yet renamed into place, and the folders made for
    outputs that are still empty (when a signal ends the command)."""
    with _signals.lock():
        for tmp in list(_PENDING):
            discard_temporary(tmp)
        for folder in sorted(_MADE, key=lambda p: len(p.parts), reverse=True):
            with contextlib.suppress(OSError):
                folder.rmdir()  # only if empty
            _MADE.discard(folder)


_signals.add_cleanup(remove_pending)


def _new_temporary(make) -> Path:
    """``make()`` (a new temporary file or folder, its path) under the signals' lock,
    registered before the lock is let go; refused if a signal is pending."""
    with _signals.lock():
        _signals.check()
        path = Path(make())
        _PENDING.add(path)
    return path


def new_temporary_folder(prefix: str) -> Path:
    """A new folder in the system's temporary folder, registered as a pending temporary
    (removed if a signal ends the command); :func:`discard_temporary` removes it.

    Parameters
    ----------
    prefix : str
        The start of the folder's name.

    Returns
    -------
    pathlib.Path
        The new, empty folder.
    """
    return _new_temporary(lambda: tempfile.mkdtemp(prefix=prefix))


def discard_temporary(path: Path) -> None:
    """Remove a temporary of :func:`new_temporary_folder` (or file) and forget it.

    Parameters
    ----------
    path : pathlib.Path
        The temporary folder or file to remove.
    """
    with contextlib.suppress(OSError):
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            os.unlink(path)
    _PENDING.discard(path)


def track_new_folder(path: Path) -> None:
    """Remember that ``path`` was made for a command's outputs: :func:`remove_pending`
    removes it if it is still empty (see :func:`forget_folder`).

    Parameters
    ----------
    path : pathlib.Path
        A folder just made for a command's outputs.
    """
    with _signals.lock():
        _MADE.add(Path(path))


def forget_folder(path: Path, *, remove: bool) -> None:
    """Stop tracking ``path`` (:func:`track_new_folder`); ``remove``: remove it now if it
    is empty (the command failed).

    Parameters
    ----------
    path : pathlib.Path
        A folder registered with :func:`track_new_folder`.
    remove : bool
        Whether to remove it now if it is empty.
    """
    with _signals.lock():
        _MADE.discard(Path(path))
        if remove:
            with contextlib.suppress(OSError):
                Path(path).rmdir()


@contextlib.contextmanager
def staging_folder(directory: Path):
    """Yield a new hidden folder inside ``directory``, removed with all it holds on exit.

    For a command that writes a set of files: write them there, then move them into place
    with :func:`replace_all`.

    Parameters
    ----------
    directory : pathlib.Path
        The folder the outputs go to, where the staging folder is made.

    Yields
    ------
    pathlib.Path
        The staging folder.
    """
    stage = _new_temporary(
        lambda: tempfile.mkdtemp(prefix=".hystcomp-", suffix=".tmp", dir=directory)
    )
    try:
        yield stage
    finally:
        shutil.rmtree(stage, ignore_errors=True)
        _PENDING.discard(stage)


def _same_file(a: Path, b: Path) -> bool:
    with contextlib.suppress(OSError):
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    return os.path.abspath(a) == os.path.abspath(b)


def _mode_for(path: Path) -> int:
    """Permissions for a new ``path``: those of the file it replaces, else the umask's."""
    with contextlib.suppress(OSError):
        return path.stat().st_mode & 0o777
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


@contextlib.contextmanager
def atomic_paths(*paths: str | os.PathLike):
    """Yield a list of temporary paths beside ``paths``; on success rename each onto its path.

    All outputs of a command are written to temporary files first, so a failure anywhere
    leaves every existing file untouched and removes the temporary files. Each temporary
    name keeps its path's suffix, so writers that choose the format by suffix work on it.

    Parameters
    ----------
    *paths : str or os.PathLike
        The output files of one command.

    Yields
    ------
    list of pathlib.Path
        One temporary file per output, in the same order, each beside its output and with its
        suffix.

    Raises
    ------
    OutputPathError
        If a path cannot be written (see :func:`check_output_path`), or the write fails
        (permissions, a full disk).
    """
    if not paths:
        raise InvalidParameterError("atomic_paths needs at least one path to write.")
    targets = [write_target(check_output_path(p)) for p in paths]
    tmps: list[Path] = []
    current: Path | None = targets[0]
    try:
        try:
            for target in targets:
                current = target
                name = _new_temporary(functools.partial(_temporary_file, target))
                tmps.append(name)
                os.chmod(name, _mode_for(target))
            current = None  # the caller writes any of them
            yield list(tmps)
            current = None
            replace_all(list(zip(tmps, targets, strict=True)))
        except OSError as exc:
            names = ", ".join(repr(str(p)) for p in ([current] if current else targets))
            raise OutputPathError(
                f"Cannot write {names}: {exc.strerror or exc}. Check the permissions and the "
                "free space of the folder."
            ) from None
        except OutputPathError as exc:  # a writer that writes atomically too: our names
            text = str(exc)
            for tmp, target in zip(tmps, targets, strict=False):
                text = text.replace(str(tmp), str(target))
            raise OutputPathError(text) from None
    finally:
        for tmp in tmps:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)
            _PENDING.discard(tmp)


def _temporary_file(target: Path) -> str:
    """A new empty hidden file beside ``target`` that keeps its suffix; its path."""
    fd, name = tempfile.mkstemp(
        prefix=f".{target.stem}.", suffix=f".tmp{target.suffix}", dir=target.parent
    )
    os.close(fd)
    return name


def replace_all(moves: list[tuple[Path, Path]]) -> None:
    """Rename each ``(new, path)`` onto ``path``, all or none.

    Each existing ``path`` is first kept under a hidden hard link (a copy where the file
    system has no links); if any rename fails, every ``path`` already replaced gets its
    old file back (or is removed if it had none), so the set of files is either all new
    or all as it was. The renames are a commit (:func:`hystcomp._signals.commit`):
    refused, before the first, once a signal is pending, and not interrupted by one;
    renames onto temporary files (a writer inside another's atomic output) are not the
    command's own commit.

    Parameters
    ----------
    moves : list of (pathlib.Path, pathlib.Path)
        Pairs ``(new, path)``: the complete new file and the path it replaces.

    Raises
    ------
    OSError
        From the rename that failed, after the rollback.
    hystcomp._signals.Interrupted
        A signal is pending: nothing renamed.
    """
    final = not all(path in _PENDING for _new, path in moves)
    with _signals.commit(final=final):
        _replace_all(moves)


def _replace_all(moves: list[tuple[Path, Path]]) -> None:
    backups: dict[Path, Path | None] = {}
    done: list[Path] = []
    try:
        for _new, path in moves:
            backups[path] = _backup(path) if path.exists() else None
        for new, path in moves:
            os.replace(new, path)
            done.append(path)
    except BaseException:
        for path in reversed(done):
            with contextlib.suppress(OSError):
                backup = backups[path]
                if backup is None:
                    os.unlink(path)
                else:
                    os.replace(backup, path)
                    del backups[path]
        raise
    finally:
        for backup in backups.values():
            if backup is not None:
                with contextlib.suppress(OSError):
                    os.unlink(backup)
                _PENDING.discard(backup)


def _backup(path: Path) -> Path:
    """A hidden hard link (or copy) of ``path`` beside it; registered as pending."""
    fd, name = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".old", dir=path.parent)
    os.close(fd)
    backup = Path(name)
    _PENDING.add(backup)
    os.unlink(backup)
    try:
        os.link(path, backup)
    except OSError:
        shutil.copy2(path, backup)
    return backup


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike):
    """Yield a temporary path beside ``path``; on success rename it onto ``path``.

    A failure leaves any existing ``path`` untouched and removes the temporary file
    (:func:`atomic_paths` with one path).

    Parameters
    ----------
    path : str or os.PathLike
        The output file.

    Yields
    ------
    pathlib.Path
        The temporary file to write, beside ``path`` and with its suffix.
    """
    with atomic_paths(path) as (tmp,):
        yield tmp


def write_all(writers: dict) -> list[Path]:
    """Write several outputs at once: all of them, or none if one write fails.

    Parameters
    ----------
    writers : dict of path to callable
        Each output path, with a function that writes its contents to the temporary path it
        is given (renamed onto the output once every write has succeeded).

    Returns
    -------
    list of pathlib.Path
        The outputs written, in the order given.
    """
    with atomic_paths(*writers) as temporaries:
        for write, tmp in zip(writers.values(), temporaries, strict=True):
            write(tmp)
    return [Path(path) for path in writers]


def refusal(exc: OSError) -> str:
    """Why the system refused a path or a write, and what to check, as one sentence.

    Parameters
    ----------
    exc : OSError
        The refusal, with the path it names if any (``filename``).

    Returns
    -------
    str
        E.g. ``"cannot use 'out.csv': Permission denied. Check the path ..."``.
    """
    where = f" {os.fsdecode(exc.filename)[:120]!r}" if exc.filename else ""
    return (
        f"cannot use{where}: {exc.strerror or exc}. Check the path (the length of its names, "
        "that its folders exist and are folders), its permissions and the free space."
    )
