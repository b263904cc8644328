"""The C template of the Preisach compensators, read from their packed system.

The generated code is a line-by-line C version of :mod:`hystcomp._kernels.preisach`, with the
packed numbers baked in: the Everett-type function X of eq. (2) (the polynomial of eq. 5 of
any degree, or a table interpolated bilinearly), the memory of alternating dominant extrema
of eqs. (3)-(4) with the wipe-out property and its prefix sums (one evaluation of X per
sample whatever the depth of the memory), its bound (the innermost stored pair wiped out
when a reversal would overflow it), and the compensator's step: the inverse multiplicative
structure of eq. (10), or the exact inverse (:mod:`hystcomp.codegen.preisach_exact`).

The memory decisions compare voltages, and a voltage one rounding apart can take the other
side of a comparison: where ``X(v, v)`` is not 0 (eq. 6 as printed) the output then steps
by ``X(v, v)``. It happens when the recursion of eq. (10) settles on a held reference. So X
and eq. (10) are written with the fused multiply-adds and the order of operations of the
compiled kernel (numba, fastmath), and the multiplicative compensator rounds as Python does
on a processor with FMA. The exact inverse holds its voltage in that step instead, and its
root finder agrees within its tolerance (about 1e-13 V).
"""

from __future__ import annotations

from hystcomp._kernels import preisach as pk
from hystcomp._kernels.chain import CLAMP_TOLERANCE
from hystcomp.codegen.c99 import CTemplate, c_double, c_table
from hystcomp.codegen.preisach_exact import exact_functions


def preisach_template(compensator) -> CTemplate:
    """The :class:`~hystcomp.codegen.c99.CTemplate` of a :class:`PreisachCompensator`.

    Both methods of :meth:`Preisach.inverse <hystcomp.models.preisach.Preisach.inverse>`:
    ``"multiplicative"`` (eq. 10) and ``"exact"``.

    Parameters
    ----------
    compensator : PreisachCompensator
        The inverse of a Preisach model, either method.

    Returns
    -------
    CTemplate
        Its tables (the Everett function), helper functions and step.
    """
    p = compensator.packed
    depth = int(p[pk.DEPTH])
    v_min, v_max = float(p[pk.V_MIN]), float(p[pk.V_MAX])
    lo, hi = compensator.voltage_range
    exact = int(p[pk.MODE]) == pk.EXACT
    template = CTemplate(
        kind=_kind_text(exact),
        summary=_summary(p, compensator, exact),
        low=lo,
        high=hi,
        max_step=float(p[pk.MAX_STEP]),
        initial_output=min(max(v_min, lo), hi),  # the kernel's start value, inside the clamp
        hold_on_overflow=False,  # the kernel takes v = +-inf to the range ends (min/max)
        state_fields=[
            "long top; /* index of the innermost stored extremum (e[0] = beta_0) */",
            "double input; /* last input applied to H, V */",
            "double h; /* H(input) without the offset x_0, um */",
            f"double e[{depth}]; /* alternating dominant extrema beta_0, alpha_1, beta_1, .. V */",
            f"double q[{depth}]; /* prefix sums of the closed contributions of eqs. 3-4, um */",
        ],
        tables=[_everett_table(p)],
        functions=[
            _everett_function(p),
            _PUSH.replace("DEPTH", str(depth)),
            _APPLY.replace("V_MIN", c_double(v_min)).replace("V_MAX", c_double(v_max)),
            *(exact_functions(v_min, v_max) if exact else []),
        ],
        reset_body=[
            "long i;",
            f"for (i = 0; i < {depth}; i++) {{",
            "    s->e[i] = 0.0;",
            "    s->q[i] = 0.0;",
            "}",
            "s->top = 0; /* all relays off at v_min: beta_0 = v_min, H = 0 */",
            f"s->e[0] = {c_double(v_min)};",
            f"s->input = {c_double(v_min)};",
            "s->h = 0.0;",
        ],
        after_body=["{p}_apply(s, v); /* H's memory follows the applied voltage */"],
        count_clamped=False,  # counted below, as the kernel does: a reference out of reach
    )
    offset = float(p[pk.OFFSET])
    template.after_body += [
        f"if (v == {c_double(hi)} || v == {c_double(lo)}) {{ /* only there can x_ref be out of reach */",
        f"    double target = {_minus('x_ref', offset)};",
        f"    double miss = {c_double(CLAMP_TOLERANCE)} * (1.0 + fabs(target));",
        f"    if ((v == {c_double(hi)} && target > s->h + miss) ||",
        f"        (v == {c_double(lo)} && target < s->h - miss)) {{",
        "        s->clamped_count++;",
        "    }",
        "}",
    ]
    if exact:
        template.step_body = [
            "/* exact inverse: the input on the current branch of H with x_0 + H(v) = x_ref */",
            f"v = {{p}}_exact_input(s, {_minus('x_ref', offset)});",
        ]
    else:
        # x[k-1] = H + x_0, summed in that order: the compiled kernel's reassociation
        x_previous = f"({_minus('s->h', -offset)})" if offset != 0.0 else "s->h"
        template.step_body = [
            "/* inverse multiplicative structure, eq. 10: v[k] = (x_ref[k] - Gamma(v[k-1])) /",
            "   rho with Gamma(v) = H(v) - rho v, i.e. v[k-1] + (x_ref[k] - x[k-1]) / rho */",
            f"v = s->input + (x_ref - {x_previous}) / {c_double(p[pk.RHO])};",
        ]
    return template


