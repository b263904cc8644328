"""The import graph of hystcomp: no cycle, and no module importing from a layer above its own.

Imports inside functions count (an import deferred to run time is still a dependency); those
under ``if TYPE_CHECKING:`` do not. The package's ``__init__`` re-exports lazily and is left out.
"""

from __future__ import annotations

import ast
from pathlib import Path

import hystcomp

SRC = Path(hystcomp.__file__).parent

#: Layers from the bottom up (docs/architecture.md, "The layers"); a module's layer is that of
#: the longest prefix listed. A module may import from its own layer and the layers below it.
LAYERS = {
    "hystcomp.errors": 0,
    "hystcomp.paper": 0,
    "hystcomp._signals": 0,  # the standard library only: the program imports it first
    "hystcomp._validation": 1,
    "hystcomp._blas": 1,
    "hystcomp._hyperparameters": 1,
    "hystcomp._notice": 1,
    "hystcomp._progress": 1,
    "hystcomp._lti": 1,
    "hystcomp._kernels": 1,
    "hystcomp.io.atomic": 1,
    "hystcomp.identify": 2,  # the array-level fits the models delegate to
    "hystcomp.models": 3,
    "hystcomp.io": 4,  # model files name every model class
    "hystcomp.plant": 4,
    "hystcomp.presets": 4,
    "hystcomp.control": 4,
    "hystcomp.codegen": 4,
    "hystcomp.experiment": 5,
    "hystcomp.workflows": 5,  # the application layer, beside experiment
    "hystcomp.cli": 6,
    "hystcomp.__main__": 6,
    "hystcomp._program": 6,
}


def _module_name(path: Path) -> str:
    parts = path.relative_to(SRC.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, modules: set[str]) -> set[str]:
    """The hystcomp modules that the module at ``path`` imports, deferred imports included."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()

    def visit(node: ast.AST) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and "TYPE_CHECKING" in ast.unparse(child.test):
                for orelse in child.orelse:
                    visit(orelse)
                continue
            if isinstance(child, ast.Import):
                found.update(alias.name for alias in child.names)
            elif isinstance(child, ast.ImportFrom):
                base = child.module or ""
                if child.level:
                    parent = package.split(".")[: len(package.split(".")) - child.level + 1]
                    base = ".".join([*parent, *([base] if base else [])])
                found.add(base)
                found.update(f"{base}.{alias.name}" for alias in child.names)
            visit(child)

    visit(ast.parse(path.read_text(encoding="utf-8")))
    return {m for m in found if m in modules and m not in (name, "hystcomp")}


def _graph() -> dict[str, set[str]]:
    paths = sorted(SRC.rglob("*.py"))
    modules = {_module_name(p) for p in paths}
    return {_module_name(p): _imports(p, modules) for p in paths if p != SRC / "__init__.py"}


def _layer(module: str) -> int:
    prefixes = [p for p in LAYERS if module == p or module.startswith(p + ".")]
    assert prefixes, f"{module} has no layer in LAYERS: add it"
    return LAYERS[max(prefixes, key=len)]


def test_every_module_imports_only_its_layer_and_those_below():
    upward = [
        f"{module} (layer {_layer(module)}) imports {target} (layer {_layer(target)})"
        for module, targets in _graph().items()
        for target in sorted(targets)
        if _layer(target) > _layer(module)
    ]
    assert upward == []


def test_the_import_graph_has_no_cycle():
    graph = _graph()
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    cycles: list[str] = []

    def walk(module: str, path: list[str]) -> None:
        state[module] = 1
        for target in sorted(graph.get(module, ())):
            if state.get(target) == 1:
                cycles.append(" -> ".join([*path[path.index(target) :], target]))
            elif target not in state:
                walk(target, [*path, target])
        state[module] = 2

    for module in sorted(graph):
        if module not in state:
            walk(module, [module])
    assert cycles == []


def test_the_graph_sees_deferred_imports():
    # identify_record builds the models: the edge must be seen, or the checks above prove little
    assert "hystcomp.models.pi" in _graph()["hystcomp.workflows.identify"]


def test_the_fits_import_no_estimator():
    # identify/ sits below the models: the estimators delegate to it, never the reverse
    graph = _graph()
    upward = {
        f"{module} imports {target}"
        for module, targets in graph.items()
        if module.startswith("hystcomp.identify")
        for target in targets
        if target.startswith("hystcomp.models")
    }
    assert upward == set()
