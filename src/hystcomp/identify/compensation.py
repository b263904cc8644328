"""How well a model's compensator is expected to track, estimated from the record alone.

A model that reproduces its record can still make a bad compensator: its inverse amplifies
every place where the fitted curve is nearly flat. The tracking error of a compensator is
the error of the voltage it commands, seen through the actuator's gain. So we run the
model's inverse on the *measured* displacement of the record: where the compensator would
ask for ``v_hat[k]`` to reach ``x[k]``, the actuator needed ``v[k]``; the difference,
mapped to µm through the record's straight-line gain ``a`` (µm/V), estimates the tracking
error in µm::

    e[k] ~ a * (v_hat[k] - v[k]),        v_hat = model.inverse().simulate(x)

The same estimate for the straight-line compensator ``v = (x - b) / a`` (the uncompensated
baseline of the paper's Table I, with the record's least-squares line) is the line's own
residual ``x - a v - b``: the two numbers are comparable, and a model is predicted to help
only if its estimate is below the line's.

It works for any model with ``inverse()`` (an object with ``simulate``) and is cheap: a
long record is thinned first (the models are rate-independent, so keeping every turning
point and a regular subset of the samples between them changes nothing for them;
:func:`~hystcomp.identify.scoring.thin`).

Choosing among candidate fits of one record (the MPI ``regularization="auto"``) needs more
than the record's own errors: a fit with less regularisation always follows its record
closer, while the compensator meets other signals. :func:`tracking_scorer` with the fits
of a cross-validation over the record's reversal segments
(:func:`~hystcomp.identify.scoring.reversal_folds`, :data:`CV_FOLDS` folds, each fit on the
other folds) rates each candidate by ``criterion_um``: the geometric mean of the held-out
forward error and the held-out inverse error above, on the branches each fit did not see.
On the panel of ``benchmarks/bench_accuracy.py`` (5 actuators of none of the model
families, 4 excitations) it ranks the candidate PI and MPI fits of a record as their
measured 1 Hz tracking does with a median Spearman rank correlation of 0.96 (mean 0.88,
worst cell 0.29), where the fit error reaches 0.93 (0.86, 0.29) and the inverse's estimate
on the whole record 0.91 (0.81, 0.25); the MPI regularisation it chooses tracks within
0.002x of the uncompensated error of the best of the grid in every cell (fit error 0.002x,
the estimate alone 0.012x; before the MPI fit chose its plays' initial memory too, 0.015x,
0.042x and 0.025x). The estimate alone is weakest on a Preisach actuator with
output saturation, where a voltage error at the saturated top counts more than the
tracking error it causes; the held-out forward error is not.
"""

from __future__ import annotations

import numpy as np

from hystcomp._validation import as_signal_pair, check_int
from hystcomp.errors import IdentificationError
from hystcomp.identify.scoring import straight_line, thin

#: Records longer than this are thinned before the inverse is run on them.
MAX_SCORED_SAMPLES = 100_000


#: Records longer than this are thinned further for the held-out fits' runs.
MAX_CV_SAMPLES = 5_000

#: Folds of the cross-validation over reversal segments in :func:`tracking_scorer`.
CV_FOLDS = 6


