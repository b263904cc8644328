"""Elementary hysteresis operators as compiled kernels (the bottom layer).

* the play (backlash) operator of eq. (11), ``y[k] = max(v[k] - r, min(v[k] + r, y[k-1]))``;
* the one-sided dead-zone of eq. (13), ``s_r(z) = max(z - r, 0)`` for ``r > 0`` and ``z``
  for ``r = 0``, and its weighted superposition, eq. (14).

Every Prandtl-Ishlinskii-type map in hystcomp, forward or inverse, is the same *chain*::

    u -> (u - in_offset) -> [dead-zones A] -> [plays] -> [dead-zones B] -> (+ out_offset)
      -> slew-rate limit -> clamp to [lo, hi]

with any stage possibly empty: the PI model (eq. 12) is the plays alone, the MPI model
(eq. 15) is plays then dead-zones, the inverse MPI (eq. 23) is dead-zones then plays. A chain
is *packed* into one float64 array (parameters, then state), so that a streaming step is one
compiled call on one array, and batch runs, steppers, the C export and the benchmarks all use
:func:`chain_step`: there is one play loop in the package.

These functions trust their input; validation happens in the public classes above.
"""

from __future__ import annotations

import numba
import numpy as np

# Fast-math without 'nnan'/'ninf': reassociation lets the reductions vectorise, while the
# stepper's finiteness test on the reference must survive compilation.
FASTMATH = {"reassoc", "contract", "nsz", "arcp"}


def _kernel(func):
    return numba.njit(cache=True, fastmath=FASTMATH, nogil=True)(func)


# Layout of a packed chain: header slots, then parameters, then state.
N_PRE, N_PLAY, N_POST, IN_OFFSET, OUT_OFFSET, LOW, HIGH, MAX_STEP = range(8)
HEADER = 8
# State slots, from chain_state_start(p): last output, count of non-finite inputs, play states.
STATE_LAST, STATE_NONFINITE, STATE_PLAYS = 0, 1, 2


@_kernel
def play_update(v, r, y):
    """Advance a bank of play operators by one sample, in place (eq. 11).

    Parameters
    ----------
    v : float
        The input sample.
    r : ndarray
        Thresholds ``r_i >= 0``.
    y : ndarray
        States ``y_i[k-1]`` on entry, ``y_i[k]`` on return.
    """
    for i in range(r.size):
        y[i] = max(v - r[i], min(v + r[i], y[i]))


@_kernel
def deadzone_sum(z, r, w):
    """Weighted superposition of one-sided dead-zones (eqs. 13-14); ``r[0]`` must be 0."""
    acc = w[0] * z
    for j in range(1, r.size):
        acc += w[j] * max(z - r[j], 0.0)
    return acc


@_kernel
def deadzone_values(z, r, out):
    """Each one-sided dead-zone of eq. (13) at ``z``: ``out[j] = s_{r_j}(z)``.

    The per-operator regressors of the inverse saturation operator in eq. (19).
    """
    for j in range(r.size):
        out[j] = max(z - r[j], 0.0) if r[j] > 0.0 else z


@_kernel
def chain_state_start(p):
    """Index of the first state slot of packed chain ``p``."""
    return HEADER + 2 * (int(p[N_PRE]) + int(p[N_PLAY]) + int(p[N_POST]))


@_kernel
def chain_step(p, u):
    """One sample through packed chain ``p``; updates the state in ``p`` and returns the output.

    A non-finite ``u``, or a result that overflows to NaN (a ``u`` near the float range),
    holds the last output and increments the non-finite counter.
    """
    n_pre = int(p[N_PRE])
    n_play = int(p[N_PLAY])
    n_post = int(p[N_POST])
    s = HEADER + 2 * (n_pre + n_play + n_post)
    last = p[s + STATE_LAST]
    if u - u != 0.0:  # NaN or +-inf
        p[s + STATE_NONFINITE] += 1.0
        return last
    z = u - p[IN_OFFSET]
    o = HEADER
    if n_pre > 0:
        z = deadzone_sum(z, p[o : o + n_pre], p[o + n_pre : o + 2 * n_pre])
        o += 2 * n_pre
    if n_play > 0:
        r = p[o : o + n_play]
        w = p[o + n_play : o + 2 * n_play]
        y = p[s + STATE_PLAYS : s + STATE_PLAYS + n_play]
        play_update(z, r, y)
        acc = 0.0
        for i in range(n_play):
            acc += w[i] * y[i]
        z = acc
        o += 2 * n_play
    if n_post > 0:
        z = deadzone_sum(z, p[o : o + n_post], p[o + n_post : o + 2 * n_post])
    out = z + p[OUT_OFFSET]
    # NaN from an overflow (u finite but near the float range): hold, as for a non-finite u.
    # Written as a comparison: fast-math folds the `out - out` test away here.
    if not abs(out) <= np.inf:
        p[s + STATE_NONFINITE] += 1.0
        return last
    step = p[MAX_STEP]
    out = min(max(out, last - step), last + step)
    out = min(max(out, p[LOW]), p[HIGH])
    p[s + STATE_LAST] = out
    return out


@_kernel
def chain_run(p, u, out):
    """Run every sample of ``u`` through packed chain ``p`` into ``out`` (state kept in ``p``)."""
    for k in range(u.size):
        out[k] = chain_step(p, u[k])


@_kernel
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
        The play operators.
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
    play_r, play_w, play_y0 = plays if plays is not None else (*empty2, np.empty(0))
    header = [len(pre_r), len(play_r), len(post_r), in_offset, out_offset, low, high, max_step]
    state = [min(max(0.0, low), high), 0.0]
    parts = [header, pre_r, pre_w, play_r, play_w, post_r, post_w, state, play_y0]
    return np.concatenate([np.asarray(a, dtype=np.float64) for a in parts])
