"""The public face is documented: every public name is in the API reference, and every public
callable says in numpydoc what it takes (``Parameters``) and what it gives (``Returns``).

The public face is ``hystcomp.__all__`` and, in every module whose dotted path has no part
that starts with an underscore, its ``__all__`` or else the classes and functions it defines
whose names do not start with one, with their public methods. The API reference leaves out
the command line (:mod:`hystcomp.cli`, whose face is the command, documented in
docs/cli.md); the docstring checks cover it too. Both leave out the deprecated alias module
:mod:`hystcomp.data`.

See docs/architecture.md ("Where to change what") for what a new public name needs.
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import pkgutil
import re
import textwrap
import typing
from pathlib import Path

import pytest

import hystcomp

ROOT = Path(__file__).resolve().parents[1]
API = ROOT / "docs" / "api.md"

#: Modules (and everything below them) left out of the API reference: the command line's
#: face is the command (docs/cli.md), and hystcomp.data is a deprecated alias.
NOT_IN_API = ("hystcomp.cli", "hystcomp.data")
#: Modules left out of the docstring checks: the deprecated alias.
NOT_CHECKED = ("hystcomp.data",)

#: A numpydoc section header: a title, then a line of dashes.
SECTION = re.compile(r"^([A-Z][A-Za-z ]+)\n-{3,}[ \t]*$", re.MULTILINE)


def _outside(name: str, prefixes: tuple[str, ...]) -> bool:
    return not any(name == p or name.startswith(p + ".") for p in prefixes)


def _raise(name: str) -> None:
    raise ImportError(f"{name} cannot be imported: the walk would miss its modules")


def public_modules(left_out: tuple[str, ...] = NOT_IN_API) -> list[str]:
    """The dotted names of the public modules but ``left_out``, the package itself first."""
    found = ["hystcomp"]
    for info in pkgutil.walk_packages(hystcomp.__path__, "hystcomp.", onerror=_raise):
        if any(part.startswith("_") for part in info.name.split(".")[1:]):
            continue
        if _outside(info.name, left_out):
            found.append(info.name)
    return sorted(found)


def _is_ours(obj: object) -> bool:
    return (inspect.isclass(obj) or inspect.isfunction(obj)) and getattr(
        obj, "__module__", ""
    ).startswith("hystcomp.")


def public_names(left_out: tuple[str, ...] = NOT_IN_API) -> dict[str, object]:
    """Every public class and function, by the dotted path of its definition."""
    names: dict[str, object] = {}
    for name in public_modules(left_out):
        module = importlib.import_module(name)
        listed = getattr(module, "__all__", None)
        for attribute in listed if listed is not None else list(vars(module)):
            if attribute.startswith("_"):
                continue
            obj = getattr(module, attribute)
            if not _is_ours(obj):
                continue
            if listed is None and obj.__module__ != name:
                continue  # imported here, documented where it is defined
            if _outside(obj.__module__, left_out):
                names[f"{obj.__module__}.{obj.__qualname__}"] = obj
    return dict(sorted(names.items()))


def public_callables(left_out: tuple[str, ...] = NOT_CHECKED) -> dict[str, object]:
    """The public names and the public methods their classes define themselves."""
    found: dict[str, object] = {}
    for path, obj in public_names(left_out).items():
        found[path] = obj
        if not inspect.isclass(obj):
            continue
        for attribute, member in vars(obj).items():
            if attribute.startswith("_"):
                continue
            if isinstance(member, staticmethod | classmethod):
                member = member.__func__
            if inspect.isfunction(member):
                found[f"{path}.{attribute}"] = member
    return found


def sections(obj: object) -> dict[str, str]:
    """The numpydoc sections of ``obj``'s docstring, by title, each with its body."""
    doc = inspect.getdoc(obj) or ""
    heads = list(SECTION.finditer(doc))
    ends = [head.start() for head in heads[1:]] + [len(doc)] * bool(heads)
    return {
        head.group(1).strip(): doc[head.end() : end] for head, end in zip(heads, ends, strict=True)
    }


def _own_init(cls: type) -> typing.Callable | None:
    """The ``__init__`` a class of ours defines (itself or a base of ours), else None."""
    for klass in cls.__mro__:
        if "__init__" in vars(klass) and klass.__module__.startswith("hystcomp."):
            return vars(klass)["__init__"]
    return None


def takes_parameters(obj: object) -> bool:
    """Whether a caller passes ``obj`` anything (a class: its constructor)."""
    if inspect.isclass(obj):
        if issubclass(obj, BaseException):
            return False  # the message, as every exception takes it
        init = _own_init(obj)
        if init is None:
            return False
        obj = init
    parameters = inspect.signature(obj).parameters  # type: ignore[arg-type]
    return any(name not in ("self", "cls") for name in parameters)


def returns_something(obj: object) -> bool:
    """Whether a function gives back a value: by its annotation, else by its source."""
    if inspect.isclass(obj):
        return False
    annotation = inspect.signature(obj).return_annotation  # type: ignore[arg-type]
    if annotation is not inspect.Signature.empty:
        return annotation not in (None, "None", "NoReturn", typing.NoReturn)
    tree = ast.parse(textwrap.dedent(inspect.getsource(obj)))  # type: ignore[arg-type]
    body = tree.body[0]
    return any(
        isinstance(node, ast.Yield | ast.YieldFrom)
        or (isinstance(node, ast.Return) and node.value is not None)
        for node in ast.walk(body)
    )


