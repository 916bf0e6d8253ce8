"""The package's layout: imports flow downward (no cycle between modules or between subpackages) and no
underscore name or private module path is imported across subpackages.

Function-level (lazy) imports count: a cycle hidden in a function body is still a cycle in the design.
A package's implicit import of its parents does not count (every module imports ``jaxplan`` that way).
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _modules() -> dict[str, Path]:
    mods = {}
    for p in (ROOT / "jaxplan").rglob("*.py"):
        name = ".".join(p.relative_to(ROOT).with_suffix("").parts)
        mods[name.removesuffix(".__init__")] = p
    return mods


MODULES = _modules()


def _unit(module: str) -> str:
    """The subpackage (or top-level module) a module belongs to: ``jaxplan.grid._gridmap`` -> ``grid``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "<jaxplan>"


def _owner(target: str) -> str:
    """The module that defines ``target`` (a module, or a name inside one)."""
    while target and target not in MODULES:
        target = target.rsplit(".", 1)[0] if "." in target else ""
    return target


def _imports() -> tuple[dict[str, set[str]], list[str]]:
    """Module -> the jaxplan modules it imports; and every cross-subpackage import of a private name or path."""
    edges: dict[str, set[str]] = defaultdict(set)
    private = []
    for name, path in MODULES.items():
        package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - node.level + 1]
                    module = ".".join(base + ([node.module] if node.module else []))
                else:
                    module = node.module or ""
                if not module.startswith("jaxplan"):
                    continue
                for alias in node.names:
                    full = f"{module}.{alias.name}"
                    edges[name].add(_owner(full if full in MODULES else module))
                    across = _unit(module) != _unit(name)
                    hidden = any(part.startswith("_") for part in module.split(".")[1:]) or alias.name.startswith("_")
                    if across and hidden:
                        private.append(f"{name}: from {module} import {alias.name}")
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name.startswith("jaxplan"):
                        edges[name].add(_owner(alias.name))
                        if _unit(alias.name) != _unit(name) and any(
                                part.startswith("_") for part in alias.name.split(".")[1:]):
                            private.append(f"{name}: import {alias.name}")
    for name in edges:
        edges[name].discard(name)
        edges[name].discard("")
    return edges, private


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected groups of more than one node (Tarjan, iterative)."""
    nodes = sorted(set(graph) | {w for ws in graph.values() for w in ws})
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found = []
    for root in nodes:
        if root in index:
            continue
        work = [(root, iter(sorted(graph.get(root, ()))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    group = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        group.append(w)
                        if w == v:
                            break
                    if len(group) > 1:
                        found.append(sorted(group))
    return found


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycle_between_modules():
    edges, _ = _imports()
    assert _cycles(edges) == []


def test_no_import_cycle_between_subpackages():
    edges, _ = _imports()
    units: dict[str, set[str]] = defaultdict(set)
    for a, targets in edges.items():
        units[_unit(a)] |= {_unit(b) for b in targets if _unit(b) != _unit(a)}
    assert _cycles(units) == []


def test_no_private_name_imported_across_subpackages():
    _, private = _imports()
    assert private == []
