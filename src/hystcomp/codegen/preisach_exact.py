"""The C functions of the exact Preisach inverse, as in :mod:`hystcomp._kernels.preisach`.

``{p}_exact_input(s, target)`` returns the input that makes ``H`` reach ``target`` (um, no
offset) from the current memory without changing it: the monotone branch from the last
input is followed through the stored extrema (where wipe-outs change it) until it brackets
``target``, then solved by the Illinois variant of regula falsi with a bisection every
fourth step. A reference out of reach gives the range ends; a reference inside the step
that a non-zero ``X(v, v)`` opens at a reversal holds the voltage. The iteration, its
tolerances and its comparisons are the Python kernel's, in the same order (its ``_solve``
serves both directions with a sign; here ``{p}_solve_up`` and ``{p}_solve_down`` write the
two out).
"""

from __future__ import annotations

from hystcomp.codegen.c99 import c_double


def exact_functions(v_min: float, v_max: float) -> list[str]:
    """C definitions of ``{p}_branch``, ``{p}_root``, ``{p}_solve_up``, ``{p}_solve_down``
    and ``{p}_exact_input`` for a Preisach plane ``v_min .. v_max`` (V); they call
    ``{p}_everett``.

    Parameters
    ----------
    v_min : float
        The lower end of the Preisach plane, V.
    v_max : float
        The upper end, V.

    Returns
    -------
    list of str
        The C definitions, one string each.
    """
    ends = {"V_MIN": c_double(v_min), "V_MAX": c_double(v_max)}
    functions = [_BRANCH, _ROOT, _SOLVE_UP, _SOLVE_DOWN, _EXACT_INPUT]
    out = []
    for text in functions:
        for name, value in ends.items():
            text = text.replace(name, value)
        out.append(text)
    return out


_BRANCH = """\
static double {p}_abs(double x)
{
    return x < 0.0 ? -x : x;
}

/* A monotone branch: base + X(v, pivot) rising, base - X(pivot, v) falling. */
static double {p}_branch(double base, double pivot, int rising, double v)
{
    if (rising) {
        return base + {p}_everett(v, pivot);
    }
    return base - {p}_everett(pivot, v);
}"""

_ROOT = """\
/* v in [lo, hi] with branch(v) = target, given branch(lo) < target <= branch(hi): Illinois
   (modified regula falsi) with a bisection every fourth step. b_lo and b_hi are the branch
   at lo and hi, evaluated by the caller. */
static double {p}_root(double base, double pivot, int rising, double lo, double hi,
                       double target, double b_lo, double b_hi)
{
    double g_lo = b_lo - target;
    double g_hi = b_hi - target;
    double f_lo, f_hi, tol_x, m, g, scale;
    int side = 0;
    int it;
    if (g_lo >= 0.0) {
        return lo;
    }
    if (g_hi <= 0.0) {
        return hi;
    }
    f_lo = g_lo; /* Illinois scales g; keep the true residuals for the final choice */
    f_hi = g_hi;
    tol_x = 1e-13 * (1.0 + {p}_abs(target));
    for (it = 0; it < 200; it++) {
        if (it % 4 == 3 || g_hi == g_lo) {
            m = 0.5 * (lo + hi);
        } else {
            m = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
            if (!(lo < m && m < hi)) {
                m = 0.5 * (lo + hi);
            }
        }
        g = {p}_branch(base, pivot, rising, m) - target;
        if ({p}_abs(g) <= tol_x) {
            return m;
        }
        if (g < 0.0) {
            lo = m;
            g_lo = g;
            f_lo = g;
            if (side == -1) {
                g_hi *= 0.5;
            }
            side = -1;
        } else {
            hi = m;
            g_hi = g;
            f_hi = g;
            if (side == 1) {
                g_lo *= 0.5;
            }
            side = 1;
        }
        scale = {p}_abs(lo) > {p}_abs(hi) ? {p}_abs(lo) : {p}_abs(hi);
        if (scale < 1.0) {
            scale = 1.0;
        }
        if (hi - lo <= 4e-16 * scale) {
            break;
        }
    }
    return -f_lo < f_hi ? lo : hi;
}"""

_SOLVE_UP = """\
/* Smallest rise of the input whose branch output reaches target (> h). */
static double {p}_solve_up(const {p}_state *s, long top, double previous, double target)
{
    double base, pivot, lo, hi, b_lo, b_hi;
    long k;
    int first = 1;
    if (top % 2 == 1) { /* a reversal: the branch starts at a new minimum beta = previous */
        base = s->q[top] - {p}_everett(s->e[top], previous);
        pivot = previous;
        hi = s->e[top];
        k = top - 1;
    } else {
        base = s->q[top];
        pivot = s->e[top];
        hi = top >= 2 ? s->e[top - 1] : V_MAX;
        k = top - 2;
    }
    lo = previous;
    for (;;) {
        b_hi = {p}_branch(base, pivot, 1, hi);
        if (target <= b_hi) {
            b_lo = {p}_branch(base, pivot, 1, lo);
            if (first && b_lo >= target) {
                return previous; /* in the step a non-zero X(v, v) opens at a reversal */
            }
            return {p}_root(base, pivot, 1, lo, hi, target, b_lo, b_hi);
        }
        if (k < 0) {
            return V_MAX;
        }
        first = 0; /* past a stored maximum: wiped out, the next outer branch */
        lo = hi;
        base = s->q[k];
        pivot = s->e[k];
        hi = k >= 2 ? s->e[k - 1] : V_MAX;
        k -= 2;
    }
}"""

_SOLVE_DOWN = """\
/* Smallest fall of the input whose branch output reaches target (< h). */
static double {p}_solve_down(const {p}_state *s, long top, double previous, double target)
{
    double base, pivot, lo, hi, b_lo, b_hi;
    long k;
    int first = 1;
    if (top % 2 == 0) { /* a reversal: the branch starts at a new maximum alpha = previous */
        base = s->q[top] + {p}_everett(previous, s->e[top]);
        pivot = previous;
        lo = s->e[top];
        k = top - 1;
    } else {
        base = s->q[top];
        pivot = s->e[top];
        lo = s->e[top - 1];
        k = top - 2;
    }
    hi = previous;
    for (;;) {
        b_lo = {p}_branch(base, pivot, 0, lo);
        if (target >= b_lo) {
            b_hi = {p}_branch(base, pivot, 0, hi);
            if (first && b_hi <= target) {
                return previous; /* in the step a non-zero X(v, v) opens at a reversal */
            }
            return {p}_root(base, pivot, 0, lo, hi, target, b_lo, b_hi);
        }
        if (k < 1) {
            return V_MIN;
        }
        first = 0; /* past a stored minimum: wiped out, the next outer branch */
        hi = lo;
        base = s->q[k];
        pivot = s->e[k];
        lo = s->e[k - 1];
        k -= 2;
    }
}"""

_EXACT_INPUT = """\
/* The input that makes H reach target (um, no offset) from the current memory, which is
   not changed; the range ends when the branch never reaches it. */
static double {p}_exact_input(const {p}_state *s, double target)
{
    if (target > s->h) {
        return {p}_solve_up(s, s->top, s->input, target);
    }
    if (target < s->h) {
        return {p}_solve_down(s, s->top, s->input, target);
    }
    return s->input;
}"""
