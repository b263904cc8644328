"""The N-axis side of the commands: ``excite multiaxis``, and ``identify``, ``compensate``,
``simulate`` and ``export-c`` on N-axis files and models.

Each command detects an N-axis file (columns ``v1``, ``x1``, ...) or a multi-axis model and
hands over to a function here; the options keep their meaning per axis.
"""

from __future__ import annotations

import sys
import warnings

import click
import numpy as np

from hystcomp.cli._options import check_data_output, progress, slew_sample_rate
from hystcomp.errors import HystcompWarning, InvalidSignalError, OutputPathError


def _read_options(columns, sample_rate, x_unit, quiet, path) -> dict:
    from hystcomp._progress import Progress

    options = {"columns": columns, "sample_rate": sample_rate, "x_unit": x_unit}
    if not quiet:
        options["progress"] = Progress(f"reading {click.format_filename(str(path))}")
    return options


def refuse(option: str, value, why: str) -> None:
    """Refuse, in the command's words, an option that an N-axis file or model does not take."""
    if value is not None and value is not False:
        raise click.UsageError(f"{option} does not apply to {why}.")


def excite_multiaxis(n_axes, output, sample_rate, voltage_range, frequency, quiet) -> None:
    """``hystcomp excite multiaxis --axes N``: columns t, v1..vN."""
    from hystcomp.identify.multiaxis_excitation import multiaxis_sequence
    from hystcomp.io.records import format_csv, write_table

    if output is not None:
        check_data_output(output, what="signal file")
    t, V = multiaxis_sequence(
        n_axes, sample_rate=sample_rate, voltage_range=voltage_range, frequency=frequency
    )
    table = {"t": t, **{f"v{i + 1}": V[:, i] for i in range(n_axes)}}
    if output is None:
        try:
            click.echo(format_csv(table), nl=False)
            sys.stdout.flush()
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise OutputPathError(
                f"Cannot write the signal to standard output: {exc.strerror or exc}. Give a "
                "file with -o, or check where standard output goes."
            ) from None
        return
    write_table(output, table, progress=progress(f"writing {output}", quiet))
    click.echo(
        f"wrote {output}: {t.size} samples of {n_axes} axes at {sample_rate:g} Hz ({t[-1]:g} s)"
    )


def identify_multiaxis(
    data,
    output,
    *,
    kind,
    options,
    columns,
    sample_rate,
    x_unit,
    quiet,
    transient,
    voltage_range,
    allow_extrapolation,
    n_jobs=None,
) -> None:
    """``hystcomp identify`` on an N-axis record."""
    from hystcomp.identify.workflow import extrapolation_error
    from hystcomp.io.atomic import atomic_paths
    from hystcomp.io.models import model_text
    from hystcomp.io.multiaxis import read_axes
    from hystcomp.workflows.multiaxis import identify_axes

    table = read_axes(data, ("v", "x"), **_read_options(columns, sample_rate, x_unit, quiet, data))
    why = None if voltage_range is None else extrapolation_error(voltage_range, table["v"])
    if why is not None and not allow_extrapolation:
        raise click.BadParameter(
            f"{why} (over the axes): the compensators would command voltages the models never "
            "saw. Give a range within the record, or pass --allow-extrapolation.",
            param_hint="'--voltage-range'",
        )
    given = {k: v for k, v in options.items() if v is not None}
    with progress(f"identifying {table['v'].shape[1]} axes", quiet).ticking():
        result = identify_axes(
            table["t"],
            table["v"],
            table["x"],
            kind=kind,
            n_jobs=n_jobs,
            source=str(data),
            voltage_range=voltage_range,
            allow_extrapolation=allow_extrapolation,
            transient=transient,
            unit_check=False,
            **given,
        )
    for line in result.lines:
        click.echo(line)
    for warning in result.warnings:
        click.echo(f"hystcomp: warning: {warning}", err=True)
    text = model_text(result.model)
    with atomic_paths(output) as (tmp,):
        tmp.write_text(text, encoding="utf-8")
    click.echo(f"  wrote {output}")


def _narrow(model, narrow_range):
    if narrow_range is None:
        return None
    low, high = narrow_range
    for i, (lo, hi) in enumerate(model.voltage_range_, 1):
        if low < lo or high > hi:
            raise click.BadParameter(
                f"may only narrow each axis's voltage range; axis {i} has {lo:g} .. {hi:g} V. "
                f"Got {low:g} {high:g}; choose limits within every axis's range.",
                param_hint="'--voltage-range'",
            )
    return narrow_range


