"""The application layer: what a command does, as a library function with a structured
result that the command line words.

* :mod:`hystcomp.workflows.evaluate`: a run's tracking, from a reference and a measured run
  (``hystcomp evaluate``; :func:`hystcomp.evaluate`).
"""
