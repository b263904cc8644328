"""Model files (JSON): writing, reading and the registry of model kinds.

A model file is JSON::

    {"format": "hystcomp-model", "version": 1, "kind": "pi" | "mpi" | ...,
     "hyperparameters": {...}, "parameters": {...}, "fit_report": {...}}

Never pickle: a model file is data, readable by any program and safe to open. Reading one
checks its shape before any model is built (:func:`model_from_dict`): the keys a kind's
``from_parameters`` takes, JSON numbers (never NaN/Infinity, never text or booleans) or
arrays of them, a bounded size; every value is then validated by ``from_parameters``.
Files are written atomically (:mod:`hystcomp.io.atomic`).
"""

from __future__ import annotations

import inspect
import json
import os
from typing import Any, TypeAlias

from hystcomp._notice import Notice
from hystcomp._validation import as_path
from hystcomp.errors import HystcompError, InvalidTypeError, ModelFileError
from hystcomp.io._formats import utf16
from hystcomp.io.atomic import atomic_path
from hystcomp.models.base import HysteresisModel
from hystcomp.models.dynamics import LinearDynamics
from hystcomp.models.hammerstein import HammersteinModel
from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
from hystcomp.models.multiaxis import AXIS_KINDS, MAX_AXES, MultiAxisModel
from hystcomp.models.pi import PrandtlIshlinskii
from hystcomp.models.preisach import Preisach

MODEL_FORMAT = "hystcomp-model"
MODEL_VERSION = 1
#: Largest model file read (bytes); a model has a few hundred numbers, not millions.
MAX_MODEL_FILE_BYTES = 64 * 2**20

#: What a model file holds: a hysteresis model, the linear dynamics (not a hysteresis
#: model), or both identified as one pair.
Model: TypeAlias = HysteresisModel | LinearDynamics | HammersteinModel | MultiAxisModel

#: Model classes by the ``kind`` written in model files.
MODEL_KINDS: dict[str, type[Model]] = {
    PrandtlIshlinskii.kind: PrandtlIshlinskii,
    ModifiedPrandtlIshlinskii.kind: ModifiedPrandtlIshlinskii,
    Preisach.kind: Preisach,
    LinearDynamics.kind: LinearDynamics,  # the linear dynamics (creep, resonance)
    HammersteinModel.kind: HammersteinModel,  # a hysteresis model and dynamics, one pair
    MultiAxisModel.kind: MultiAxisModel,  # N coupled axes: a model per axis and the coupling
}
#: The kinds a pair's parts may have.
PAIR_PARTS = {"hysteresis": ("pi", "mpi", "preisach"), "dynamics": ("dynamics",)}


def model_to_dict(model: Model) -> dict[str, Any]:
    """The JSON document of a model (format, version, then the model's own dictionary).

    Parameters
    ----------
    model : model
        A fitted model of a kind that :data:`MODEL_KINDS` lists.

    Returns
    -------
    dict
        ``{"format", "version", "kind", ...}``, ready for ``json.dumps``.
    """
    if not isinstance(model, tuple(MODEL_KINDS.values())):
        raise InvalidTypeError(
            f"'model' must be one of hystcomp's models ({', '.join(sorted(MODEL_KINDS))}). "
            f"Got {type(model).__name__}."
        )
    return {"format": MODEL_FORMAT, "version": MODEL_VERSION, **model.to_dict()}


