"""The play / dead-zone chain as compiled kernels: the PI-type models and their inverses.

* the play (backlash) operator of eq. (11), ``y[k] = max(v[k] - r, min(v[k] + r, y[k-1]))``;
* the one-sided dead-zone of eq. (13), ``s_r(z) = max(z - r, 0)`` for ``r > 0`` and ``z``
  for ``r = 0``, and its weighted superposition, eq. (14).

Every Prandtl-Ishlinskii-type map in hystcomp, forward or inverse, is the same *chain*::

    u -> (u - in_offset) -> [dead-zones A] -> [plays] -> [dead-zones B] -> (+ out_offset)
      -> slew-rate limit -> clamp to [lo, hi]

with any stage possibly empty: the PI model (eq. 12) is the plays alone, the MPI model
(eq. 15) is plays then dead-zones, the inverse MPI (eq. 23) is dead-zones then plays. A chain
is *packed* into one float64 array (parameters, then state), so that a streaming step is one
compiled call on one array. Batch runs and steppers both go through :func:`chain_blocks`
(a step is a one-sample run), which uses the one play loop (:func:`play_step`) and the one
dead-zone loop (:func:`deadzone_block`) of the package; :data:`CHAIN_KERNELS` tells the
streaming stepper how to run a chain. The layout of a packed chain is named by the slot
constants below (header ``N_PRE`` .. ``MAX_STEP``, state ``STATE_LAST`` .. ``STATE_PLAYS``);
:func:`pack_chain` and :func:`unpack_chain` write and read it and live here, beside the
layout they must agree with.

Speed: a batch run takes the samples in blocks and the chain stage by stage. The dead-zones
are stateless, so each is a pass over the block that vectorises over samples; the plays are
the only recurrence and go sample by sample, vectorised over operators (their count is
padded to :data:`PLAY_MULTIPLE` with operators of zero weight, so the vector loop has no
scalar remainder). The figures are in the documentation (Benchmarks, "Speed").

These functions trust their input; validation happens in the public classes above.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from hystcomp._kernels._jit import StepKernels, inline_kernel, kernel, step_kernel

# Layout of a packed chain: header slots, then parameters, then state.
N_PRE, N_PLAY, N_POST, IN_OFFSET, OUT_OFFSET, LOW, HIGH, MAX_STEP = range(8)
HEADER = 8
# State slots, from chain_state_start(p): last output, count of non-finite inputs, count of
# clamped outputs, three scratch slots for chain_step (its input, output and work sample),
# then the play states.
(
    STATE_LAST,
    STATE_NONFINITE,
    STATE_CLAMPED,
    STATE_INPUT,
    STATE_OUTPUT,
    STATE_WORK,
    STATE_PLAYS,
) = range(7)
#: An output beyond the clamp by more than this fraction of the range counts as clamped
#: (an exactly reachable reference may land a few roundings outside it).
CLAMP_TOLERANCE = 1e-9
# Samples per stage pass in a batch run: the block and the parameters stay in L1 cache.
BLOCK = 256
#: Largest input of the plays that moves them: beyond it (a reference near the float range,
#: where the weighted sum would overflow) the sample is held like a non-finite one, and the
#: plays stay where they are, so that they keep following what the amplifier was given.
PLAY_INPUT_LIMIT = 1e150
# pack_chain pads the plays to a multiple of this count (the vector loop's step on AVX2).
PLAY_MULTIPLE = 8

ChainParts = namedtuple(
    "ChainParts",
    "in_offset out_offset low high max_step pre_r pre_w play_r play_w post_r post_w state plays",
)
ChainParts.__doc__ = """Views into a packed chain: its scalars, stage parameters and state."""


@inline_kernel
def play_step(v, r, w, y):
    """Advance a bank of play operators by one sample, in place, and weigh them.

    The one play loop of the package: eq. (11) for every operator and, in the same pass,
    the weighted sum of eq. (12) (a fused loop vectorises; two loops cost more).

    Parameters
    ----------
    v : float
        The input sample.
    r : ndarray
        Thresholds ``r_i >= 0``.
    w : ndarray
        Weights ``w_i``, as long as ``r``.
    y : ndarray
        States ``y_i[k-1]`` on entry, ``y_i[k]`` on return.

    Returns
    -------
    float
        ``sum_i w_i y_i[k]``.
    """
    acc = 0.0
    for i in range(r.size):
        yi = max(v - r[i], min(v + r[i], y[i]))
        y[i] = yi
        acc += w[i] * yi
    return acc


@inline_kernel
def play_update(v, r, y):
    """Advance a bank of play operators by one sample, in place (eq. 11), without weights."""
    play_step(v, r, r, y)  # the weighted sum is unused and compiled away


@inline_kernel
def deadzone_block(x, shift, r, w, out):
    """Weighted one-sided dead-zones (eqs. 13-14) of every sample of a block.

    ``out[k] = sum_j w_j s_{r_j}(x[k] - shift)``, with ``s_0(z) = z`` (``r[0]`` must be 0,
    and the thresholds must not decrease) and ``s_r(z) = max(z - r, 0)``. The one dead-zone
    loop of the package. Operators are the outer loop and samples the inner one, so the
    inner loop vectorises over samples without a reduction, and each sample's sum is formed
    in the same order whatever the block length (a one-sample block gives the same bits as a
    long one). ``out`` must not overlap ``x``.

    A one-sample block (a streaming step) is folded: its sum is kept in a register, not in
    ``out`` (which a step's caller passes as a slot of the packed array beside ``r`` and
    ``w``, so the compiler reloaded it after every term), and it stops at the
    first threshold the sample does not pass: every later term is ``w_j * 0``, which adds
    nothing. The terms it adds are those of the block loop, in the same order, so the bits
    are the same (the data-dependent exit also keeps the compiler from reordering the sum).
    """
    if x.size == 1:
        xk = x[0]
        acc = w[0] * min(xk - shift, 0.0)
        for j in range(r.size):
            d = xk - (r[j] + shift)
            if not d > 0.0:  # s_r = 0 here and at every later (larger) threshold
                break
            acc += w[j] * d
        out[0] = acc
        return
    w0 = w[0]
    for k in range(x.size):
        out[k] = w0 * min(x[k] - shift, 0.0)  # with the j = 0 term below: w_0 * (x - shift)
    for j in range(r.size):
        rj = r[j] + shift
        wj = w[j]
        for k in range(x.size):
            out[k] += wj * max(x[k] - rj, 0.0)


@kernel
def deadzone_values(z, r, out):
    """Each one-sided dead-zone of eq. (13) at ``z``: ``out[j] = s_{r_j}(z)``.

    The per-operator regressors of the inverse saturation operator in eq. (19).
    """
    for j in range(r.size):
        out[j] = max(z - r[j], 0.0) if r[j] > 0.0 else z


@kernel
def regressor_rows(u, r, y, z, rs, begin, rows):
    """Regressor rows ``[plays | dead-zones (positive) | 1 | z]`` of eqs. (12) and (19).

    Fills ``rows[i]`` for sample ``begin + i`` (as many as ``rows`` has), advancing the
    play states ``y`` over those samples in place. No matrix product here: the Gram update
    is NumPy's (BLAS) in :func:`hystcomp.identify.lsq.normal_equations`, so that this
    kernel compiles without numba's linear algebra (which took most of a first run's
    compile time).
    """
    n = r.size
    m = rs.size
    for i in range(rows.shape[0]):
        k = begin + i
        play_update(u[k], r, y)
        for j in range(n):  # a loop, not row[:n] = y: slice assignment compiles slowly
            rows[i, j] = y[j]
        deadzone_values(z[k], rs, rows[i, n : n + m])  # negated after the sums
        rows[i, n + m] = 1.0
        rows[i, n + m + 1] = z[k]


@inline_kernel
def chain_state_start(p):
    """Index of the first state slot of packed chain ``p``."""
    return HEADER + 2 * (int(p[N_PRE]) + int(p[N_PLAY]) + int(p[N_POST]))


@inline_kernel
def chain_parts(p):
    """The :data:`ChainParts` of packed chain ``p`` (views that share its memory)."""
    n_pre = int(p[N_PRE])
    n_play = int(p[N_PLAY])
    n_post = int(p[N_POST])
    o_play = HEADER + 2 * n_pre
    o_post = o_play + 2 * n_play
    s = o_post + 2 * n_post
    return ChainParts(
        p[IN_OFFSET],
        p[OUT_OFFSET],
        p[LOW],
        p[HIGH],
        p[MAX_STEP],
        p[HEADER : o_play - n_pre],
        p[o_play - n_pre : o_play],
        p[o_play : o_post - n_play],
        p[o_post - n_play : o_post],
        p[o_post : s - n_post],
        p[s - n_post : s],
        p[s : s + STATE_PLAYS],
        p[s + STATE_PLAYS : s + STATE_PLAYS + n_play],
    )


@inline_kernel
def chain_blocks(p, u, out, work):
    """Run every sample of ``u`` through packed chain ``p`` into ``out``; state kept in ``p``.

    A non-finite sample, or one whose result overflows or that reaches the plays beyond
    :data:`PLAY_INPUT_LIMIT`, holds the last output and increments the non-finite counter;
    the plays advance only on the samples that are not held. An output
    that the clamp moves by more than :data:`CLAMP_TOLERANCE` of the range increments the
    clamped counter. Samples go through in blocks of :data:`BLOCK`, stage by stage: the stateless dead-zone
    stages as passes over the block, the plays and the output limits sample by sample.
    ``out`` is the work buffer of the stages before the plays and ``work`` (at least
    ``min(BLOCK, u.size)`` long if the chain has dead-zones after the plays) that of the
    stage after; none of the three may overlap another.
    """
    (
        in_offset,
        out_offset,
        low,
        high,
        max_step,
        pre_r,
        pre_w,
        play_r,
        play_w,
        post_r,
        post_w,
        state,
        plays,
    ) = chain_parts(p)
    last = state[STATE_LAST]
    held = state[STATE_NONFINITE]
    clamped = state[STATE_CLAMPED]
    tol = CLAMP_TOLERANCE * (high - low)  # inf without a clamp: nothing counts
    slewing = max_step < np.inf  # a loop-invariant test: without a limit, no recurrence
    for start in range(0, u.size, BLOCK):
        ub = u[start : start + BLOCK]
        z = out[start : start + BLOCK]
        if pre_r.size > 0:
            deadzone_block(ub, in_offset, pre_r, pre_w, z)
        else:
            for k in range(ub.size):
                z[k] = ub[k] - in_offset
        if play_r.size > 0:
            for k in range(ub.size):
                if abs(z[k]) < PLAY_INPUT_LIMIT:  # the plays advance
                    z[k] = play_step(z[k], play_r, play_w, plays)
                else:  # NaN, +-inf or near the float range: held below, plays unmoved
                    z[k] = np.inf
        zb = z
        if post_r.size > 0:
            zb = work[: ub.size]
            deadzone_block(z, 0.0, post_r, post_w, zb)
        for k in range(ub.size):
            zk = zb[k] + out_offset
            # NaN or +-inf input, or a result that overflowed (a finite input near the
            # float range): hold the last output. Written as comparisons with inf, which
            # the fast-math flags in use keep.
            if ub[k] - ub[k] != 0.0 or not abs(zk) < np.inf:
                held += 1.0
            else:
                if slewing:
                    zk = min(max(zk, last - max_step), last + max_step)
                if zk < low - tol or zk > high + tol:
                    clamped += 1.0
                last = min(max(zk, low), high)
            z[k] = last
    state[STATE_LAST] = last
    state[STATE_NONFINITE] = held
    state[STATE_CLAMPED] = clamped


@inline_kernel
def one_sample(block, p, i, o, w, u):
    """``u`` through ``block(p, u, out, work)`` as a one-sample block, the output.

    The sample, the output and the work buffer are the slots ``i``, ``o`` and ``w`` of
    ``p`` (a state's scratch slots), so that a streaming step and the batch run it mirrors
    are the same code, bit for bit. Inlined into each step kernel, with ``block`` a
    compile-time constant there.
    """
    p[i] = u
    block(p, p[i : i + 1], p[o : o + 1], p[w : w + 1])
    return p[o]


@step_kernel
def chain_step(p, u):
    """One sample through packed chain ``p``; updates the state in ``p`` and returns the output.

    A one-sample :func:`chain_blocks` run (:func:`one_sample`). A non-finite ``u`` holds the
    last output and increments the non-finite counter.
    """
    s = chain_state_start(p)
    return one_sample(chain_blocks, p, s + STATE_INPUT, s + STATE_OUTPUT, s + STATE_WORK, u)


@kernel
def chain_run(p, u, out):
    """Run every sample of ``u`` through packed chain ``p`` into ``out`` (state kept in ``p``).

    ``u`` and ``out`` must not overlap. A non-finite sample holds the last output and
    increments the non-finite counter.
    """
    work = np.empty(min(BLOCK, u.size)) if p[N_POST] > 0 else out[:0]
    chain_blocks(p, u, out, work)


@inline_kernel
def block_status(u, out):
    """0 if ``out`` can take the outputs of ``u`` (as long, not overlapping), else 1 (a
    length) or 2 (an overlap): the checks of a block kernel called from Python."""
    if out.size != u.size:
        return 1
    a, b = u.ctypes.data, out.ctypes.data
    if u.size and a < b + out.nbytes and b < a + u.nbytes:
        return 2
    return 0


@step_kernel
def chain_step_block(p, u, out, work):
    """:func:`chain_run` for a short block from Python (``Stepper.step_block``): the same
    :func:`chain_blocks`, compiled as a step is, without reference counting, so a call of 20
    samples costs little more than their samples; ``work`` holds at least :data:`BLOCK`
    values. Returns :func:`block_status` (0: done; else nothing done)."""
    status = block_status(u, out)
    if status == 0:
        chain_blocks(p, u, out, work)
    return status


#: The :class:`StepKernels` of a packed chain.
CHAIN_KERNELS = StepKernels(
    chain_step,
    chain_run,
    chain_state_start.py_func,
    STATE_LAST,
    STATE_NONFINITE,
    STATE_CLAMPED,
    chain_step_block,
)


@kernel
def play_outputs(v, r, y0, out):
    """Outputs of each play operator for every sample: ``out[k, i] = play_{r_i}(v)[k]``.

    The regressors of PI identification; ``y0`` holds the initial states and is not changed.
    """
    y = y0.copy()
    for k in range(v.size):
        play_update(v[k], r, y)
        out[k, :] = y


def pack_chain(
    *,
    pre: tuple[np.ndarray, np.ndarray] | None = None,
    plays: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    post: tuple[np.ndarray, np.ndarray] | None = None,
    in_offset: float = 0.0,
    out_offset: float = 0.0,
    low: float = -np.inf,
    high: float = np.inf,
    max_step: float = np.inf,
) -> np.ndarray:
    """Pack a chain into one float64 array (see the module docstring for the stages).

    Parameters
    ----------
    pre, post : (thresholds, weights), optional
        Dead-zone superpositions before and after the plays.
    plays : (thresholds, weights, initial_states), optional
        The play operators. They are padded to a multiple of :data:`PLAY_MULTIPLE` with
        operators of threshold 0, weight 0 and state 0, which add nothing to the output
        (:func:`unpack_chain` leaves them out).
    in_offset, out_offset : float
        Subtracted from the input, added to the output.
    low, high : float
        Output clamp.
    max_step : float
        Largest change of the output from one sample to the next (slew-rate limit).

    Returns
    -------
    ndarray
        The packed chain. Its "last output" starts at ``clip(0, low, high)``: the value an
        amplifier holds before the first command.
    """
    empty2 = (np.empty(0), np.empty(0))
    pre_r, pre_w = pre if pre is not None else empty2
    post_r, post_w = post if post is not None else empty2
    play_r, play_w, play_y0 = (*empty2, np.empty(0))
    if plays is not None:
        pad = np.zeros(-len(plays[0]) % PLAY_MULTIPLE)
        play_r, play_w, play_y0 = (np.concatenate([np.asarray(a, np.float64), pad]) for a in plays)
    header = [len(pre_r), len(play_r), len(post_r), in_offset, out_offset, low, high, max_step]
    state = np.zeros(STATE_PLAYS)
    state[STATE_LAST] = min(max(0.0, low), high)
    parts = [header, pre_r, pre_w, play_r, play_w, post_r, post_w, state, play_y0]
    return np.concatenate([np.asarray(a, dtype=np.float64) for a in parts])


def unpack_chain(p: np.ndarray) -> ChainParts:
    """The parts of packed chain ``p`` as read-only copies, without the padding plays.

    For code that reads a chain's parameters (the C export, tests); the kernels use
    :func:`chain_parts`. The padding plays are those after the first with threshold 0
    (real thresholds increase strictly from 0).
    """
    parts = chain_parts.py_func(np.asarray(p, dtype=np.float64))
    n_play = parts.play_r.size
    if n_play > 1:
        zero = np.flatnonzero(parts.play_r[1:] == 0.0)
        n_play = int(zero[0]) + 1 if zero.size else n_play
    copies = {}
    for name, value in parts._asdict().items():
        if isinstance(value, np.ndarray):
            value = value[:n_play].copy() if name in ("play_r", "play_w", "plays") else value.copy()
            value.setflags(write=False)
        else:
            value = float(value)
        copies[name] = value
    return ChainParts(**copies)
