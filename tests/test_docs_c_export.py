"""docs/c-export.md runs as written: its shell and Python examples in order in an empty
folder, then every C example compiled with the system cc against the files they made."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.codegen.test_codegen import CC, STRICT, needs_cc

DOC = Path(__file__).parent.parent / "docs" / "c-export.md"
BLOCK = re.compile(r"^```(\w*)\n(.*?)^```$", re.DOTALL | re.MULTILINE)


def blocks(kind: str) -> list[str]:
    return [body for lang, body in BLOCK.findall(DOC.read_text()) if lang == kind]


def test_every_example_block_is_tagged_with_its_language():
    languages = [lang for lang, _ in BLOCK.findall(DOC.read_text())]
    assert languages
    assert set(languages) <= {"sh", "python", "c"}


@needs_cc
@pytest.mark.slow
def test_the_examples_run_as_written_in_an_empty_folder(tmp_path):
    bin_dir = str(Path(sys.executable).parent)  # hystcomp and python of this environment
    env = {**os.environ, "PATH": bin_dir + os.pathsep + os.environ.get("PATH", "")}
    steps = [("sh", body) for body in blocks("sh")[:-1]]  # the last one builds, below
    steps.insert(2, ("python", blocks("python")[0]))  # in the page's order
    for lang, body in steps:
        cmd = ["bash", "-euo", "pipefail", "-c", body] if lang == "sh" else [sys.executable]
        done = subprocess.run(
            cmd,
            input=None if lang == "sh" else body,
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            check=False,
        )
        assert done.returncode == 0, f"{body}\n{done.stdout}\n{done.stderr}"
    hyst = tmp_path / "firmware" / "hyst"
    assert sorted(p.name for p in hyst.iterdir()) == ["stage_x.c", "stage_x.h"]
    build = blocks("sh")[-1]
    done = subprocess.run(
        ["bash", "-euo", "pipefail", "-c", build],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert (hyst / "stage_x.o").is_file()
    for i, body in enumerate(blocks("c")):
        source = tmp_path / f"example_{i}.c"
        source.write_text(body)
        cmd = [CC, *STRICT, "-I", str(hyst), "-c", source.name]
        done = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, check=False)
        assert done.returncode == 0, f"{body}\n{done.stderr}"
