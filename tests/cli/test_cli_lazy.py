"""The command line loads its heavy modules only when a command needs them."""

from __future__ import annotations

import importlib
import os
import pkgutil
import subprocess
import sys
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

import hystcomp
import hystcomp.cli
from hystcomp.cli import COMMANDS, main

HEAVY = ("numba", "scipy.sparse", "scipy.io", "matplotlib", "hystcomp.models", "quadprog")

PROBE = """
import sys
from hystcomp.cli import main
try:
    main(sys.argv[1:], prog_name="hystcomp")
except SystemExit:
    pass
heavy = sorted(m for m in sys.modules if m.split(".")[0] in {"numba", "matplotlib", "quadprog"}
               or m.startswith(("scipy.sparse", "scipy.io", "hystcomp.models")))
sys.stderr.write("HEAVY:" + ",".join(heavy) + "\\n")
"""


def _loaded(*args: str) -> tuple[str, list[str]]:
    env = dict(os.environ)
    src = str(Path(hystcomp.__file__).parents[1])  # the hystcomp under test
    env["PYTHONPATH"] = os.pathsep.join([src, env.get("PYTHONPATH", "")])
    done = subprocess.run(
        [sys.executable, "-c", PROBE, *args], env=env, capture_output=True, text=True, check=False
    )
    line = [ln for ln in done.stderr.splitlines() if ln.startswith("HEAVY:")]
    assert line, done.stderr
    heavy = line[0].removeprefix("HEAVY:")
    return done.stdout, [m for m in heavy.split(",") if m]


@pytest.mark.parametrize(
    "args",
    [("--help",), ("--version",), ("excite", "--help"), ("excite", "pi"), ("nosuch",)],
)
def test_commands_that_need_no_kernel_load_no_heavy_module(args):
    out, heavy = _loaded(*args)
    assert heavy == [], f"hystcomp {' '.join(args)} imported {heavy[:5]}"
    if args == ("--help",):
        for name in COMMANDS:
            assert name in out


def test_import_hystcomp_loads_no_heavy_module_until_asked():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(Path(hystcomp.__file__).parents[1]), env.get("PYTHONPATH", "")]
    )
    code = (
        "import sys, hystcomp; a = 'numba' in sys.modules; hystcomp.PrandtlIshlinskii; "
        "print(a, 'numba' in sys.modules, 'hystcomp.models.pi' in sys.modules)"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    assert done.stdout.split() == ["False", "True", "True"]


def test_every_public_name_resolves():
    assert set(hystcomp.__all__) == {"__version__", *hystcomp._LAZY}
    for name, (module, attribute) in hystcomp._LAZY.items():  # the object it names
        owner = importlib.import_module(module)
        assert getattr(hystcomp, name) is (
            owner if attribute is None else getattr(owner, attribute)
        )
    assert set(hystcomp.__all__) <= set(dir(hystcomp))
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        hystcomp.nothing  # noqa: B018


def test_the_lazy_table_matches_the_commands_it_loads():
    modules = {
        info.name
        for info in pkgutil.iter_modules(hystcomp.cli.__path__)
        if not info.name.startswith("_")
    }
    assert {module.rsplit(".", 1)[1] for module, _ in COMMANDS.values()} == modules
    for name, (module, first_line) in COMMANDS.items():
        importlib.import_module(module)
        command = main.commands[name]
        for limit in (30, 45, 80, 200):
            stand_in = click.Command(name, help=first_line)
            assert stand_in.get_short_help_str(limit) == command.get_short_help_str(limit), name


def test_help_lists_every_command_once_loaded_or_not():
    result = CliRunner().invoke(main, ["--help"])
    assert result.exit_code == 0
    listed = [ln.split()[0] for ln in result.output.split("Commands:")[1].splitlines() if ln]
    assert listed == sorted(COMMANDS)


def test_shell_completion_offers_the_commands(monkeypatch):
    monkeypatch.setenv("_HYSTCOMP_COMPLETE", "bash_complete")
    monkeypatch.setenv("COMP_WORDS", "hystcomp ex")
    monkeypatch.setenv("COMP_CWORD", "1")
    result = CliRunner().invoke(main, [], prog_name="hystcomp", complete_var="_HYSTCOMP_COMPLETE")
    assert "excite" in result.output
    assert "export-c" in result.output
    assert "identify" not in result.output


def test_an_unknown_command_is_bad_usage():
    result = CliRunner().invoke(main, ["nosuch"])
    assert result.exit_code == 2
    assert "hystcomp: error:" in result.output
