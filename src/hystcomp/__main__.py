"""``python -m hystcomp``: the ``hystcomp`` command."""

from hystcomp._program import run

run()
