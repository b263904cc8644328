"""Atomic outputs: checks on an output path, and writes that never leave a broken file.

Every file hystcomp writes goes through here. A command checks its output paths before
any work (:func:`check_output_path`), writes to temporary files beside them
(:func:`atomic_paths`, :func:`atomic_path`, or :func:`staging_folder` for a set of files)
and renames them into place only on success, all or none (:func:`replace_all`). A signal
handler removes the temporaries of an interrupted write with :func:`remove_pending`.

A leaf: this module imports only the standard library, :mod:`hystcomp.errors` and
:mod:`hystcomp._validation`, never a model or a record reader, so that writing a file
loads nothing else.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from pathlib import Path

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
    """
    return Path(os.path.realpath(path)) if path.is_symlink() else path


#: Temporary files being written now (see :func:`atomic_paths`), for a signal handler that
#: must remove them before the process ends (:func:`remove_pending`).
_PENDING: set[Path] = set()


def remove_pending() -> None:
    """Remove every temporary output not yet renamed into place (for signal handlers)."""
    for tmp in list(_PENDING):
        with contextlib.suppress(OSError):
            if tmp.is_dir() and not tmp.is_symlink():
                shutil.rmtree(tmp)
            else:
                os.unlink(tmp)
        _PENDING.discard(tmp)


@contextlib.contextmanager
def staging_folder(directory: Path):
    """Yield a new hidden folder inside ``directory``, removed with all it holds on exit.

    For a command that writes a set of files: write them there, then move them into place
    with :func:`replace_all`.
    """
    stage = Path(tempfile.mkdtemp(prefix=".hystcomp-", suffix=".tmp", dir=directory))
    _PENDING.add(stage)
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
                fd, name = tempfile.mkstemp(
                    prefix=f".{target.stem}.", suffix=f".tmp{target.suffix}", dir=target.parent
                )
                os.close(fd)
                tmps.append(Path(name))
                _PENDING.add(Path(name))
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


def replace_all(moves: list[tuple[Path, Path]]) -> None:
    """Rename each ``(new, path)`` onto ``path``, all or none.

    Each existing ``path`` is first kept under a hidden hard link (a copy where the file
    system has no links); if any rename fails, or the process is interrupted, every
    ``path`` already replaced gets its old file back (or is removed if it had none), so
    the set of files is either all new or all as it was.

    Raises
    ------
    OSError
        From the rename that failed, after the rollback.
    """
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
    """
    with atomic_paths(path) as (tmp,):
        yield tmp
