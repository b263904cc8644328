"""Many play chains of one structure run together, vectorised across channels.

A deformable mirror has tens to thousands of actuators, each with its own hysteresis,
stepped together. Its channels' chains (:mod:`hystcomp._kernels.chain`: dead-zones, plays,
dead-zones, offsets, slew limit, clamp) have the same structure when they come from one
kind of model, so a *bank* holds each parameter as an array of shape ``(operators,
channels)`` and the state likewise, and :func:`bank_run` runs all channels in one call with
the channel as the innermost loop: each operator's update is a vector operation over the
channels of a block (no reduction across lanes).

Loop order: samples in blocks of :data:`SAMPLE_BLOCK`, then channels in blocks of
:data:`CHANNEL_BLOCK`, then the samples of the block, then stages, then operators (two plays
per pass, so the running sum is loaded and stored once per two plays), then the channels
of the block. A block's parameters and states stay in L1 cache over the samples of a
block, and the inputs of a block of samples in L2 over all channel blocks. A step (one
sample) is the same call with one row. Each channel computes what
:func:`~hystcomp._kernels.chain.chain_blocks` computes for it, stage by stage and in the
same formulas (the dead-zones of :func:`~hystcomp._kernels.chain.deadzone_block`, the play
of eq. 11, the hold of a non-finite sample, the slew limit, the clamp and its counters);
only the order of the sum over the plays differs (two by two here, vectorised over
operators there), so the two agree to rounding.

Layout of a bank (the arrays :func:`bank_run` takes):

* ``pre_r, pre_w, play_r, play_w, post_r, post_w``: (n_stage, C) thresholds and weights
  (an even number of plays: a play of threshold and weight 0 pads an odd count);
* ``scalars``: (5, C), rows :data:`IN_OFFSET`, :data:`OUT_OFFSET`, :data:`LOW`,
  :data:`HIGH`, :data:`MAX_STEP`;
* ``plays``: (n_play, C) play states; ``counters``: (3, C), rows :data:`LAST`,
  :data:`NONFINITE`, :data:`CLAMPED`;
* ``work``: (2, :data:`CHANNEL_BLOCK`) scratch.

Kernels trust their input; :mod:`hystcomp.models.channels` validates and packs.
"""

from __future__ import annotations

import numpy as np

from hystcomp._kernels._jit import flat_kernel, inline_kernel
from hystcomp._kernels.chain import CLAMP_TOLERANCE, PLAY_INPUT_LIMIT

IN_OFFSET, OUT_OFFSET, LOW, HIGH, MAX_STEP = range(5)
LAST, NONFINITE, CLAMPED = range(3)
#: Channels per block (a vector loop over them; 16 plays' thresholds, weights and states of
#: a block take 48 KiB, an L1 cache; 128 ran faster than 64: Benchmarks, "Speed").
CHANNEL_BLOCK = 128
#: Plays per pass over a block's channels (the running sum is loaded and stored once per
#: pass): the bank's play count is a multiple of it.
PLAYS_PER_PASS = 4
#: Samples per block of a batch run.
SAMPLE_BLOCK = 32


@inline_kernel
def _deadzones(x, shift, r, w, out, m):
    """``out[c] = sum_j w[j, c] s_{r[j, c]}(x[c] - shift[c])``: deadzone_block's formulas,
    for the ``m`` channels of a block (``r``, ``w``: rows of the block)."""
    for c in range(m):
        out[c] = w[0, c] * min(x[c] - shift[c], 0.0)
    for j in range(r.shape[0]):
        rj = r[j]
        wj = w[j]
        for c in range(m):
            out[c] += wj[c] * max(x[c] - (rj[c] + shift[c]), 0.0)


@inline_kernel
def _four_plays(z, r, w, y, i, c0, acc, m):
    """Advance plays ``i .. i + 3`` (eq. 11) of every channel of a block (``c0 ..``) and add
    their weighted sum to ``acc``."""
    r0, r1, r2, r3 = r[i, c0:], r[i + 1, c0:], r[i + 2, c0:], r[i + 3, c0:]
    w0, w1, w2, w3 = w[i, c0:], w[i + 1, c0:], w[i + 2, c0:], w[i + 3, c0:]
    y0, y1, y2, y3 = y[i, c0:], y[i + 1, c0:], y[i + 2, c0:], y[i + 3, c0:]
    for c in range(m):
        zc = z[c]
        a = max(zc - r0[c], min(zc + r0[c], y0[c]))
        b = max(zc - r1[c], min(zc + r1[c], y1[c]))
        d = max(zc - r2[c], min(zc + r2[c], y2[c]))
        e = max(zc - r3[c], min(zc + r3[c], y3[c]))
        y0[c] = a
        y1[c] = b
        y2[c] = d
        y3[c] = e
        acc[c] += (w0[c] * a + w1[c] * b) + (w2[c] * d + w3[c] * e)


