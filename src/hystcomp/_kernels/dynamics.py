"""Compiled kernels of the linear dynamics: the inverse (a batch loop, one step, and one step
in front of a hysteresis compensator) and the two stages of the forward model (a creep lag,
the resonance) that :mod:`hystcomp._lti` runs for the model's output and its identification.

The inverse filter (see :mod:`hystcomp.models.dynamics`) is a FIR stage (non-negative taps
fitted so that the resonance times them is close to 1 in the band) in series with the
exact inverse of the creep bank. Its parameters and state are one packed
float64 array, as the chain's (:mod:`hystcomp._kernels.chain`)::

    [N_FIR, N_CREEP, SCALE, DIRECT, LOW, HIGH, BIAS, h_0 .. h_{N_FIR-1}, a_1 .. a_n, c_1 .. c_n,
     head, input, output, cut (the scratch slots of one step), delay line (2 N_FIR slots),
     creep lag states (n), count of clamped outputs]

The delay line is circular: each sample moves ``head`` back one place (from 0 to
``N_FIR - 1``) and is written there, instead of shifting every sample along. It is held twice
over, each sample written at ``head`` and at ``head + N_FIR``, so that the ``N_FIR`` samples
from the newest (``line[head]``) to the oldest are always contiguous and the taps run over
them in one loop that the compiler vectorises, with no index that wraps.

The creep bank of the forward model is ``D_c[q] = (q + sum_i c_i lag_i) / SCALE`` with
``lag_i[k] = a_i lag_i[k-1] + (1 - a_i) q[k]`` and ``SCALE = 1 + sum_i c_i``. Its inverse
solves that equation for ``q[k]`` each sample (``DIRECT = 1 + sum_i c_i (1 - a_i)``): no
root of any polynomial is computed, so creep poles a hair below 1 stay exact. The output
is clamped to ``[LOW, HIGH]`` (the hysteresis model's displacement range), so that the
hysteresis inverse downstream never takes a memory the actuator cannot follow; the creep
lags follow the clamped output, and an output that the clamp moves by more than
:data:`~hystcomp._kernels.chain.CLAMP_TOLERANCE` of the range is counted (the reference
is out of reach there), as the chain counts its voltage clamp. Kernels trust
their input. The FIR's output is ``BIAS + sum_j h_j u[k - j]`` (a gain other than 1 at
0 Hz, about a rest point, is a scaling of the taps and a bias).
"""

from __future__ import annotations

import math

from hystcomp._kernels import chain, preisach
from hystcomp._kernels._jit import inline_kernel, inner_kernel, kernel, step_kernel
from hystcomp._kernels.chain import CLAMP_TOLERANCE

N_FIR, N_CREEP, SCALE, DIRECT, LOW, HIGH, BIAS = range(7)
#: Creep lag states smaller than this (µm) are set to 0: far below any displacement, and
#: above the subnormal numbers they would otherwise decay through.
TINY = 1e-200
HEADER = 7
#: Offsets from :func:`state_start` of the state slots: the head of the delay line (the index
#: of its newest sample), the scratch slots of a one-sample run (its input, its output, 1 if
#: the clamp counted it, else 0), then the delay line.
ST_HEAD, ST_INPUT, ST_OUTPUT, ST_CUT, ST_LINE = range(5)


@kernel
def state_start(p):
    """Index of the first state slot (:data:`ST_HEAD`)."""
    return HEADER + int(p[N_FIR]) + 2 * int(p[N_CREEP])


@kernel
def clamped_slot(p):
    """Index of the count of clamped outputs (the last slot)."""
    return state_start(p) + ST_LINE + 2 * int(p[N_FIR]) + int(p[N_CREEP])


@inner_kernel
def inverse_block(p, u, out, cuts):
    """Run every sample of ``u`` through the inverse filter ``p`` into ``out`` (state kept).

    The state is read into locals once and written back at the end; the delay line and the
    creep lags are updated in place. ``cuts[k]`` is 1.0 where the clamp counted sample ``k``,
    else 0.0 (if ``cuts`` is not empty). A non-finite sample gives NaN and leaves the state
    as it was; a huge finite one whose result overflows gives NaN too (it stays in the delay
    line, the lags and the count unmoved). ``u``, ``out`` and ``cuts`` may be slots of ``p``
    outside the state (:func:`inverse_step`). Compiled once, for float64 arrays, whichever
    kernel calls it: the batch runs and the step run the same code.
    """
    n_fir = int(p[N_FIR])
    n_creep = int(p[N_CREEP])
    a0 = HEADER + n_fir
    c0 = a0 + n_creep
    s = c0 + n_creep
    line0 = s + ST_LINE
    lag0 = line0 + 2 * n_fir
    taps = p[HEADER:a0]
    a = p[a0:c0]
    c = p[c0:s]
    line = p[line0:lag0]
    lags = p[lag0 : lag0 + n_creep]
    bias, scale, direct, low, high = p[BIAS], p[SCALE], p[DIRECT], p[LOW], p[HIGH]
    tol = CLAMP_TOLERANCE * (high - low)  # inf without a clamp: nothing counts
    keep_cuts = cuts.size > 0
    head = int(p[s + ST_HEAD])
    count = p[lag0 + n_creep]
    for k in range(u.size):
        x = u[k]
        y = math.nan
        cut = False
        if math.isfinite(x):
            head = head - 1 if head > 0 else n_fir - 1
            line[head] = x
            line[head + n_fir] = x
            w = bias
            for j in range(n_fir):
                w += taps[j] * line[head + j]
            acc = w * scale
            for i in range(n_creep):
                acc -= c[i] * a[i] * lags[i]
            y = acc / direct
            if math.isfinite(y):
                cut = y > high + tol or y < low - tol
                if cut:
                    count += 1.0
                y = min(max(y, low), high)
                for i in range(n_creep):
                    lag = a[i] * lags[i] + (1.0 - a[i]) * y
                    # a lag decaying towards 0 (a reference held at a rest of 0 µm) would
                    # run through subnormal numbers, ten times slower to compute
                    lags[i] = lag if abs(lag) > TINY else 0.0
            else:  # a huge finite reference overflowed: held downstream
                y = math.nan
        out[k] = y
        if keep_cuts:
            cuts[k] = cut
    p[s + ST_HEAD] = head
    p[lag0 + n_creep] = count


