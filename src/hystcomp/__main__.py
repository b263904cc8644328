"""``python -m hystcomp``: the ``hystcomp`` command."""

from hystcomp.cli import run

run()
