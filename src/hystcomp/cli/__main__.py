"""``python -m hystcomp.cli``: the ``hystcomp`` command."""

from hystcomp._program import run

run()
