"""Classical Preisach model as compiled kernels (paper eqs. 2-5 and 10).

The model output follows eqs. (3)-(4): a memory of alternating dominant extrema
``beta_0 = v_min < ... `` with the wipe-out property, and the Everett-type function
``X(alpha, beta)`` of eq. (2). The memory is a stack ``e[0..L]`` (``e[0] = beta_0 = v_min``,
then ``alpha_1, beta_1, alpha_2, ...``): an even top ``L`` means the input rises from the
minimum ``e[L]`` (eq. 3), an odd top means it falls from the maximum ``e[L]`` (eq. 4).
Beside each entry the stack keeps the prefix sum of the closed contributions,

    P[j] = P[j-1] + X(e[j], e[j-1])   (j odd, a maximum)
    P[j] = P[j-1] - X(e[j-1], e[j])   (j even, a minimum),

so the output is ``P[L] + X(v, e[L])`` when rising and ``P[L] - X(e[L], v)`` when falling:
one evaluation of ``X`` per sample whatever the depth of the memory, plus the amortised
pushes and wipe-outs (each entry is pushed once and popped at most once). A prefix sum is
written once, when its entry is pushed, and never updated, so no rounding drift builds up
over long runs.

The memory is bounded by ``depth`` entries. When a reversal would overflow it, the innermost
stored pair (the most recent closed minor loop, the smallest) is wiped out first, as if the
input had just passed it; the output then differs from the unbounded model's by the Preisach
weight of that small loop, until a larger excursion wipes both out. The default depth of the
model is far beyond what measured signals reach.

``X`` is either the polynomial of eq. (5) in ``a = alpha - v_min``, ``b = beta - v_min``, held
as a coefficient matrix ``C[i, j]`` of ``b**i a**j``, or a table on a uniform grid over
``[v_min, v_max]`` interpolated bilinearly; the table holds ``X(alpha_i, beta_j)`` for
``j <= i`` and its antisymmetric extension ``X(alpha_i, beta_j) = -X(alpha_j, beta_i)`` above
the diagonal, so that the interpolant vanishes on the diagonal as eq. (2) requires.

Everything (parameters, state, memory) is packed into one float64 array, so a streaming step
is one compiled call on one array, as :mod:`hystcomp._kernels.chain` does for the play chain.
The same :func:`preisach_step` serves the forward model, the inverse multiplicative structure
(eq. 10) and the exact inverse, in batch and streaming use. These functions trust their input.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import cast

import numba
import numpy as np
from llvmlite import ir  # type: ignore[import-untyped]
from numba.extending import intrinsic

from hystcomp._kernels._jit import (
    StepKernels,
    inline_kernel,
    inner_kernel,
    kernel,
    step_kernel,
)
from hystcomp._kernels.chain import CLAMP_TOLERANCE, block_status

# Modes of a packed system: what a step maps.
FORWARD, MULTIPLICATIVE, EXACT = 0, 1, 2
# Representations of X.
POLYNOMIAL, TABLE = 0, 1
# Header slots.
MODE, KIND, V_MIN, V_MAX, OFFSET, GRID_STEP, N_COEF, DEPTH, RHO, MAX_STEP, LOW, HIGH = range(12)
HEADER = 12
# State slots (from state_start(p)): stack top, last input, last H (without offset),
# last output, count of non-finite inputs, count of clamped outputs. The stack and its
# prefix sums follow.
ST_TOP, ST_INPUT, ST_H, ST_LAST, ST_NONFINITE, ST_CLAMPED = range(6)
N_STATE = 6
#: Default bound on the stored extrema: 512 nested reversals, far beyond measured signals.
DEFAULT_DEPTH = 1024
#: Largest memory bound a model may ask for (a packed system holds it whole).
MAX_DEPTH = 1_000_000


def _fma_intrinsic(typingctx, x, y, z):
    """``x * y + z`` rounded once (LLVM's ``llvm.fma``), as C99's ``fma()``.

    Written out rather than left to the compiler's contraction, so that the order and the
    rounding of X's multiply-adds are fixed whatever the fast-math flags let LLVM
    reassociate, and the generated C (which calls ``fma()``) rounds alike.
    """
    sig = numba.types.float64(numba.types.float64, numba.types.float64, numba.types.float64)

    def codegen(context, builder, signature, args):
        double = ir.DoubleType()
        fnty = ir.FunctionType(double, [double, double, double])
        fma = builder.module.declare_intrinsic("llvm.fma", [double], fnty)
        return builder.call(fma, args)

    return sig, codegen


# as the kernels call it: three floats, the typing context is numba's (its type hints name it)
_fma = cast("Callable[[float, float, float], float]", intrinsic(_fma_intrinsic))


def monomial_exponents(degree: int) -> list[tuple[int, int]]:
    """Exponents ``(i, j)`` of the monomials ``beta**i * alpha**j`` of X, in eq. (5)'s order.

    Degree by degree, and within degree ``k`` from ``beta**k`` to ``alpha**k``; degree 3 is
    eq. (5): ``beta, alpha, beta^2, beta alpha, alpha^2, beta^3, beta^2 alpha, beta alpha^2,
    alpha^3``.

    Examples
    --------
    >>> monomial_exponents(2)
    [(1, 0), (0, 1), (2, 0), (1, 1), (0, 2)]
    """
    return [(k - j, j) for k in range(1, degree + 1) for j in range(k + 1)]


def n_monomials(degree: int) -> int:
    """Number of coefficients of a degree-``degree`` X: ``degree (degree + 3) / 2`` (9 for 3)."""
    return degree * (degree + 3) // 2


def coefficient_matrix(theta: np.ndarray, degree: int) -> np.ndarray:
    """``C[i, j]``, the coefficient of ``b**i a**j``, from theta in eq. (5)'s order."""
    c = np.zeros((degree + 1, degree + 1))
    for value, (i, j) in zip(theta, monomial_exponents(degree), strict=True):
        c[i, j] = value
    return c


def antisymmetric_table(lower: np.ndarray) -> np.ndarray:
    """The full grid table from its lower triangle (diagonal included): ``T[j, i] = -T[i, j]``."""
    strict = np.tril(lower, -1)
    return strict - strict.T + np.diag(np.diag(lower))


def pack_preisach(
    *,
    kind: int,
    coef: np.ndarray,
    v_min: float,
    v_max: float,
    offset: float,
    depth: int,
    mode: int = FORWARD,
    rho: float = 1.0,
    max_step: float = np.inf,
    clamp: tuple[float, float] | None = None,
) -> np.ndarray:
    """Pack a Preisach system in its initial state: all relays off at ``v_min``.

    Parameters
    ----------
    kind : int
        :data:`POLYNOMIAL` (``coef`` from :func:`coefficient_matrix`) or :data:`TABLE`
        (``coef`` from :func:`antisymmetric_table` on a uniform grid over the range).
    coef : ndarray
        Square matrix of coefficients or table values (µm).
    v_min, v_max : float
        The Preisach plane ``v_min <= beta <= alpha <= v_max`` (V); inputs are clamped to it.
    offset : float
        Output offset ``x_0`` added to ``H`` (µm).
    depth : int
        Largest number of stored extrema (>= 3).
    mode : int
        :data:`FORWARD` (v -> x), :data:`MULTIPLICATIVE` or :data:`EXACT` (x_ref -> v).
    rho : float
        The gain of the inverse multiplicative structure (µm/V), eq. (10).
    max_step : float
        Largest change of a compensator's output per sample (V).
    clamp : (float, float), optional
        A compensator's output range (V), inside the plane; the whole plane by default.
    """
    low, high = (v_min, v_max) if clamp is None else clamp
    n = coef.shape[0]
    step = (v_max - v_min) / (n - 1) if kind == TABLE else 0.0
    header = np.array(
        [mode, kind, v_min, v_max, offset, step, n, depth, rho, max_step, low, high],
        dtype=np.float64,
    )
    # a compensator holds (on a non-finite first sample) the start voltage v_min, inside
    # its clamp: a narrowed range holds its nearest end
    last = offset if mode == FORWARD else min(max(v_min, low), high)
    state = np.array([0.0, v_min, 0.0, last, 0.0, 0.0])
    stack = np.zeros(depth)
    stack[0] = v_min
    parts = [header, np.ascontiguousarray(coef, dtype=np.float64).ravel(), state, stack]
    return np.concatenate([*parts, np.zeros(depth)])


@inline_kernel
def state_start(p):
    """Index of the first state slot of packed system ``p``."""
    n = int(p[N_COEF])
    return HEADER + n * n


@inner_kernel
def everett(p, alpha, beta):
    """``X(alpha, beta)`` of eq. (2) in µm, for voltages inside the plane.

    The cubic of eq. (5) is written out here, small enough for LLVM to inline it where it is
    called (the root search of the exact inverse calls it at every step); any other
    polynomial and the table are one call of :func:`_everett_any`. Compiled once, not copied
    into each caller: every copy would be typed and compiled again.
    """
    if p[KIND] == POLYNOMIAL and p[N_COEF] == 4:
        # sum_i b^i (sum_j C[i, j] a^j), Horner in both variables, with fused multiply-adds:
        # the loop of _everett_any unrolled (its first terms are C[i, 0])
        a = alpha - p[V_MIN]
        b = beta - p[V_MIN]
        c = HEADER
        acc = _fma(p[c + 12], b, _fma(p[c + 9], a, p[c + 8]))
        acc = _fma(acc, b, _fma(_fma(p[c + 6], a, p[c + 5]), a, p[c + 4]))
        inner = _fma(_fma(_fma(p[c + 3], a, p[c + 2]), a, p[c + 1]), a, p[c])
        return _fma(acc, b, inner)
    return _everett_any(p, alpha, beta)


@inner_kernel
def _everett_any(p, alpha, beta):
    """:func:`everett` for any polynomial and for the table."""
    a = alpha - p[V_MIN]
    b = beta - p[V_MIN]
    n = int(p[N_COEF])
    if p[KIND] == POLYNOMIAL:
        acc = 0.0
        for i in range(n - 1, -1, -1):
            row = HEADER + i * n
            inner = 0.0
            for j in range(n - 1 - i, -1, -1):
                inner = _fma(inner, a, p[row + j])
            acc = _fma(acc, b, inner)
        return acc
    u = a / p[GRID_STEP]
    w = b / p[GRID_STEP]
    i = min(max(int(u), 0), n - 2)
    j = min(max(int(w), 0), n - 2)
    s = u - i
    t = w - j
    k = HEADER + i * n + j
    return (1.0 - s) * ((1.0 - t) * p[k] + t * p[k + 1]) + s * (
        (1.0 - t) * p[k + n] + t * p[k + n + 1]
    )


@kernel
def everett_many(p, alpha, beta, out):
    """``out[k] = X(alpha[k], beta[k])`` for voltages inside the plane."""
    for k in range(alpha.size):
        out[k] = everett(p, alpha[k], beta[k])


@inline_kernel
def _push(p, e, q, top, value):
    """Push a turning point (a maximum on an even top, a minimum on an odd one)."""
    if top + 1 >= int(p[DEPTH]):
        top -= 2  # full: wipe out the innermost stored pair first
    # X(value, e[top]) added on an even top, X(e[top], value) subtracted on an odd one: one
    # call site of X, the sign exact
    if top % 2 == 0:
        alpha, beta, sign = value, p[e + top], 1.0
    else:
        alpha, beta, sign = p[e + top], value, -1.0
    p[e + top + 1] = value
    p[q + top + 1] = p[q + top] + sign * everett(p, alpha, beta)
    return top + 1


@inline_kernel  # one call site, in preisach_step; X is a call (LLVM inlines it), not a copy
def preisach_apply(p, v):
    """Apply input ``v`` (inside the plane) and return ``H(v)`` without offset, eqs. (3)-(4)."""
    s = state_start(p)
    e = s + N_STATE
    q = e + int(p[DEPTH])
    top = int(p[s + ST_TOP])
    previous = p[s + ST_INPUT]
    if (v < previous) if top % 2 == 0 else (v > previous):
        top = _push(p, e, q, top, previous)  # a reversal
    if top % 2 == 0:
        while top >= 2 and v >= p[e + top - 1]:
            top -= 2  # wipe-out: the input passed the maximum alpha_N
        alpha, beta, sign = v, p[e + top], 1.0  # H = P[top] + X(v, e[top])
    else:
        while top >= 3 and v <= p[e + top - 1]:
            top -= 2  # wipe-out: the input passed the minimum beta_N
        alpha, beta, sign = p[e + top], v, -1.0  # H = P[top] - X(e[top], v)
    h = p[q + top] + sign * everett(p, alpha, beta)
    p[s + ST_TOP] = top
    p[s + ST_INPUT] = v
    p[s + ST_H] = h
    return h


@inline_kernel
def _branch(p, base, pivot, sign, v):
    """A monotone branch: ``base + X(v, pivot)`` rising (``sign`` 1), ``base - X(pivot, v)``
    falling (``sign`` -1)."""
    alpha, beta = (v, pivot) if sign > 0.0 else (pivot, v)
    return base + sign * everett(p, alpha, beta)  # the sign is exact


@inner_kernel
def _root(p, base, pivot, sign, lo, hi, target, b_lo, b_hi):
    """``v`` in ``[lo, hi]`` with branch(v) = target, given branch(lo) < target <= branch(hi).

    Illinois (modified regula falsi) with a bisection every fourth step: the bracket
    always shrinks, and smooth branches converge superlinearly. ``b_lo`` and ``b_hi`` are
    the branch at ``lo`` and ``hi``, which the caller has evaluated already.
    """
    g_lo = b_lo - target
    g_hi = b_hi - target
    if g_lo >= 0.0:
        return lo
    if g_hi <= 0.0:
        return hi
    f_lo = g_lo  # Illinois scales these; keep the true residuals for the final choice
    f_hi = g_hi
    tol_x = 1e-13 * (1.0 + abs(target))
    side = 0
    for it in range(200):
        if it % 4 == 3 or g_hi == g_lo:
            m = 0.5 * (lo + hi)
        else:
            m = (lo * g_hi - hi * g_lo) / (g_hi - g_lo)
            if not (lo < m < hi):
                m = 0.5 * (lo + hi)
        g = _branch(p, base, pivot, sign, m) - target
        if abs(g) <= tol_x:
            return m
        if g < 0.0:
            lo, g_lo, f_lo = m, g, g
            if side == -1:
                g_hi *= 0.5
            side = -1
        else:
            hi, g_hi, f_hi = m, g, g
            if side == 1:
                g_lo *= 0.5
            side = 1
        if hi - lo <= 4e-16 * max(abs(lo), abs(hi), 1.0):
            break
    return lo if -f_lo < f_hi else hi


@inner_kernel
def _solve(p, e, q, top, previous, target, sign):
    """Smallest rise (``sign`` 1) or fall (``sign`` -1) of the input from ``previous`` whose
    branch output reaches ``target`` (above, or below, the present output).

    The branch runs from the near end ``previous`` to the far end, the next stored extremum
    in that direction (or the range end); past it, that extremum and its partner are wiped
    out and the next outer branch goes on. A reversal first starts a branch at ``previous``.
    """
    rising = sign > 0.0
    end = p[V_MAX] if rising else p[V_MIN]
    if (top % 2 == 1) == rising:
        # a reversal: the branch starts at a new extremum (a minimum rising, a maximum falling)
        alpha, beta = (p[e + top], previous) if rising else (previous, p[e + top])
        base = p[q + top] - sign * everett(p, alpha, beta)
        pivot = previous
        far = p[e + top]
        k = top - 1
    else:
        base = p[q + top]
        pivot = p[e + top]
        far = p[e + top - 1] if top >= 1 else end
        k = top - 2
    near = previous
    first = True
    while True:
        b_far = _branch(p, base, pivot, sign, far)
        if sign * target <= sign * b_far:
            b_near = _branch(p, base, pivot, sign, near)
            if first and sign * b_near >= sign * target:
                return previous  # in the gap a non-zero X(v, v) opens at a reversal: hold
            if rising:
                return _root(p, base, pivot, sign, near, far, target, b_near, b_far)
            return _root(p, base, pivot, sign, far, near, target, b_far, b_near)
        if k < 0:
            return end
        first = False  # past a stored extremum: wiped out, the next outer branch
        near = far
        base = p[q + k]
        pivot = p[e + k]
        far = p[e + k - 1] if k >= 1 else end
        k -= 2


@inner_kernel
def exact_input(p, target):
    """The input that makes ``H`` reach ``target`` (µm, no offset) from the current memory.

    The branch from the last input is followed through the stored extrema (where wipe-outs
    change it) until it brackets ``target``; the range ends are returned when it never does.
    The memory is not changed.
    """
    s = state_start(p)
    e = s + N_STATE
    q = e + int(p[DEPTH])
    top = int(p[s + ST_TOP])
    previous = p[s + ST_INPUT]
    h = p[s + ST_H]
    if target == h:
        return previous
    return _solve(p, e, q, top, previous, target, 1.0 if target > h else -1.0)


@inner_kernel
def _count_clamped(p, s, u, v, h):
    """Count a compensator's sample as clamped if ``v``, at an end of the range, leaves
    ``x_0 + H(v)`` short of the reference ``u`` (eq. 10 may ask beyond a range end for a
    reachable reference while it catches up: that is not counted)."""
    target = u - p[OFFSET]
    miss = CLAMP_TOLERANCE * (1.0 + abs(target))
    if (v == p[HIGH] and target > h + miss) or (v == p[LOW] and target < h - miss):
        p[s + ST_CLAMPED] += 1.0


@step_kernel
def preisach_step(p, u):
    """One sample through packed system ``p``; updates its state and returns the output.

    The streaming step (a :func:`~hystcomp._kernels._jit.step_kernel`), which the batch
    :func:`preisach_run` calls for every sample: the two run the same compiled code and agree
    bit for bit, and it is compiled once (an inlined copy would be compiled again for each
    signature of the batch kernel, and cost more than the call saves).

    FORWARD maps a voltage to ``x_0 + H(v)``; MULTIPLICATIVE is eq. (10),
    ``v[k] = v[k-1] + (x_ref[k] - x[k-1]) / rho``, i.e. ``(x_ref[k] - Gamma(v[k-1])) / rho``
    with ``Gamma(v) = H(v) - rho v``; EXACT solves ``x_0 + H(v) = x_ref`` on the current
    branch. Compensators slew-limit and clamp ``v``, then advance ``H``'s memory with it.
    A non-finite ``u`` holds the last output and increments the non-finite counter. A
    compensator's sample counts as clamped (out of reach) when ``v`` sits at an end of the
    range and ``x_0 + H(v)`` still falls short of ``x_ref`` there by more than
    :data:`~hystcomp._kernels.chain.CLAMP_TOLERANCE` of it.
    """
    s = state_start(p)
    if u - u != 0.0:  # NaN or +-inf
        p[s + ST_NONFINITE] += 1.0
        return p[s + ST_LAST]
    mode = int(p[MODE])
    if mode == FORWARD:
        v = min(max(u, p[V_MIN]), p[V_MAX])  # the plane
    else:
        previous = p[s + ST_INPUT]
        if mode == MULTIPLICATIVE:
            v = previous + (u - p[OFFSET] - p[s + ST_H]) / p[RHO]
        else:
            v = exact_input(p, u - p[OFFSET])
        step = p[MAX_STEP]
        if step < np.inf:  # a slew limit (none by default: a shorter path from x_ref to v)
            v = min(max(v, previous - step), previous + step)
        v = min(max(v, p[LOW]), p[HIGH])  # the clamp, inside the plane
    h = preisach_apply(p, v)
    if mode == FORWARD:
        out = h + p[OFFSET]
    else:
        if v == p[HIGH] or v == p[LOW]:  # rare: only then can the reference be out of reach
            _count_clamped(p, s, u, v, h)
        out = v
    p[s + ST_LAST] = out
    return out


@kernel
def preisach_run(p, u, out):
    """Run every sample of ``u`` through packed system ``p`` into ``out`` (state kept in ``p``)."""
    for k in range(u.size):
        out[k] = preisach_step(p, u[k])


@step_kernel
def preisach_step_block(p, u, out, work):
    """:func:`preisach_run` for a short block from Python (``Stepper.step_block``), compiled
    as a step is; ``work`` is unused. Returns the chain's
    :func:`~hystcomp._kernels.chain.block_status` (0: done; else nothing done)."""
    status = block_status(u, out)
    if status == 0:
        for k in range(u.size):
            out[k] = preisach_step(p, u[k])
    return status


#: The :class:`~hystcomp._kernels._jit.StepKernels` of a packed Preisach system.
PREISACH_KERNELS = StepKernels(
    preisach_step,
    preisach_run,
    state_start.py_func,
    ST_LAST,
    ST_NONFINITE,
    ST_CLAMPED,
    preisach_step_block,
)


# --- Regressors of the general least-squares identification ------------------------------
#
# A Preisach output is linear in the parameters of a linear Everett function
# ``X = sum_m c_m X_m``: with the memory of eqs. (3)-(4), ``H[k] = sum_m c_m R_m[k]`` where
# ``R_m`` is eqs. (3)-(4) evaluated with ``X_m`` alone. The kernels below run the memory
# exactly as :func:`preisach_apply` does (same reversal tests, wipe-out and bounded depth)
# and keep, beside each stored extremum, the prefix sum of the closed contributions as a
# vector over the basis, so a regressor row costs one basis evaluation per sample.

#: Bases of a linear Everett function: polynomials vanishing on the diagonal, Preisach cells.
BASIS_POLYNOMIAL, BASIS_CELLS = 0, 1


@kernel
def everett_basis(kind, exps, n_seg, v_min, v_max, alpha, beta, out):
    """``out[m] = X_m(alpha, beta)``, the Everett function of basis element ``m`` alone.

    With ``a = (alpha - v_min) / (v_max - v_min)`` and ``b`` likewise (the unit square):

    * :data:`BASIS_POLYNOMIAL`: ``X_m = b**i a**j - b**(i + j)`` for the exponents
      ``exps[m] = (i, j)``, ``j >= 1``: eq. (5)'s monomials with ``X(v, v) = 0`` built in.
    * :data:`BASIS_CELLS`, ``n_seg`` segments of the input range: first ``n_seg`` unit masses
      spread along the diagonal segments (a reversible part), then one unit mass spread
      uniformly over each cell ``(s_a, s_b)``, ``s_b < s_a``, of the limiting triangle, in the
      order ``(1, 0), (2, 0), (2, 1), (3, 0), ...``. Their Everett functions are the areas
      (lengths) of the switched-on parts, which interpolate bilinearly between grid nodes.
    """
    span = v_max - v_min
    a = (alpha - v_min) / span
    b = (beta - v_min) / span
    if kind == BASIS_POLYNOMIAL:
        for m in range(exps.shape[0]):
            i = exps[m, 0]
            j = exps[m, 1]
            out[m] = b**i * a**j - b ** (i + j)
        return
    ua = a * n_seg
    ub = b * n_seg
    m = 0
    for s in range(n_seg):
        out[m] = max(min(ua, s + 1.0) - max(ub, float(s)), 0.0)
        m += 1
    for sa in range(1, n_seg):
        fa = min(max(ua - sa, 0.0), 1.0)
        for sb in range(sa):
            out[m] = fa * min(max(sb + 1.0 - ub, 0.0), 1.0)
            m += 1


@inner_kernel
def _basis_output(kind, exps, n_seg, v_min, v_max, e, q, top, value, work, dest, d):
    """``dest[d, m]``: basis element ``m``'s output at input ``value`` on the branch from
    stored extremum ``top`` (its prefix sum ``q[top]`` plus, rising from a minimum,
    ``X_m(value, e[top])``, or, falling from a maximum, minus ``X_m(e[top], value)``), as
    :func:`preisach_apply` forms the model's output. ``work`` holds the basis values.

    One compiled function for the pushes and the rows, called with a row index rather than
    a view of the row; measured 10 % faster than the two inlined copies it replaces (an
    inlined helper was 1.4x slower)."""
    if top % 2 == 0:
        everett_basis(kind, exps, n_seg, v_min, v_max, value, e[top], work)
        sign = 1.0
    else:
        everett_basis(kind, exps, n_seg, v_min, v_max, e[top], value, work)
        sign = -1.0
    for m in range(work.size):
        dest[d, m] = q[top, m] + sign * work[m]


@kernel
def _push_basis(kind, exps, n_seg, v_min, v_max, e, q, top, value, work):
    """:func:`_push` on the basis: a turning point and its prefix-sum vector."""
    if top + 1 >= e.size:
        top -= 2  # full: wipe out the innermost stored pair first, as the model does
    _basis_output(kind, exps, n_seg, v_min, v_max, e, q, top, value, work, q, top + 1)
    e[top + 1] = value
    return top + 1


@kernel
def preisach_rows(kind, exps, n_seg, v_min, v_max, v, x, first, start, stride, memory, rows):
    """Regressor rows ``[R_0[k] .. R_(p-1)[k], 1, x[k]]`` of samples ``k = first, ...``.

    ``memory = (e, q, st)`` holds the memory between calls: the stored extrema ``e``
    (``e[0] = v_min``; its size is the depth bound), their prefix-sum vectors ``q`` (one row
    each, ``q[0] = 0``) and ``st = [top, last input]``; start it as :func:`pack_preisach`
    starts a model (all relays off at ``v_min``). Every sample advances the memory; a row is
    written for the samples ``k >= start`` with ``(k - start) % stride == 0`` until ``rows``
    is full. Returns ``(next sample, rows written)``.
    """
    e, q, st = memory
    p = q.shape[1]
    work = np.empty(p)
    top = int(st[0])
    previous = st[1]
    count = 0
    k = first
    while k < v.size and count < rows.shape[0]:
        u = min(max(v[k], v_min), v_max)
        if top % 2 == 0:
            if u < previous:
                top = _push_basis(kind, exps, n_seg, v_min, v_max, e, q, top, previous, work)
        elif u > previous:
            top = _push_basis(kind, exps, n_seg, v_min, v_max, e, q, top, previous, work)
        if top % 2 == 0:
            while top >= 2 and u >= e[top - 1]:
                top -= 2
        else:
            while top >= 3 and u <= e[top - 1]:
                top -= 2
        previous = u
        if k >= start and (k - start) % stride == 0:
            row = rows[count]
            _basis_output(kind, exps, n_seg, v_min, v_max, e, q, top, u, work, rows, count)
            row[p] = 1.0
            row[p + 1] = x[k]
            count += 1
        k += 1
    st[0] = top
    st[1] = previous
    return k, count


@kernel
def gram_update(rows, count, gram):
    """Add ``rows[:count]^T rows[:count]`` to the upper triangle of ``gram``.

    A plain loop rather than BLAS: interleaved with :func:`preisach_rows` calls, a threaded
    BLAS wakes its threads for every block, which on a loaded machine costs far more than
    the arithmetic (Benchmarks, "Speed"); zeros, frequent in Preisach regressors, are skipped.
    """
    p = rows.shape[1]
    for r in range(count):
        for i in range(p):
            ri = rows[r, i]
            if ri == 0.0:
                continue
            for j in range(i, p):
                gram[i, j] += ri * rows[r, j]