def _minus(name: str, value: float) -> str:
    """``name - value`` in C (``name + |value|`` for a negative value: the same double)."""
    if value == 0.0:
        return name
    sign = "-" if value > 0 else "+"
    return f"{name} {sign} {c_double(abs(value))}"


def _everett_table(p) -> str:
    n = int(p[pk.N_COEF])
    values = p[pk.HEADER : pk.HEADER + n * n]
    if int(p[pk.KIND]) == pk.POLYNOMIAL:
        what = f"eq. 5: entry i * {n} + j is the coefficient of b^i a^j, um/V^(i+j)"
    else:
        what = f"X(alpha_i, beta_j) of eq. 2 in um: entry i * {n} + j, {n} x {n} grid"
    return c_table("{p}_everett_coef", values, what)


def _everett_function(p) -> str:
    n = int(p[pk.N_COEF])
    a = _minus("alpha", float(p[pk.V_MIN]))
    b = _minus("beta", float(p[pk.V_MIN]))
    if int(p[pk.KIND]) == pk.POLYNOMIAL:
        text = _POLYNOMIAL.replace("ALPHA", a).replace("BETA", b)
    else:
        inverse_step = c_double(1.0 / p[pk.GRID_STEP])  # as the kernel's compiled division
        text = _TABLE.replace("ALPHA", _scaled(a, inverse_step))
        text = text.replace("BETA", _scaled(b, inverse_step))
    numbers = {"NN - 2": n - 2, "NN - 1": n - 1, "NN + 1": n + 1, "NN": n}
    for name, value in numbers.items():
        text = text.replace(name, str(value))
    return text


def _scaled(expression: str, factor: str) -> str:
    return f"({expression}) * {factor}" if " " in expression else f"{expression} * {factor}"


_POLYNOMIAL = """\
/* X(alpha, beta) of eq. 2 in um, the polynomial of eq. 5: sum_i b^i (sum_j C[i][j] a^j),
   Horner in both variables, with the fused multiply-adds of the compiled Python kernel so
   that both round alike. */
static double {p}_everett(double alpha, double beta)
{
    const double a = ALPHA;
    const double b = BETA;
    double acc = 0.0;
    int i, j;
    for (i = NN - 1; i >= 0; i--) {
        double inner = 0.0;
        for (j = NN - 1 - i; j >= 0; j--) {
            inner = fma(inner, a, {p}_everett_coef[i * NN + j]);
        }
        acc = fma(acc, b, inner);
    }
    return acc;
}"""

