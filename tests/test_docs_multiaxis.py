"""docs/multiaxis.md runs as written: its Python blocks, in order."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def test_the_multiaxis_page_python_blocks_run():
    text = (ROOT / "docs" / "multiaxis.md").read_text(encoding="utf-8")
    blocks = re.findall(r"^```python\n(.*?)^```", text, flags=re.MULTILINE | re.DOTALL)
    assert len(blocks) == 2
    axes: dict = {}
    exec(compile(blocks[0], "docs/multiaxis.md", "exec"), axes)  # noqa: S102 - our own docs
    assert np.abs(axes["model"].coupling_ - axes["scanner"].coupling).max() < 0.005
    assert axes["v"].shape == (100, 2)
    mirror: dict = {}
    exec(compile(blocks[1], "docs/multiaxis.md", "exec"), mirror)  # noqa: S102
    assert mirror["v"].shape == (10, 64)
    assert np.array_equal(mirror["v_k"], mirror["v"][0])
