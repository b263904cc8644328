"""The application layer: what a command does, as a library function with a structured
result (figures, the fitted or built objects, report lines and warnings) that the command
line words. A sentence that names a remedy is a :class:`hystcomp._notice.Notice`: Python's
words by default, the command line's options when it says it.

* :mod:`hystcomp.workflows.identify`: a hysteresis model (PI, MPI, Preisach) from a record,
  its fit, hold-out and tracking estimate (``hystcomp identify``).
* :mod:`hystcomp.workflows.auto`: the model family whose compensator is predicted to track
  best (the family ``'auto'``).
* :mod:`hystcomp.workflows.pair`: a hysteresis model and the linear dynamics identified as
  one pair (from a hysteresis record and a dynamics record), the dynamics alone, and what
  :mod:`~hystcomp.workflows.compensate` reads of the pair's estimates.
* :mod:`hystcomp.workflows.multiaxis`: N coupled axes from one record.
* :mod:`hystcomp.workflows.record`: whichever of these the options ask for.
* :mod:`hystcomp.workflows.compensate`: the voltage for a reference, with what to know of it
  (clamps, extrapolation, eq. 10's own turns), and the C export (``hystcomp compensate``,
  ``export-c``).
* :mod:`hystcomp.workflows.simulate`: the forward model on a voltage, validated against a
  measured displacement (``hystcomp simulate``).
* :mod:`hystcomp.workflows.evaluate`: a run's tracking, from a reference and a measured run
  (``hystcomp evaluate``; :func:`hystcomp.evaluate`).
* :mod:`hystcomp.workflows.compare`: the paper's experiment on the twin, using a second
  process and the cycle collector as the command does (``hystcomp compare``).
"""
