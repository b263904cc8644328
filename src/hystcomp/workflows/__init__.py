"""The application layer: what a command does, as a library function with a structured
result that the command line words.

* :mod:`hystcomp.workflows.evaluate`: a run's tracking, from a reference and a measured run
  (``hystcomp evaluate``; :func:`hystcomp.evaluate`).
* :mod:`hystcomp.workflows.auto`: the model family whose compensator is predicted to track
  best (``hystcomp identify --model auto``).
* :mod:`hystcomp.workflows.pair`: a hysteresis model and the linear dynamics identified as
  one pair (``hystcomp identify --dynamics-record``), the dynamics alone (``--model
  dynamics``), and what ``compensate`` reads of the pair's estimates.
"""
