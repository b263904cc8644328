"""C99 export of compensators: a state struct and ``init`` / ``reset`` / ``step`` functions.

>>> import hystcomp
>>> from hystcomp.codegen import generate_c
>>> header, source = generate_c(hystcomp.presets.paper_pi().inverse(), prefix="stage_x")
>>> "double stage_x_step(stage_x_state *s, double x_ref);" in header
True

A template per kind of compensator (:data:`TEMPLATES`) describes its state, tables and step
(:class:`~hystcomp.codegen.c99.CTemplate`); :func:`~hystcomp.codegen.c99.render` writes
the same files for all of them. PI and MPI compensators share the chain template; the
Preisach compensators (both methods of ``Preisach.inverse``) have their own.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from hystcomp import paper
from hystcomp._validation import check_real
from hystcomp.codegen.c99 import CTemplate, check_prefix, render
from hystcomp.codegen.chain import chain_template
from hystcomp.codegen.preisach import preisach_template
from hystcomp.errors import InvalidParameterError, InvalidTypeError
from hystcomp.io.atomic import atomic_paths, check_output_path, forget_folder, track_new_folder

DEFAULT_PREFIX = "hystcomp_compensator"

#: Templates by the ``kind`` of the compensator.
TEMPLATES: dict[str, Callable[..., CTemplate]] = {
    "pi": chain_template,
    "mpi": chain_template,
    "preisach": preisach_template,
}

__all__ = ["DEFAULT_PREFIX", "TEMPLATES", "CTemplate", "check_prefix", "export_c", "generate_c"]


def generate_c(
    compensator,
    *,
    prefix: str = DEFAULT_PREFIX,
    source: str | None = None,
    sample_rate: float | None = None,
) -> tuple[str, str]:
    """The C99 header and source of ``compensator`` (see :func:`export_c`).

    Parameters
    ----------
    compensator : Compensator, PreisachCompensator or DynamicCompensator
        From ``model.inverse(...)``.
    prefix : str, optional
        NAME of the files, the state type and the functions; a C identifier.
    source : str, optional
        The model file, named in the header comment.
    sample_rate : float, optional
        Hz at which ``NAME_step`` is called, for the comments (the compensator's own if None).

    Returns
    -------
    (str, str)
        The texts of ``PREFIX.h`` and ``PREFIX.c``.
    """
    kind = getattr(compensator, "kind", None)
    if callable(getattr(compensator, "inverse", None)):  # a model, not its compensator
        raise InvalidTypeError(
            f"'compensator' must be a compensator; got the model {type(compensator).__name__}. "
            "Export its inverse: generate_c(model.inverse(), ...)."
        )
    if not hasattr(compensator, "voltage_range") or not isinstance(kind, str):
        raise InvalidTypeError(
            "'compensator' must be a hystcomp compensator, as returned by model.inverse(). "
            f"Got {type(compensator).__name__}."
        )
    if kind not in TEMPLATES:
        raise InvalidParameterError(
            f"C export supports compensators of kinds {sorted(TEMPLATES)}. "
            f"Got a compensator of kind {kind!r}."
        )
    check_prefix(prefix)
    sample_rate = _code_rate(compensator, sample_rate)
    inner = getattr(compensator, "hysteresis", compensator)  # a DynamicCompensator's
    template = TEMPLATES[kind](inner)
    if inner is not compensator:
        from hystcomp.codegen.dynamics import add_dynamics

        template = add_dynamics(template, compensator.dynamics_inverse)
    return render(template, prefix, source=source, sample_rate=sample_rate)


def _code_rate(compensator, sample_rate) -> float:
    """The rate (Hz) the code is called at: ``sample_rate``, else the compensator's own
    (the dynamics' rate of a compensator with them), else 20000. A compensator with
    dynamics runs at their rate only: another ``sample_rate`` is refused."""
    own = getattr(compensator, "sample_rate", None)
    if sample_rate is None:
        return paper.SAMPLE_RATE if own is None else float(own)
    sample_rate = check_real(sample_rate, "sample_rate", "generate_c", positive=True)
    if own is not None and abs(sample_rate - own) > 1e-9 * own:
        raise InvalidParameterError(
            f"The 'sample_rate' parameter of generate_c/export_c ({sample_rate:g} Hz) differs "
            f"from the rate of the compensator's dynamics ({own:g} Hz): its inverse of the "
            "dynamics, and so the code, runs at that rate only. Leave sample_rate out, or "
            "identify the dynamics at the rate the code is called."
        )
    return sample_rate


def export_c(
    compensator,
    directory: str | os.PathLike,
    *,
    prefix: str = DEFAULT_PREFIX,
    source: str | None = None,
    sample_rate: float | None = None,
    inputs=(),
) -> tuple[Path, Path]:
    """Write ``PREFIX.h`` and ``PREFIX.c``, a C99 version of ``compensator``, into ``directory``.

    The identified parameters are baked in; the code clamps its output to the compensator's
    voltage range, applies its slew-rate limit if it has one, and holds the last output on a
    non-finite reference, sample for sample as :meth:`Compensator.stepper` does.

    Parameters
    ----------
    compensator : Compensator
        From ``model.inverse(...)`` of a PI, MPI or Preisach model (for Preisach, either
        method: the inverse multiplicative structure of eq. 10 or the exact inverse).
    directory : path
        Output folder; created if its parent exists.
    prefix : str, default "hystcomp_compensator"
        Names the files, the state type ``PREFIX_state`` and the functions; a C identifier.
    source : str, optional
        The model file, named in the header comment.
    sample_rate : float, optional
        Hz at which the code is meant to be called, for the header comment (finite, > 0);
        by default the compensator's own (that of its dynamics), else 20000. A compensator
        with dynamics runs at their rate only: another rate is refused.
    inputs : sequence of path, optional
        Files the caller read (the model file): refused as outputs, never overwritten.

    Returns
    -------
    (Path, Path)
        The header and source written. Nothing is written if anything fails (a folder
        made for them is removed again), and existing
        files are replaced only once both new files are complete (both, or neither). The
        header defines ``PREFIX_PAIR_ID``, a hash of both files, which the source checks
        with ``#error``: a pair mixed from two exports does not compile.
    """
    header, source_text = generate_c(
        compensator, prefix=prefix, source=source, sample_rate=sample_rate
    )
    directory = Path(directory)
    if not directory.is_dir():
        if directory.exists():
            raise InvalidParameterError(
                f"Cannot write the C files into {str(directory)!r}: it exists and is not a "
                "folder. Choose an output folder (it is made if its parent exists)."
            )
        if not directory.parent.is_dir():
            raise InvalidParameterError(
                f"Cannot write the C files into {str(directory)!r}: its parent "
                f"{str(directory.parent)!r} is not an existing folder. Create it first or "
                "choose another output folder."
            )
        directory.mkdir()
        made = directory
        track_new_folder(made)  # removed (if empty) should a signal end the command
    else:
        made = None
    paths = (directory / f"{prefix}.h", directory / f"{prefix}.c")
    try:
        for path in paths:
            check_output_path(path, inputs=inputs)
        # both files checked before anything is written, renamed into place only once both are
        with atomic_paths(*paths) as (tmp_h, tmp_c):
            tmp_h.write_text(header, encoding="ascii")
            tmp_c.write_text(source_text, encoding="ascii")
    except BaseException:
        if made is not None:  # a failed export leaves no empty folder behind
            forget_folder(made, remove=True)
        raise
    if made is not None:
        forget_folder(made, remove=False)
    return paths
