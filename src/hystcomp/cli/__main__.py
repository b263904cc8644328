"""``python -m hystcomp.cli``: the ``hystcomp`` command."""

from hystcomp.cli import main

main(prog_name="hystcomp")