def tracking_scorer(v, x, *, start: int = 0, max_samples=MAX_SCORED_SAMPLES, folds=None):
    """A function ``score(model, held_out=()) -> dict`` that rates a model's compensator.

    The record is validated, its straight line fitted and thinned once, so that scoring many
    candidate models of the same record costs one inverse run of the thinned record each
    (:func:`compensation_error`), and one forward run per held-out fit.

    With ``folds`` (the fold of every sample, :func:`~hystcomp.identify.scoring.
    reversal_folds`) and, for a model, its fits ``held_out`` on all folds but one (fit
    ``f`` leaves out fold ``f``), the score also holds the cross-validated forward error
    ``held_out_rms_um``: each held-out fit's error on the reversal segments it did not see.
    The tracking error of a compensator is the forward model's error at the voltages the
    compensator commands, so an error on unseen branches predicts it where the record's
    own error cannot (a fit with less regularisation always follows its own record
    better). The ranking criterion ``criterion_um`` is the geometric mean of the two
    estimates: the held-out forward error (the size of the model's error away from its
    record) and the inverse's error on the record (which sees the steep slopes of an
    inverse the forward error cannot). Without held-out fits it is the latter alone.

    ``score(model, held_out, estimate=False)`` leaves out the inverse's run over the whole
    record: the score then holds the held-out figures and ``criterion_um`` only, enough to
    rank candidates at a fraction of the cost.
    """
    owner = "compensation_error"
    v, x = as_signal_pair(v, x, ("v", "x"), owner, min_samples=2)
    start = check_int(start, "start", owner, minimum=0)
    max_samples = check_int(max_samples, "max_samples", owner, minimum=2)
    if start >= v.size - 1:
        raise IdentificationError(
            f"{owner}: 'start' ({start}) leaves fewer than 2 of the {v.size} samples to score."
        )
    a, b = straight_line(v[start:], x[start:])
    if not a > 0:
        raise IdentificationError(
            f"{owner}: the record's straight-line gain is {a:g} µm/V; the displacement must "
            "rise with the voltage. Check the sign and the columns of the record."
        )
    keep = thin(v, start, max_samples)
    v_k, x_k = v[keep], np.ascontiguousarray(x[keep])
    scored = keep >= start
    v_s = v_k[scored]
    line = x_k[scored] - a * v_s - b
    line_rms = float(np.sqrt(np.mean(line**2)))
    folds_k = None
    if folds is not None:
        folds = np.asarray(folds)
        if folds.shape != v.shape:
            raise IdentificationError(
                f"{owner}: 'folds' must give one fold per sample ({v.size}). "
                f"Got shape {folds.shape}."
            )
        # the held-out fits run on fewer samples still (every turning point kept)
        cv_keep = thin(v_k, int(np.searchsorted(keep, start)), MAX_CV_SAMPLES)
        v_cv, x_cv = v_k[cv_keep], np.ascontiguousarray(x_k[cv_keep])
        folds_k = folds[keep][cv_keep]

    def score(model, held_out=(), *, estimate=True) -> dict:
        out: dict = {}
        if estimate or not (held_out and folds_k is not None):
            v_hat = np.asarray(model.inverse().simulate(x_k), dtype=np.float64)
            err = a * (v_hat[scored] - v_s)
            model_rms = float(np.sqrt(np.mean(err**2)))
            out = {
                "tracking_rms_um": model_rms,
                "baseline_rms_um": line_rms,
                "ratio": model_rms / line_rms if line_rms > 0 else float("inf"),
                "gain_um_per_v": a,
                "n_scored": int(v_s.size),
                "criterion_um": model_rms,
            }
        if held_out and folds_k is not None:
            forward, inverse, count = 0.0, 0.0, 0
            for fold, fitted in enumerate(held_out):
                mine = folds_k == fold
                e = np.asarray(fitted.simulate(v_cv), dtype=np.float64)[mine] - x_cv[mine]
                forward += float(e @ e)
                e = np.asarray(fitted.inverse().simulate(x_cv), dtype=np.float64)[mine]
                e = a * (e - v_cv[mine])
                inverse += float(e @ e)
                count += int(mine.sum())
            count = max(count, 1)
            out["held_out_rms_um"] = float(np.sqrt(forward / count))
            out["held_out_tracking_rms_um"] = float(np.sqrt(inverse / count))
            out["criterion_um"] = float(np.sqrt(np.sqrt(forward * inverse) / count))
        return out

    return score


def compensation_error(model, v, x, *, start: int = 0, max_samples=MAX_SCORED_SAMPLES) -> dict:
    """Estimated tracking error of ``model.inverse()`` from a record ``(v, x)``, in µm rms.

    Parameters
    ----------
    model : object
        Any fitted model with ``inverse()`` (PI, MPI, Preisach).
    v, x : array_like
        The record: voltage (V) and measured displacement (µm).
    start : int, default 0
        First sample scored (after a start-up transient); the inverse runs from sample 0.
    max_samples : int, default 100000
        Thin longer records to about this many samples
        (:func:`~hystcomp.identify.scoring.thin`).

    Returns
    -------
    dict
        ``tracking_rms_um``: the estimate for the model's compensator; ``baseline_rms_um``:
        the same for the straight line ``v = (x - b) / a``; ``ratio``: their quotient
        (below 1 when the model is predicted to track better than the line);
        ``gain_um_per_v``: ``a``; ``n_scored``: samples scored.

    Examples
    --------
    >>> from hystcomp import presets
    >>> from hystcomp.identify.excitation import triangle_sequence
    >>> model = presets.paper_mpi()
    >>> _, v = triangle_sequence(sample_rate=500)
    >>> est = compensation_error(model, v, model.simulate(v))
    >>> bool(est["tracking_rms_um"] < 1e-6 < est["baseline_rms_um"])
    True
    """
    return tracking_scorer(v, x, start=start, max_samples=max_samples)(model)
