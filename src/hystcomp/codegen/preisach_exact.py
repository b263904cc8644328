"""The C functions of the exact Preisach inverse, as in :mod:`hystcomp._kernels.preisach`.

``{p}_exact_input(s, target)`` returns the input that makes ``H`` reach ``target`` (um, no
offset) from the current memory without changing it: the monotone branch from the last
input is followed through the stored extrema (where wipe-outs change it) until it brackets
``target``, then solved by the Illinois variant of regula falsi with a bisection every
fourth step. A reference out of reach gives the range ends; a reference inside the step
that a non-zero ``X(v, v)`` opens at a reversal holds the voltage. The iteration, its
tolerances and its comparisons are the Python kernel's, in the same order (``{p}_solve``
serves both directions, as ``_solve`` does with its sign; a comparison multiplied by a sign
of 1 or -1 in Python is written as the comparison itself in C, the same test).
"""

from __future__ import annotations

from hystcomp.codegen.c99 import c_double


def exact_functions(v_min: float, v_max: float) -> list[str]:
    """C definitions of ``{p}_branch``, ``{p}_root``, ``{p}_solve`` and ``{p}_exact_input``
    for a Preisach plane ``v_min .. v_max`` (V); they call ``{p}_everett``.

    Parameters
    ----------
    v_min, v_max : float
        The ends of the Preisach plane, V, written into the C as ``V_MIN`` and ``V_MAX``.

    Returns
    -------
    list of str
        The C definitions, one string each.
    """
    ends = {"V_MIN": c_double(v_min), "V_MAX": c_double(v_max)}
    functions = [_BRANCH, _ROOT, _SOLVE, _EXACT_INPUT]
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

_SOLVE = """\
/* Smallest rise (rising) or fall of the input from previous whose branch output reaches
   target (above, or below, h). The branch runs from the near end previous to the far end,
   the next stored extremum in that direction (or the range end); past it, that extremum
   and its partner are wiped out and the next outer branch goes on. */
static double {p}_solve(const {p}_state *s, long top, double previous, double target,
                        int rising)
{
    double end = rising ? V_MAX : V_MIN;
    double base, pivot, near, far, b_near, b_far;
    long k;
    int first = 1;
    if ((top % 2 == 1) == rising) {
        /* a reversal: the branch starts at a new extremum (a minimum rising, a maximum
           falling) at previous */
        base = rising ? s->q[top] - {p}_everett(s->e[top], previous)
                      : s->q[top] + {p}_everett(previous, s->e[top]);
        pivot = previous;
        far = s->e[top];
        k = top - 1;
    } else {
        base = s->q[top];
        pivot = s->e[top];
        far = top >= 1 ? s->e[top - 1] : end;
        k = top - 2;
    }
    near = previous;
    for (;;) {
        b_far = {p}_branch(base, pivot, rising, far);
        if (rising ? target <= b_far : target >= b_far) {
            b_near = {p}_branch(base, pivot, rising, near);
            if (first && (rising ? b_near >= target : b_near <= target)) {
                return previous; /* in the step a non-zero X(v, v) opens at a reversal */
            }
            if (rising) {
                return {p}_root(base, pivot, 1, near, far, target, b_near, b_far);
            }
            return {p}_root(base, pivot, 0, far, near, target, b_far, b_near);
        }
        if (k < 0) {
            return end;
        }
        first = 0; /* past a stored extremum: wiped out, the next outer branch */
        near = far;
        base = s->q[k];
        pivot = s->e[k];
        far = k >= 1 ? s->e[k - 1] : end;
        k -= 2;
    }
}"""

_EXACT_INPUT = """\
/* The input that makes H reach target (um, no offset) from the current memory, which is
   not changed; the range ends when the branch never reaches it. */
static double {p}_exact_input(const {p}_state *s, double target)
{
    if (target > s->h) {
        return {p}_solve(s, s->top, s->input, target, 1);
    }
    if (target < s->h) {
        return {p}_solve(s, s->top, s->input, target, 0);
    }
    return s->input;
}"""