@step_kernel
def inverse_step(p, u):
    """One reference sample ``u`` (µm) through the inverse filter; NaN (state kept) if not finite.

    A one-sample :func:`inverse_block` run (:func:`~hystcomp._kernels.chain.one_sample`), so
    that the streaming step and the batch run are the same code and agree bit for bit; the
    slot :data:`ST_CUT` (its scratch slot) then says whether the clamp counted the sample.
    """
    s = state_start(p)
    return chain.one_sample(inverse_block, p, s + ST_INPUT, s + ST_OUTPUT, s + ST_CUT, u)


@kernel
def inverse_run(p, u, out):
    """Run every sample of ``u`` through the inverse filter ``p`` into ``out`` (state kept
    in ``p``), as :func:`inverse_step` would one by one."""
    inverse_block(p, u, out, out[:0])


@kernel
def inverse_run_cuts(p, u, out, cuts):
    """:func:`inverse_run`, and ``cuts[k]`` 1.0 where the clamp counted sample ``k``, else 0.0
    (float64, as the scratch slot of :func:`inverse_step`: one compiled :func:`inverse_block`
    serves all three)."""
    inverse_block(p, u, out, cuts)


# -- the inverse filter in front of a hysteresis compensator, one compiled call a sample ----


@inline_kernel
def _pair_step(pd, ph, clamped, step, u):
    """``u`` (µm) through the inverse filter ``pd``, then ``step`` of the packed compensator
    ``ph`` whose clamp count is in slot ``clamped``: the voltage.

    A sample that the filter's clamp counted (out of reach) is not counted again by the
    voltage range's: the compensator's count is put back. A non-finite ``u`` leaves the
    filter as it was, and the compensator holds its last output and counts it. Inlined into
    each pair's step kernel, with ``step`` a compile-time constant there.
    """
    counted = ph[clamped]
    v = step(ph, inverse_step(pd, u))
    if pd[state_start(pd) + ST_CUT] != 0.0:
        ph[clamped] = counted
    return v


@step_kernel
def chain_pair_step(pd, ph, u):
    """``u`` (µm) through the inverse filter ``pd``, then the packed chain ``ph``: the voltage.

    The streaming step of a compensator with dynamics in one compiled call
    (:func:`_pair_step`).
    """
    clamped = chain.chain_state_start(ph) + chain.STATE_CLAMPED
    return _pair_step(pd, ph, clamped, chain.chain_step, u)


@step_kernel
def preisach_pair_step(pd, ph, u):
    """:func:`chain_pair_step` with a packed Preisach compensator ``ph`` behind the filter."""
    clamped = preisach.state_start(ph) + preisach.ST_CLAMPED
    return _pair_step(pd, ph, clamped, preisach.preisach_step, u)


#: The step kernel of the inverse filter in front of a compensator, by the compensator's
#: step kernel (:class:`~hystcomp.models.dynamic_compensator.DynamicStepper`).
PAIR_STEPS = {chain.chain_step: chain_pair_step, preisach.preisach_step: preisach_pair_step}


@kernel
def lag_run(a, u, out):
    """A first-order lag of unit gain from rest at 0: ``y[k] = a y[k-1] + (1 - a) u[k]``.

    One creep mode of the forward model (``lfilter([1 - a], [1, -a], u)``).
    """
    y = 0.0
    for k in range(u.size):
        y = a * y + (1.0 - a) * u[k]
        out[k] = y


@kernel
def resonance_run(b, a, u, out):
    """``R(z) = (b0 z^-1 + b1 z^-2) / (1 + a1 z^-1 + a2 z^-2)`` from rest at 0.

    The resonance of the forward model (``lfilter([0, b0, b1], a, u)``): the output of
    sample ``k`` is the position before the input of sample ``k`` acts.
    """
    u1 = 0.0
    u2 = 0.0
    y1 = 0.0
    y2 = 0.0
    for k in range(u.size):
        y = b[0] * u1 + b[1] * u2 - a[1] * y1 - a[2] * y2
        out[k] = y
        y2 = y1
        y1 = y
        u2 = u1
        u1 = u[k]
