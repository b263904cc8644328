"""A MkDocs hook that renders the notebooks of ``docs/notebooks`` (py-percent files) as pages.

A page holds a marker ``<!-- notebook: notebooks/NAME.py -->``; the hook replaces it with the
notebook's cells, run in order in a scratch folder: Markdown cells as they are, code cells
as Python blocks followed by what they printed and the figures they showed (PNG, inline).
The tests run the same function (``tests/test_notebooks.py``), so the notebook the docs show
is the one that runs.

It needs nothing beyond the docs extra: a py-percent notebook is a Python file whose
``# %%`` lines start the cells (``# %% [markdown]`` a Markdown cell, its lines commented),
as jupytext, VS Code and Spyder read it.
"""

from __future__ import annotations

import base64
import contextlib
import io
import os
import re
import tempfile
from pathlib import Path

MARKER = re.compile(r"<!--\s*notebook:\s*(\S+)\s*-->")


def cells(text: str) -> list[tuple[str, str]]:
    """The cells of a py-percent notebook: ``("markdown" | "code", source)`` in order (the
    header above the first ``# %%`` left out)."""
    out: list[tuple[str, list[str]]] = []
    for line in text.splitlines():
        if line.startswith("# %%"):
            out.append(("markdown" if "[markdown]" in line else "code", []))
        elif out:
            out[-1][1].append(line)
    result = []
    for kind, lines in out:
        if kind == "markdown":
            lines = [line[2:] if line.startswith("# ") else line.lstrip("#") for line in lines]
        source = "\n".join(lines).strip("\n")
        if source:
            result.append((kind, source))
    return result


def run(path: Path, folder: Path | None = None) -> list[tuple[str, str, str, list[bytes]]]:
    """Run the notebook at ``path`` cell by cell in ``folder`` (a scratch folder if None):
    ``(kind, source, printed, figures as PNG bytes)`` per cell."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    shown: list[bytes] = []

    def show(*args, **kwargs):  # plt.show in a notebook: keep each open figure
        for number in plt.get_fignums():
            buffer = io.BytesIO()
            plt.figure(number).savefig(buffer, format="png", dpi=90)
            shown.append(buffer.getvalue())
        plt.close("all")

    namespace: dict = {"__name__": "__main__"}
    results = []
    with contextlib.ExitStack() as stack:
        if folder is None:
            folder = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="notebook-")))
        here = Path.cwd()
        os.chdir(folder)
        stack.callback(os.chdir, here)
        original = plt.show
        plt.show = show
        stack.callback(setattr, plt, "show", original)
        for kind, source in cells(path.read_text(encoding="utf-8")):
            printed = io.StringIO()
            if kind == "code":
                with contextlib.redirect_stdout(printed):
                    exec(compile(source, str(path), "exec"), namespace)  # noqa: S102 - our notebook
            results.append((kind, source, printed.getvalue(), list(shown)))
            shown.clear()
        plt.close("all")
    return results


def render(path: Path) -> str:
    """The notebook at ``path`` as Markdown, with its outputs."""
    parts = []
    for kind, source, printed, figures in run(path):
        if kind == "markdown":
            parts.append(source)
            continue
        parts.append(f"```python\n{source}\n```")
        if printed.strip():
            parts.append(f"```text\n{printed.rstrip()}\n```")
        for png in figures:
            data = base64.b64encode(png).decode("ascii")
            parts.append(f"![a figure of the notebook](data:image/png;base64,{data})")
    return "\n\n".join(parts) + "\n"


def on_page_markdown(markdown: str, page, config, files) -> str:
    """MkDocs' hook: each marker becomes its notebook, run."""
    docs = Path(config["docs_dir"])
    return MARKER.sub(lambda match: render(docs / match[1]), markdown)