def model_text(model: Model) -> str:
    """The model file's text (JSON) for ``model``.

    Parameters
    ----------
    model : model
        The fitted model to write: its :func:`model_to_dict`, as indented JSON.

    Returns
    -------
    str
        The JSON text of the model file, ending in a newline.

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


def save_model(model: Model, path: str | os.PathLike) -> None:
    """Write ``model`` to ``path`` as JSON (atomically: a failure leaves ``path`` as it was).

    Parameters
    ----------
    model : model
        A fitted model of a kind that :data:`MODEL_KINDS` lists.
    path : str or os.PathLike
        The model file to write (JSON).
    """
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


def _check_document(doc: Any, source: str) -> type[Model]:
    """Check the shape of a model document and return the class of its kind."""
    if not isinstance(doc, dict) or doc.get("format") != MODEL_FORMAT:
        raise ModelFileError(
            Notice(
                '{source} is not a hystcomp model file (no "format": "{format}"). Give a file '
                "written by {saved_by}.",
                source=source,
                format=MODEL_FORMAT,
            )
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
    if issubclass(cls, HammersteinModel):
        for part, kinds in PAIR_PARTS.items():
            inner = doc.get(part)
            if not isinstance(inner, dict) or inner.get("kind") not in kinds:
                raise ModelFileError(
                    f'{source} has no "{part}" object of kind {" or ".join(kinds)}, which a '
                    "'hammerstein' model (a pair) holds; the file is corrupt or was edited "
                    "by hand."
                )
            _check_document(
                {"format": MODEL_FORMAT, "version": version, **inner}, f"{source} ({part})"
            )
        if "fit_report" in doc and not isinstance(doc["fit_report"], dict):
            raise ModelFileError(f'{source} has a "fit_report" that is not an object.')
        return cls
    if issubclass(cls, MultiAxisModel):
        _check_multiaxis(doc, version, source)
        return cls
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


def _check_multiaxis(doc: dict, version: int, source: str) -> None:
    """The shape of a multi-axis document: an "axes" list of axis models and a square
    "coupling" matrix of as many rows."""
    axes = doc.get("axes")
    if not isinstance(axes, list) or not 1 <= len(axes) <= MAX_AXES:
        raise ModelFileError(
            f'{source} has no "axes" list of 1 to {MAX_AXES} axis models, which a '
            "'multiaxis' model holds; the file is corrupt or was edited by hand."
        )
    for i, inner in enumerate(axes):
        if not isinstance(inner, dict) or inner.get("kind") not in AXIS_KINDS:
            raise ModelFileError(
                f"{source} has an axis {i + 1} that is not a model of kind "
                f"{' or '.join(AXIS_KINDS)}; the file is corrupt or was edited by hand."
            )
        _check_document(
            {"format": MODEL_FORMAT, "version": version, **inner}, f"{source} (axis {i + 1})"
        )
    coupling = doc.get("coupling")
    _check_value(coupling, '"coupling"', source)
    if not (
        isinstance(coupling, list)
        and len(coupling) == len(axes)
        and all(isinstance(row, list) and len(row) == len(axes) for row in coupling)
    ):
        raise ModelFileError(
            f'{source} has a "coupling" that is not a {len(axes)} x {len(axes)} matrix (one '
            "row and column per axis); the file is corrupt or was edited by hand."
        )
    for key in ("hyperparameters", "fit_report"):
        if key in doc and not isinstance(doc[key], dict):
            raise ModelFileError(f'{source} has a "{key}" that is not an object.')


def model_from_dict(doc: Any, source: str = "the model document") -> Model:
    """Build a model from a JSON document, checking format, version, kind, keys and values.

    Parameters
    ----------
    doc : Any
        The parsed JSON document.
    source : str, optional
        How error messages name the document (the file's path).

    Returns
    -------
    model
        The model the document describes, validated.

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


def load_model(path: str | os.PathLike) -> Model:
    """Read a model file written by :func:`save_model` or the ``hystcomp`` command.

    Parameters
    ----------
    path : str or os.PathLike
        The model file (JSON).

    Returns
    -------
    model
        The model the file holds, fitted: a PI, MPI or Preisach model, linear dynamics,
        a Hammerstein pair or a multi-axis model (the kinds of :data:`MODEL_KINDS`).

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
        text = path.read_text(encoding="utf-8-sig")  # a byte-order mark, as editors add
    except FileNotFoundError:
        raise ModelFileError(f"Model file {name} does not exist; check the path.") from None
    except UnicodeDecodeError:
        raise ModelFileError(
            f"{name} is "
            + (
                "UTF-16 text; save it as UTF-8."
                if utf16(path)
                else "not a text file; a model file is JSON written by hystcomp."
            )
        ) from None
    except OSError as exc:
        raise ModelFileError(f"Cannot read model file {name}: {exc.strerror or exc}.") from None
    try:
        doc = json.loads(text, parse_constant=_refuse_constant)
    except json.JSONDecodeError as exc:
        raise ModelFileError(
            Notice(
                "{name} is not valid JSON (line {line}: {why}); a model file is written by "
                "{saved_by}.",
                name=name,
                line=exc.lineno,
                why=exc.msg,
            )
        ) from None
    except ValueError as exc:  # NaN/Infinity, or an integer too long to read
        if "integer string conversion" in str(exc):
            raise ModelFileError(
                f"{name} holds an integer of thousands of digits, which no model parameter "
                "can be. Model files hold finite numbers only."
            ) from None
        raise ModelFileError(
            f"{name} is not a valid model file: {exc}. Model files hold finite numbers only."
        ) from None
    except RecursionError:
        raise ModelFileError(
            f"{name} nests arrays or objects too deeply to be a model file."
        ) from None
    return model_from_dict(doc, source=name)
