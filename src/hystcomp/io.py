"""Files: model files (JSON) and, for every output, writes that never leave a broken file.

A model file is JSON::

    {"format": "hystcomp-model", "version": 1, "kind": "pi" | "mpi" | ...,
     "hyperparameters": {...}, "parameters": {...}, "fit_report": {...}}

Never pickle: a model file is data, readable by any program and safe to open. Reading one
checks its shape before any model is built (:func:`model_from_dict`): the keys a kind's
``from_parameters`` takes, JSON numbers (never NaN/Infinity, never text or booleans) or
arrays of them, a bounded size; every value is then validated by ``from_parameters``.
"""

from __future__ import annotations

import contextlib
import inspect
import json
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any

from hystcomp._validation import as_path
from hystcomp.errors import (
    HystcompError,
    InvalidParameterError,
    InvalidTypeError,
    ModelFileError,
    OutputPathError,
)
from hystcomp.models.base import HysteresisModel
from hystcomp.models.dynamics import LinearDynamics
from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
from hystcomp.models.pi import PrandtlIshlinskii
from hystcomp.models.preisach import Preisach

MODEL_FORMAT = "hystcomp-model"
MODEL_VERSION = 1
#: Largest model file read (bytes); a model has a few hundred numbers, not millions.
MAX_MODEL_FILE_BYTES = 64 * 2**20

