"""``python -m hystcomp.cli``: the ``hystcomp`` command."""

from hystcomp.cli import run

run()
