"""The package's layout keeps its architecture: a few top-level modules, one
subpackage per layer, no private name crossing modules, one import cycle at most
(the tree's operators calling the set operations)."""

from __future__ import annotations

import ast
import pathlib

PACKAGE = pathlib.Path(__file__).parents[1] / "src" / "moveability"
LAYERS = {"compiled", "hypertree", "mechanisms", "analysis", "output", "sweep", "cli"}
ACCEPTED_CYCLES = [{"moveability.hypertree.tree", "moveability.hypertree.setops"}]


def modules() -> dict[str, tuple[pathlib.Path, list[str]]]:
    """Module name -> (file, the package its relative imports start from)."""
    found = {}
    for path in PACKAGE.rglob("*.py"):
        parts = ["moveability", *path.relative_to(PACKAGE).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts = parts[:-1]
            package = parts
        else:
            package = parts[:-1]
        found[".".join(parts)] = (path, package)
    return found


def imports() -> dict[str, set[tuple[str, str]]]:
    """Module -> the (module, name) pairs it imports from the package, anywhere in it
    (in functions and under TYPE_CHECKING too)."""
    known = modules()
    out: dict[str, set[tuple[str, str]]] = {name: set() for name in known}
    for name, (path, package) in known.items():
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.ImportFrom):
                continue
            if node.level:
                base = package[: len(package) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("moveability"):
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                out[name].add((sub, "") if sub in known else (target, alias.name))
    return out


def test_few_top_level_modules_and_a_subpackage_per_layer():
    top = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert len(top) <= 8, top
    assert {p.name for p in PACKAGE.iterdir() if (p / "__init__.py").exists()} == LAYERS


def test_no_private_name_is_imported_from_another_module():
    crossing = [
        (module, target, name)
        for module, pairs in imports().items()
        for target, name in pairs
        if name.startswith("_") and not name.startswith("__")
    ]
    assert crossing == []


def strongly_connected(graph: dict[str, set[str]]) -> list[set[str]]:
    """Tarjan's components of a directed graph (iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[set[str]] = []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is None:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = set()
                    while True:
                        top = stack.pop()
                        on_stack.discard(top)
                        component.add(top)
                        if top == node:
                            break
                    found.append(component)
            elif child not in index:
                index[child] = low[child] = len(index)
                stack.append(child)
                on_stack.add(child)
                work.append((child, iter(sorted(graph.get(child, ())))))
            elif child in on_stack:
                low[node] = min(low[node], index[child])
    return found


def test_at_most_the_accepted_import_cycle():
    graph = {
        module: {target for target, _ in pairs if target != module}
        for module, pairs in imports().items()
    }

    def is_package_of(a: str, b: str) -> bool:
        return b.startswith(a + ".")

    # a package importing its own modules (re-exports) is not a cycle of layers
    for module in graph:
        graph[module] = {t for t in graph[module] if not is_package_of(t, module)}
    cycles = [c for c in strongly_connected(graph) if len(c) > 1]
    assert all(c in ACCEPTED_CYCLES for c in cycles), cycles


def test_the_cycle_finder_finds_cycles():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": set()}
    assert sorted(map(sorted, strongly_connected(graph))) == [["a", "b", "c"], ["d"], ["e"]]