def missing_sections(obj: object) -> list[str]:
    """The numpydoc sections that ``obj``'s docstring lacks."""
    found = sections(obj)
    missing = []
    if takes_parameters(obj):
        # a result record (a dataclass) documents its fields as Attributes
        wanted = {"Parameters", "Attributes"} if dataclasses.is_dataclass(obj) else {"Parameters"}
        if not wanted & found.keys():
            missing.append("Parameters")
    if returns_something(obj) and not {"Returns", "Yields"} & found.keys():
        missing.append("Returns")
    return missing


def test_the_walk_sees_the_public_face():
    # the checks below prove little if the walk misses what users import
    names = public_names()
    for name in ("PrandtlIshlinskii", "LinearDynamics", "load_model", "evaluate"):
        obj = getattr(hystcomp, name)
        assert f"{obj.__module__}.{obj.__qualname__}" in names
    assert "hystcomp.models.dynamic_compensator.DynamicCompensator" in names
    assert "hystcomp.codegen.export_c" in names
    assert "hystcomp.identify.excitation.triangle_sequence" in names
    assert "hystcomp.models.pi.PrandtlIshlinskii.fit" in public_callables()
    assert not any(name.startswith("hystcomp.cli") for name in names)
    assert any(name.startswith("hystcomp.cli") for name in public_callables())


def api_directives() -> set[str]:
    """What docs/api.md renders: each ``::: path`` with all its members, or with those
    its ``members: [...]`` option lists (none for ``members: false``)."""
    text = API.read_text(encoding="utf-8")
    blocks = re.findall(r"^:::[ \t]*(\S+)[ \t]*\n((?:[ \t]+\S.*\n)*)", text, re.MULTILINE)
    rendered = set()
    for path, options in blocks:
        listed = re.search(r"^\s*members:\s*(.+)$", options, re.MULTILINE)
        if listed is None:
            rendered.add(path)
        elif listed.group(1).strip().startswith("["):
            names = listed.group(1).strip().strip("[]").split(",")
            rendered.update(f"{path}.{name.strip()}" for name in names)
    return rendered


def test_every_public_name_is_in_the_api_reference():
    directives = api_directives()
    assert "hystcomp.models.mpi" in directives
    assert "hystcomp.io" not in directives  # its docstring only: its names are its modules'
    assert "hystcomp.models.pi.PrandtlIshlinskii" in directives  # listed in members: [...]
    missing = [
        path
        for path, obj in public_names().items()
        if path not in directives and obj.__module__ not in directives  # type: ignore[attr-defined]
    ]
    assert missing == [], "add these to docs/api.md (their module or themselves)"


def test_every_public_name_has_a_docstring():
    # mkdocstrings leaves out what has none (show_if_no_docstring: false)
    assert [path for path, obj in public_callables().items() if not inspect.getdoc(obj)] == []


@pytest.mark.parametrize("section", ["Parameters", "Returns"])
def test_every_public_callable_has_the_numpydoc_section(section):
    lacking = [path for path, obj in public_callables().items() if section in missing_sections(obj)]
    assert lacking == [], f"{len(lacking)} public callables lack a {section} section"


def test_documented_parameters_are_the_signatures():
    # a Parameters section names every argument a caller can pass, and nothing else
    # (mkdocs --strict checks the second half too, for the pages it renders)
    wrong = []
    for path, obj in public_callables().items():
        body = sections(obj).get("Parameters")
        if body is None:
            continue
        target = _own_init(obj) if inspect.isclass(obj) else obj
        if target is None:
            continue
        signature = inspect.signature(target)
        wanted = {
            name
            for name, p in signature.parameters.items()
            if name not in ("self", "cls") and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
        }
        documented = set()
        for line in body.splitlines():
            if line and not line[0].isspace():
                for name in line.split(":")[0].split(","):
                    documented.add(name.strip().lstrip("*"))
        if wanted - documented:
            wrong.append(f"{path}: undocumented {sorted(wanted - documented)}")
    assert wrong == []


#: A benchmark ratio such as "0.48x" or "12x": figures belong in docs/benchmarks.md.
RATIO = re.compile(r"\b\d+(\.\d+)?x\b")


def test_docstrings_hold_no_benchmark_ratios():
    # docstrings say what the code does; how well it does it is measured and kept in the docs
    found = [
        path for path, obj in public_callables().items() if RATIO.search(inspect.getdoc(obj) or "")
    ]
    found += [
        name
        for name in public_modules(NOT_CHECKED)
        if RATIO.search(importlib.import_module(name).__doc__ or "")
    ]
    assert found == [], "move the figures to docs/benchmarks.md"


def test_error_messages_hold_no_benchmark_ratios():
    # a message names the argument, what was found and the fix; no measured figure
    src = Path(hystcomp.__file__).parent
    found = []
    for path in sorted(src.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            is_warning = isinstance(node, ast.Call) and "warn" in ast.unparse(node.func)
            if not (isinstance(node, ast.Raise) or is_warning):
                continue
            text = " ".join(
                c.value
                for c in ast.walk(node)
                if isinstance(c, ast.Constant) and isinstance(c.value, str)
            )
            if RATIO.search(text):
                found.append(f"{path.relative_to(src)}:{node.lineno}")
    assert found == []
