"""``python -m hystcomp``: the ``hystcomp`` command."""

from hystcomp.cli import main

main(prog_name="hystcomp")