@flat_kernel
def bank_run(pre_r, pre_w, play_r, play_w, post_r, post_w, scalars, plays, counters, u, out, work):
    """Run every row of ``u`` (samples, channels) through the bank into ``out``; the
    states in ``plays`` and ``counters`` advance. ``u`` and ``out`` must not overlap."""
    n, n_ch = u.shape
    n_pre = pre_r.shape[0]
    n_play = play_r.shape[0]
    n_post = post_r.shape[0]
    for k0 in range(0, n, SAMPLE_BLOCK):
        k1 = min(n, k0 + SAMPLE_BLOCK)
        for c0 in range(0, n_ch, CHANNEL_BLOCK):
            c1 = min(c0 + CHANNEL_BLOCK, n_ch)
            m = c1 - c0
            z = work[0, :m]
            acc = work[1, :m]
            in_off = scalars[IN_OFFSET, c0:c1]
            out_off = scalars[OUT_OFFSET, c0:c1]
            low = scalars[LOW, c0:c1]
            high = scalars[HIGH, c0:c1]
            max_step = scalars[MAX_STEP, c0:c1]
            last = counters[LAST, c0:c1]
            held = counters[NONFINITE, c0:c1]
            clamped = counters[CLAMPED, c0:c1]
            for k in range(k0, k1):
                uk = u[k, c0:c1]
                # the dead-zones before the plays, or the offset
                if n_pre > 0:
                    _deadzones(uk, in_off, pre_r[:, c0:c1], pre_w[:, c0:c1], z, m)
                else:
                    for c in range(m):
                        z[c] = uk[c] - in_off[c]
                # the plays, two by two, the channels of the block in the innermost loop
                if n_play > 0:
                    moving = True
                    for c in range(m):
                        moving &= abs(z[c]) < PLAY_INPUT_LIMIT
                        acc[c] = 0.0
                    if moving:  # the common case: every channel's plays advance
                        for i in range(0, n_play, PLAYS_PER_PASS):
                            _four_plays(z, play_r, play_w, plays, i, c0, acc, m)
                        for c in range(m):
                            z[c] = acc[c]
                    else:  # some channel's input is held: its plays stay where they are
                        for c in range(m):
                            q = c0 + c
                            zc = z[c]
                            if abs(zc) < PLAY_INPUT_LIMIT:
                                s = 0.0
                                for i in range(n_play):
                                    y = max(zc - play_r[i, q], min(zc + play_r[i, q], plays[i, q]))
                                    plays[i, q] = y
                                    s += play_w[i, q] * y
                                z[c] = s
                            else:
                                z[c] = np.inf
                # the dead-zones after the plays
                if n_post > 0:
                    for c in range(m):
                        acc[c] = post_w[0, c0 + c] * min(z[c], 0.0)
                    for j in range(n_post):
                        rj = post_r[j, c0:c1]
                        wj = post_w[j, c0:c1]
                        for c in range(m):
                            acc[c] += wj[c] * max(z[c] - rj[c], 0.0)
                    for c in range(m):
                        z[c] = acc[c]
                # offset, hold, slew limit, clamp and counters (chain_blocks' last loop),
                # without branches: each channel's outcome selected
                ok = out[k, c0:c1]
                for c in range(m):
                    zk = z[c] + out_off[c]
                    prev = last[c]
                    bad = (uk[c] - uk[c] != 0.0) | (not abs(zk) < np.inf)
                    zs = min(max(zk, prev - max_step[c]), prev + max_step[c])
                    tol = CLAMP_TOLERANCE * (high[c] - low[c])
                    cut = (zs < low[c] - tol) | (zs > high[c] + tol)
                    new = min(max(zs, low[c]), high[c])
                    held[c] += 1.0 if bad else 0.0
                    clamped[c] += 1.0 if cut and not bad else 0.0
                    new = prev if bad else new
                    last[c] = new
                    ok[c] = new
