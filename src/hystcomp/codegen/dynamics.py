"""C99 of the inverse of the linear dynamics, put in front of any compensator template.

The generated ``NAME_step`` first runs the reference through the inverse filter of
:mod:`hystcomp.models.dynamics` (the non-negative FIR of the resonance inverse, then the
exact inverse of the creep bank, clamped to the model's displacement range), then the
hysteresis compensator's own code on the filtered reference, exactly as
:class:`~hystcomp.models.dynamic_compensator.DynamicStepper` does. The FIR looks ahead: the caller
passes the reference ``preview`` samples ahead of the sample the voltage is for.
"""

from __future__ import annotations

import numpy as np

from hystcomp._kernels import dynamics as dk
from hystcomp._kernels.chain import CLAMP_TOLERANCE
from hystcomp.codegen.c99 import CTemplate, c_double, c_table

#: ``NAME_prime``: the filter alone, as ``DynamicStepper.prime`` (``{p}`` the prefix).
PRIME = """void {p}_prime({p}_state *s, double x_ref)
{
    if (isfinite(x_ref)) {
        (void){p}_dyn_filter(s, &x_ref);
    }
}"""


def add_dynamics(template: CTemplate, inverse) -> CTemplate:
    """``template`` with the inverse filter ``inverse`` (a DynamicsInverse) before its step.

    Parameters
    ----------
    template : CTemplate
        The hysteresis compensator's template.
    inverse : DynamicsInverse
        The inverse of the linear dynamics.

    Returns
    -------
    CTemplate
        The template of the compensator in series with the filter.
    """
    p = inverse.packed
    n_fir, n_creep = int(p[dk.N_FIR]), int(p[dk.N_CREEP])
    taps = p[dk.HEADER : dk.HEADER + n_fir]
    lags = p[dk.HEADER + n_fir : dk.HEADER + n_fir + n_creep]
    weights = p[dk.HEADER + n_fir + n_creep : dk.HEADER + n_fir + 2 * n_creep]
    low, high = inverse.output_range
    template.summary = [
        *template.summary,
        (
            f"Inverse of the linear dynamics in front (beyond the paper): {n_fir} FIR taps, "
            f"{n_creep} creep modes."
        ),
        f"  PREVIEW: call NAME_step with the reference {inverse.preview} samples ahead of the",
        "  sample its voltage is for (fed the reference of now, the stage lags it by that).",
        f"  Call NAME_prime on the first {inverse.preview} reference samples first, then NAME_step.",
    ]
    template.defines += [
        "/* the samples by which {p}_step takes the reference ahead ({p}_prime that many) */",
        f"#define {{P}}_PREVIEW {inverse.preview}",
    ]
    # the circular delay line of the kernel (hystcomp._kernels.dynamics): held twice over,
    # so that the samples from the newest, dyn_line[dyn_head], to the oldest are contiguous
    template.state_fields += [
        f"double dyn_line[{2 * n_fir}]; /* reference delay line, twice over, um */",
        f"int dyn_head; /* dyn_line[dyn_head] (and [dyn_head + {n_fir}]) is the newest sample */",
    ]
    template.tables.append(c_table("{p}_dyn_h", taps, "FIR taps: resonance inverse, non-negative"))
    rest = c_double(inverse.rest)
    template.reset_body += [
        "{",
        "    int j;",
        f"    for (j = 0; j < {2 * n_fir}; j++) {{",
        f"        s->dyn_line[j] = {rest};",
        "    }",
        "    s->dyn_head = 0;",
    ]
    # the filter, one function for NAME_step and NAME_prime: x_ref in, filtered in place;
    # -1 if the result overflowed (held), 1 if the clamp cut it (counted), else 0
    body = [
        "static int {p}_dyn_filter({p}_state *s, double *x)",
        "{",
        "    int j;",
        "    int cut = 0;",
        f"    int head = s->dyn_head > 0 ? s->dyn_head - 1 : {n_fir - 1};",
        f"    double w = {c_double(p[dk.BIAS])};",
        "    double y;",
        "    const double *line = s->dyn_line + head;",
        "    s->dyn_head = head; /* one place back, instead of shifting every sample */",
        "    s->dyn_line[head] = *x;",
        f"    s->dyn_line[head + {n_fir}] = *x;",
        f"    for (j = 0; j < {n_fir}; j++) {{",
        "        w += {p}_dyn_h[j] * line[j];",
        "    }",
    ]
    if n_creep:
        template.state_fields.append(f"double dyn_lag[{n_creep}]; /* creep lag states, um */")
        template.tables += [
            c_table("{p}_dyn_a", lags, "creep lag factors a_i = exp(-Ts/tau_i)"),
            c_table("{p}_dyn_c", weights, "creep weights c_i"),
        ]
        template.reset_body += [
            f"    for (j = 0; j < {n_creep}; j++) {{",
            f"        s->dyn_lag[j] = {rest};",
            "    }",
        ]
        body += [
            "    {",
            f"        double acc = w * {c_double(p[dk.SCALE])};",
            f"        for (j = 0; j < {n_creep}; j++) {{",
            "            acc -= {p}_dyn_c[j] * {p}_dyn_a[j] * s->dyn_lag[j];",
            "        }",
            f"        y = acc / {c_double(p[dk.DIRECT])};",
            "    }",
        ]
    else:
        body.append(f"    y = w * {c_double(p[dk.SCALE])} / {c_double(p[dk.DIRECT])};")
    body += [
        "    if (!isfinite(y)) { /* a huge finite x_ref overflowed */",
        "        return -1;",
        "    }",
    ]
    tol = CLAMP_TOLERANCE * (high - low)  # the kernel's rule: a cut beyond a rounding counts
    for limit, beyond, edge in ((low, "<", low - tol), (high, ">", high + tol)):
        if np.isfinite(limit):
            body += [
                f"    if (y {beyond} {c_double(limit)}) {{",
                f"        if (y {beyond} {c_double(edge)}) {{",
                "            s->clamped_count++;",
                "            cut = 1;",
                "        }",
                f"        y = {c_double(limit)};",
                "    }",
            ]
    if n_creep:
        body += [
            f"    for (j = 0; j < {n_creep}; j++) {{",
            "        double lag = {p}_dyn_a[j] * s->dyn_lag[j] + (1.0 - {p}_dyn_a[j]) * y;",
            "        /* a lag below 1e-200 um is 0, not a slow subnormal decay */",
            f"        s->dyn_lag[j] = fabs(lag) > {c_double(dk.TINY)} ? lag : 0.0;",
            "    }",
        ]
    body += ["    *x = y;", "    return cut;", "}"]
    template.functions.append("\n".join(body))
    template.reset_body.append("}")
    template.public.append(
        (
            [
                f"/* Feed the first {inverse.preview} reference samples (the look-ahead) to the inverse of",
                "   the dynamics, one per call, before the first {p}_step; no voltage is",
                "   output, as the stepper's prime() in Python. A non-finite x_ref is skipped. */",
            ],
            PRIME,
        )
    )
    # a sample out of reach counted by the filter's clamp is not counted again by the
    # voltage range's (DynamicStepper.clamped_count)
    template.locals += ["int dyn_cut;", "unsigned long dyn_counted;"]
    step = [
        "",
        f"/* inverse of the linear dynamics; x_ref is {inverse.preview} samples ahead */",
        "dyn_cut = {p}_dyn_filter(s, &x_ref);",
        "if (dyn_cut < 0) { /* a huge finite x_ref overflowed: hold the output */",
        "    s->nonfinite_count++;",
        "    return s->last;",
        "}",
        "dyn_counted = s->clamped_count;",
        "",
    ]
    template.after_body += [
        "if (dyn_cut) {",
        "    s->clamped_count = dyn_counted;",
        "}",
    ]
    template.step_body = step + template.step_body
    return template