def compensate_multiaxis(
    model,
    model_file,
    reference_file,
    output,
    *,
    columns,
    sample_rate,
    x_unit,
    quiet,
    slew_rate,
    narrow_range,
    method,
    strict,
) -> None:
    """``hystcomp compensate`` with a multi-axis model: t, x1..xN -> t, v1..vN, x1_ref..xN_ref."""
    from hystcomp.io.multiaxis import read_axes
    from hystcomp.io.records import write_table

    check_data_output(output, inputs=(model_file, reference_file), what="voltage file")
    table = read_axes(
        reference_file, ("x",), **_read_options(columns, sample_rate, x_unit, quiet, reference_file)
    )
    X = table["x"]
    n = model.n_axes
    if X.shape[1] != n:
        raise InvalidSignalError(
            f"{reference_file!r} holds references for {X.shape[1]} axes (x1..x{X.shape[1]}), "
            f"but {model_file} is a model of {n} axes: give one column per axis, x1..x{n}."
        )
    options: dict = {"voltage_range": _narrow(model, narrow_range)}
    if slew_rate is not None:
        options.update(
            slew_rate=slew_rate, sample_rate=slew_sample_rate(table["t"], reference_file)
        )
    if method is not None:
        if not any(a.kind == "preisach" for a in model.axes_):
            raise click.BadParameter(
                f"applies to Preisach axes only; {model_file} has none. Drop --method.",
                param_hint="'--method'",
            )
        options["method"] = method
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HystcompWarning)
        compensator = model.inverse(**options)
    with progress("computing the voltages", quiet).ticking():
        result = compensator.run(X)
    H = X @ np.asarray(compensator.decoupling).T
    told = []
    for i, clamped in enumerate(result.clamped):
        if not clamped:
            continue
        lo, hi = compensator.voltage_range[i]
        r_lo, r_hi = model.axes_[i].reachable_range(voltage_range=(lo, hi))
        told.append(
            f"axis {i + 1}: {clamped} of {X.shape[0]} samples ({100 * clamped / X.shape[0]:.3g} "
            f"%) are out of reach and clamped to {lo:.4g} .. {hi:.4g} V: its own displacement "
            f"asked for (the reference with the other axes' coupling taken out) spans "
            f"{H[:, i].min():.4g} .. {H[:, i].max():.4g} µm, the axis reaches {r_lo:.4g} .. "
            f"{r_hi:.4g} µm"
        )
    if told and strict:
        raise InvalidSignalError(
            f"{told[0]}. Nothing written (--strict); shift or scale that axis's reference, or "
            "drop --strict to accept the clamp."
        )
    for line in told:
        click.echo(f"hystcomp: warning: {line}.", err=True)
    V = result.v
    out = {"t": table["t"]}
    out.update({f"v{i + 1}": V[:, i] for i in range(n)})
    out.update({f"x{i + 1}_ref": X[:, i] for i in range(n)})
    write_table(output, out, progress=progress(f"writing {output}", quiet))
    ranges = ", ".join(f"v{i + 1} {V[:, i].min():.4g} .. {V[:, i].max():.4g} V" for i in range(n))
    click.echo(
        f"wrote {output}: {V.shape[0]} samples of {n} axes ({ranges}; "
        f"{sum(result.clamped)} clamped)"
    )


def simulate_multiaxis(
    model, model_file, input_file, output, *, columns, sample_rate, x_unit, quiet
) -> None:
    """``hystcomp simulate`` with a multi-axis model: t, v1..vN -> t, v1..vN, x1..xN."""
    from hystcomp.io.multiaxis import read_axes
    from hystcomp.io.records import write_table

    check_data_output(output, inputs=(model_file, input_file), what="result file")
    table = read_axes(
        input_file, ("v",), **_read_options(columns, sample_rate, x_unit, quiet, input_file)
    )
    V = table["v"]
    n = model.n_axes
    if V.shape[1] != n:
        raise InvalidSignalError(
            f"{input_file!r} holds voltages for {V.shape[1]} axes, but {model_file} is a model "
            f"of {n} axes: give one column per axis, v1..v{n}."
        )
    for i, (lo, hi) in enumerate(model.voltage_range_):
        if V[:, i].min() < lo or V[:, i].max() > hi:
            click.echo(
                f"hystcomp: warning: axis {i + 1}'s input ({V[:, i].min():.4g} .. "
                f"{V[:, i].max():.4g} V) leaves its model's voltage range ({lo:.4g} .. "
                f"{hi:.4g} V); the model extrapolates there.",
                err=True,
            )
    with progress("simulating", quiet).ticking():
        X = model.simulate(V)
    out = {"t": table["t"]}
    out.update({f"v{i + 1}": V[:, i] for i in range(n)})
    out.update({f"x{i + 1}": X[:, i] for i in range(n)})
    write_table(output, out, progress=progress(f"writing {output}", quiet))
    click.echo(f"wrote {output}: {X.shape[0]} samples of {n} axes")


def export_multiaxis(model, model_file, directory, prefix, slew_rate, sample_rate, method) -> None:
    """``hystcomp export-c`` with a multi-axis model: NAME.h/.c and one pair per axis."""
    from hystcomp.codegen.multiaxis import export_multiaxis_c

    options: dict = {"slew_rate": slew_rate, "sample_rate": sample_rate}
    if method is not None:
        options["method"] = method
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HystcompWarning)
        compensator = model.inverse(**options)
    paths = export_multiaxis_c(
        compensator,
        directory,
        prefix=prefix,
        source=str(model_file),
        sample_rate=sample_rate,
        inputs=(model_file,),
    )
    click.echo(f"wrote {', '.join(str(p) for p in paths)}")
