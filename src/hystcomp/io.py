"""Files: model files (JSON) and, for every output, writes that never leave a broken file.

A model file is JSON::

    {"format": "hystcomp-model", "version": 1, "kind": "pi" | "mpi" | ...,
     "hyperparameters": {...}, "parameters": {...}, "fit_report": {...}}

Never pickle: a model file is data, readable by any program and safe to open.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from pathlib import Path
from typing import Any

from hystcomp.errors import HystcompError, InvalidTypeError, ModelFileError
from hystcomp.models.base import HysteresisModel
from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
from hystcomp.models.pi import PrandtlIshlinskii
from hystcomp.models.preisach import Preisach

MODEL_FORMAT = "hystcomp-model"
MODEL_VERSION = 1

#: Model classes by the ``kind`` written in model files.
MODEL_KINDS: dict[str, type[HysteresisModel]] = {
    PrandtlIshlinskii.kind: PrandtlIshlinskii,
    ModifiedPrandtlIshlinskii.kind: ModifiedPrandtlIshlinskii,
    Preisach.kind: Preisach,
}


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike):
    """Yield a temporary path beside ``path``; on success rename it onto ``path``.

    A failure leaves any existing ``path`` untouched and removes the temporary file.
    """
    path = Path(path)
    if not path.parent.is_dir():
        raise ModelFileError(
            f"Cannot write {str(path)!r}: the folder {str(path.parent)!r} does not exist. "
            "Create it first or choose another output path."
        )
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)


def model_to_dict(model: HysteresisModel) -> dict[str, Any]:
    """The JSON document of a model (format, version, then the model's own dictionary)."""
    if not isinstance(model, tuple(MODEL_KINDS.values())):
        raise InvalidTypeError(
            f"'model' must be one of hystcomp's models ({', '.join(sorted(MODEL_KINDS))}). "
            f"Got {type(model).__name__}."
        )
    return {"format": MODEL_FORMAT, "version": MODEL_VERSION, **model.to_dict()}


def save_model(model: HysteresisModel, path: str | os.PathLike) -> None:
    """Write ``model`` to ``path`` as JSON (atomically: a failure leaves ``path`` as it was)."""
    text = json.dumps(model_to_dict(model), indent=2, allow_nan=False)
    with atomic_path(path) as tmp:
        tmp.write_text(text + "\n", encoding="utf-8")


def model_from_dict(doc: Any, source: str = "the model document") -> HysteresisModel:
    """Build a model from a JSON document, checking format, version, kind and values."""
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
    if kind not in MODEL_KINDS:
        raise ModelFileError(
            f"{source} has model kind {kind!r}; expected one of {sorted(MODEL_KINDS)}."
        )
    if not isinstance(doc.get("parameters"), dict):
        raise ModelFileError(f'{source} has no "parameters" object; the file is corrupt.')
    try:
        return MODEL_KINDS[kind].from_dict(doc)
    except HystcompError as exc:
        raise ModelFileError(f"{source} holds invalid parameters: {exc}") from None
    except (TypeError, ValueError, KeyError) as exc:
        raise ModelFileError(
            f"{source} holds invalid parameters for a {kind!r} model ({exc}); "
            "the file is corrupt or was edited by hand."
        ) from None


def load_model(path: str | os.PathLike) -> HysteresisModel:
    """Read a model file written by :func:`save_model` or the ``hystcomp`` command."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ModelFileError(f"Model file {str(path)!r} does not exist; check the path.") from None
    except IsADirectoryError:
        raise ModelFileError(f"{str(path)!r} is a folder, not a model file.") from None
    except UnicodeDecodeError:
        raise ModelFileError(
            f"{str(path)!r} is not a text file; a model file is JSON written by hystcomp."
        ) from None
    except OSError as exc:
        raise ModelFileError(f"Cannot read model file {str(path)!r}: {exc.strerror}.") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ModelFileError(
            f"{str(path)!r} is not valid JSON (line {exc.lineno}: {exc.msg}); "
            "a model file is written by 'hystcomp identify' or hystcomp.save_model."
        ) from None
    return model_from_dict(doc, source=repr(str(path)))