#: Model classes by the ``kind`` written in model files.
MODEL_KINDS: dict[str, type[HysteresisModel]] = {
    PrandtlIshlinskii.kind: PrandtlIshlinskii,
    ModifiedPrandtlIshlinskii.kind: ModifiedPrandtlIshlinskii,
    Preisach.kind: Preisach,
    LinearDynamics.kind: LinearDynamics,  # the linear dynamics (creep, resonance)
}


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
    path = as_path(path, "path", "check_output_path")
    if path.is_dir():
        raise OutputPathError(
            f"Cannot write the {what} {str(path)!r}: it is a folder. Give a file name, "
            f"e.g. {str(path / 'out')!r} with a suffix."
        )
    target = write_target(path)
    if target.exists() and not target.is_file():
        raise OutputPathError(
            f"Cannot write the {what} {str(path)!r}: it is a device, a pipe or a socket, not "
            "a regular file, and replacing it would break whatever uses it. Choose a file."
        )
    if not target.parent.is_dir():
        raise OutputPathError(
            f"Cannot write the {what} {str(path)!r}: the folder {str(target.parent)!r} does "
            "not exist. Create it first or choose another output path."
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
    paths = [write_target(check_output_path(p)) for p in paths]
    tmps: list[Path] = []
    current = paths[0]
    try:
        try:
            for current in paths:
                fd, tmp = tempfile.mkstemp(
                    prefix=f".{current.stem}.", suffix=f".tmp{current.suffix}", dir=current.parent
                )
                os.close(fd)
                tmps.append(Path(tmp))
                _PENDING.add(Path(tmp))
                os.chmod(tmp, _mode_for(current))
            current = None  # the caller writes any of them
            yield list(tmps)
            current = None
            replace_all(list(zip(tmps, paths, strict=True)))
        except OSError as exc:
            names = ", ".join(repr(str(p)) for p in ([current] if current else paths))
            raise OutputPathError(
                f"Cannot write {names}: {exc.strerror or exc}. Check the permissions and the "
                "free space of the folder."
            ) from None
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
                if backups[path] is None:
                    os.unlink(path)
                else:
                    os.replace(backups.pop(path), path)
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


def model_to_dict(model: HysteresisModel) -> dict[str, Any]:
    """The JSON document of a model (format, version, then the model's own dictionary)."""
    if not isinstance(model, tuple(MODEL_KINDS.values())):
        raise InvalidTypeError(
            f"'model' must be one of hystcomp's models ({', '.join(sorted(MODEL_KINDS))}). "
            f"Got {type(model).__name__}."
        )
    return {"format": MODEL_FORMAT, "version": MODEL_VERSION, **model.to_dict()}


def model_text(model: HysteresisModel) -> str:
    """The model file's text (JSON) for ``model``.

    Raises
    ------
    NotFittedError
        If the model has no parameters yet.
    ModelFileError
        If a parameter is not finite.
    """
    doc = model_to_dict(model)  # NotFittedError (a ValueError) before the JSON check
    try:
        return json.dumps(doc, indent=2, allow_nan=False) + "\n"
    except ValueError:
        raise ModelFileError(
            f"This {type(model).__name__} holds a non-finite number (NaN or infinity), which "
            "a model file cannot store; refit the model."
        ) from None


def save_model(model: HysteresisModel, path: str | os.PathLike) -> None:
    """Write ``model`` to ``path`` as JSON (atomically: a failure leaves ``path`` as it was)."""
    text = model_text(model)
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def _check_value(value: Any, where: str, source: str, *, depth: int = 0) -> None:
    """A parameter value: a JSON number, null, or an array (of arrays) of them."""
    if value is None or (isinstance(value, int | float) and not isinstance(value, bool)):
        return
    if isinstance(value, list | tuple) and depth < 2:
        for i, item in enumerate(value):
            _check_value(item, f"{where}[{i}]", source, depth=depth + 1)
        return
    if isinstance(value, bool):
        found = f"the boolean {json.dumps(value)}"
    elif isinstance(value, str):
        found = f"the text {value[:40]!r}"
    elif isinstance(value, list | tuple):
        found = "an array nested too deep"
    else:
        found = "an object"
    raise ModelFileError(
        f"{source} has {found} at {where}, where a number or an array of numbers belongs; "
        "the file is corrupt or was edited by hand."
    )


def _check_document(doc: Any, source: str) -> type[HysteresisModel]:
    """Check the shape of a model document and return the class of its kind."""
    if not isinstance(doc, dict) or doc.get("format") != MODEL_FORMAT:
        raise ModelFileError(
            f'{source} is not a hystcomp model file (no "format": "{MODEL_FORMAT}"). '
            "Give a file written by 'hystcomp identify' or hystcomp.save_model."
        )
    version = doc.get("version")
    if not isinstance(version, int) or isinstance(version, bool):
        raise ModelFileError(f'{source} has no integer "version"; the file is corrupt.')
    if version > MODEL_VERSION:
        raise ModelFileError(
            f"{source} has format version {version}, newer than this hystcomp reads "
            f"({MODEL_VERSION}). Upgrade hystcomp (pip install -U hystcomp)."
        )
    if version < 1:
        raise ModelFileError(f"{source} has an invalid format version {version}.")
    kind = doc.get("kind")
    if not isinstance(kind, str) or kind not in MODEL_KINDS:
        raise ModelFileError(
            f"{source} has model kind {kind!r}; expected one of {sorted(MODEL_KINDS)}. "
            "A newer hystcomp may know it: upgrade hystcomp."
        )
    cls = MODEL_KINDS[kind]
    params = doc.get("parameters")
    if not isinstance(params, dict):
        raise ModelFileError(f'{source} has no "parameters" object; the file is corrupt.')
    signature = inspect.signature(cls.from_parameters).parameters
    required = [n for n, p in signature.items() if p.default is inspect.Parameter.empty]
    for name in required:
        if name not in params:
            raise ModelFileError(
                f'{source} has no "{name}" in its parameters, which a {kind!r} model needs; '
                "the file is corrupt or was edited by hand."
            )
    for name, value in params.items():
        if name not in signature:
            raise ModelFileError(
                f'{source} has an unknown parameter "{name}" for a {kind!r} model (expected '
                f"{', '.join(signature)}); the file is corrupt or from another program."
            )
        _check_value(value, f'parameters["{name}"]', source)
    for key in ("hyperparameters", "fit_report"):
        if key in doc and not isinstance(doc[key], dict):
            raise ModelFileError(
                f'{source} has a "{key}" that is not an object; the file is corrupt.'
            )
    for name, value in doc.get("hyperparameters", {}).items():
        if isinstance(value, dict | list | tuple) and not (
            isinstance(value, list | tuple) and all(isinstance(v, int | float) for v in value)
        ):
            raise ModelFileError(
                f'{source} has an invalid hyperparameter "{name}" ({json.dumps(value)[:60]}); '
                "the file is corrupt or was edited by hand."
            )
    return cls


def model_from_dict(doc: Any, source: str = "the model document") -> HysteresisModel:
    """Build a model from a JSON document, checking format, version, kind, keys and values.

    Raises
    ------
    ModelFileError
        Naming the key at fault and the fix.
    """
    cls = _check_document(doc, source)
    try:
        return cls.from_dict(doc)
    except HystcompError as exc:
        raise ModelFileError(f"{source} holds invalid parameters: {exc}") from None
    except (TypeError, ValueError, KeyError, AttributeError, IndexError, OverflowError) as exc:
        raise ModelFileError(
            f"{source} holds invalid parameters for a {doc['kind']!r} model ({exc}); "
            "the file is corrupt or was edited by hand."
        ) from None
    except MemoryError:
        raise ModelFileError(
            f"{source} describes a model too large for this computer's memory; the file is "
            "corrupt or was edited by hand."
        ) from None


def _refuse_constant(name: str):
    raise ValueError(f"{name} is not a number a model file may hold")


def load_model(path: str | os.PathLike) -> HysteresisModel:
    """Read a model file written by :func:`save_model` or the ``hystcomp`` command.

    Raises
    ------
    ModelFileError
        If the file is missing, not a regular file, too large, not JSON, holds NaN or
        Infinity, or is not a valid model of a known kind and supported version.
    """
    path = as_path(path, "path", "load_model")
    name = repr(str(path))
    try:
        if path.is_dir():
            raise ModelFileError(f"{name} is a folder, not a model file.")
        if path.exists() and not path.is_file():
            raise ModelFileError(f"{name} is not a regular file (a device or a pipe?).")
        if path.exists() and path.stat().st_size > MAX_MODEL_FILE_BYTES:
            raise ModelFileError(
                f"{name} is {path.stat().st_size} bytes, too large for a model file "
                f"(at most {MAX_MODEL_FILE_BYTES}); check the path."
            )
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ModelFileError(f"Model file {name} does not exist; check the path.") from None
    except UnicodeDecodeError:
        raise ModelFileError(
            f"{name} is not a text file; a model file is JSON written by hystcomp."
        ) from None
    except OSError as exc:
        raise ModelFileError(f"Cannot read model file {name}: {exc.strerror or exc}.") from None
    try:
        doc = json.loads(text, parse_constant=_refuse_constant)
    except json.JSONDecodeError as exc:
        raise ModelFileError(
            f"{name} is not valid JSON (line {exc.lineno}: {exc.msg}); "
            "a model file is written by 'hystcomp identify' or hystcomp.save_model."
        ) from None
    except ValueError as exc:  # NaN/Infinity, or an integer too long to read
        raise ModelFileError(
            f"{name} is not a valid model file: {exc}. Model files hold finite numbers only."
        ) from None
    except RecursionError:
        raise ModelFileError(
            f"{name} nests arrays or objects too deeply to be a model file."
        ) from None
    return model_from_dict(doc, source=name)