_TABLE = """\
/* X(alpha, beta) of eq. 2 in um: the table interpolated bilinearly,
   (1 - s) ((1 - t) T[i][j] + t T[i][j+1]) + s ((1 - t) T[i+1][j] + t T[i+1][j+1]),
   written as the Python kernel's compiler evaluates it (a reciprocal of the grid step,
   A + s (B - A), fused multiply-adds) so that it rounds alike. */
static double {p}_everett(double alpha, double beta)
{
    const double u = ALPHA; /* in grid steps */
    const double w = BETA;
    long i = (long)u;
    long j = (long)w;
    double s, t, t1, row;
    const double *k;
    if (i < 0) {
        i = 0;
    }
    if (i > NN - 2) {
        i = NN - 2;
    }
    if (j < 0) {
        j = 0;
    }
    if (j > NN - 2) {
        j = NN - 2;
    }
    s = u - (double)i;
    t = w - (double)j;
    t1 = 1.0 - t;
    k = {p}_everett_coef + i * NN + j;
    row = fma(k[1], t, k[0] * t1); /* A = (1 - t) T[i][j] + t T[i][j+1] */
    return fma(fma(t, k[NN + 1], -fma(-t1, k[NN], row)), s, row); /* A + s (B - A) */
}"""

_PUSH = """\
/* Store a turning point (a maximum on an even top, a minimum on an odd one) with its prefix
   sum, and return the new top. When the memory is full the innermost stored pair (the most
   recent closed minor loop) is wiped out first. */
static long {p}_push({p}_state *s, long top, double value)
{
    double c;
    if (top + 1 >= DEPTH) {
        top -= 2;
    }
    if (top % 2 == 0) {
        c = {p}_everett(value, s->e[top]);
    } else {
        c = -{p}_everett(s->e[top], value);
    }
    s->e[top + 1] = value;
    s->q[top + 1] = s->q[top] + c;
    return top + 1;
}"""

_APPLY = """\
/* Apply input v (clamped to the Preisach plane) to H, eqs. 3-4 with the wipe-out property:
   update the memory and s->h = H(v) without the offset. */
static void {p}_apply({p}_state *s, double v)
{
    long top = s->top;
    const double previous = s->input;
    if (v < V_MIN) {
        v = V_MIN;
    }
    if (v > V_MAX) {
        v = V_MAX;
    }
    if (top % 2 == 0) {
        if (v < previous) {
            top = {p}_push(s, top, previous);
        }
    } else if (v > previous) {
        top = {p}_push(s, top, previous);
    }
    if (top % 2 == 0) {
        while (top >= 2 && v >= s->e[top - 1]) {
            top -= 2; /* wipe-out: the input passed the maximum alpha_N */
        }
        s->h = s->q[top] + {p}_everett(v, s->e[top]);
    } else {
        while (top >= 3 && v <= s->e[top - 1]) {
            top -= 2; /* wipe-out: the input passed the minimum beta_N */
        }
        s->h = s->q[top] - {p}_everett(s->e[top], v);
    }
    s->top = top;
    s->input = v;
}"""


def _kind_text(exact: bool) -> str:
    if exact:
        return "Preisach compensator, exact inverse of eqs. 3-4 (paper eqs. 1-5)"
    return "Preisach compensator, inverse multiplicative structure (paper eqs. 7-10)"


def _summary(p, compensator, exact: bool) -> list[str]:
    n = int(p[pk.N_COEF])
    depth = int(p[pk.DEPTH])
    v_min, v_max = float(p[pk.V_MIN]), float(p[pk.V_MAX])
    lo, hi = compensator.voltage_range
    if int(p[pk.KIND]) == pk.POLYNOMIAL:
        everett = f"  X: Everett polynomial of degree {n - 1} (eq. 5 is degree 3)"
    else:
        everett = f"  X: {n} x {n} table, bilinear interpolation"
    lines = [
        "Parameters (the identified values are tables in the .c file):",
        everett,
        f"  Preisach plane {v_min:.9g} .. {v_max:.9g} V, output offset {p[pk.OFFSET]:.9g} um",
    ]
    if not exact:
        lines.append(f"  rho {p[pk.RHO]:.9g} um/V (eq. 10)")
    lines += [
        f"  memory: up to {depth} extrema ({16 * depth} bytes of state)",
        "  X uses fma() of <math.h>: link with -lm where the C library keeps it apart",
        f"  output clamped to [{lo:.9g}, {hi:.9g}] V",
    ]
    return lines
