"""The house's layering: imports point down only (no import circle, deferred imports counted), and the
library knows nothing of its front ends (DESIGN.md, Layout)."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _module_name(path):
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    if parts[0] == "app":
        parts[0] = "activecontour_app"
    return ".".join(parts)


def _modules():
    return {_module_name(path): path
            for top in ("activecontour", "app") for path in (ROOT / top).rglob("*.py")}


def _imported(path, module, known):
    """Every project module that ``module`` imports, wherever the import stands (a function's too)."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(parts + ([base] if base else []))
            base = base.replace("app.", "activecontour_app.", 1) if base.split(".")[0] == "app" else base
            names = [base] + [f"{base}.{alias.name}" for alias in node.names]
        else:
            continue
        for name in names:
            while name and name not in known:
                name = name.rpartition(".")[0]
            if name and name != module and not module.startswith(name + "."):
                found.add(name)
    return found


def _graph():
    modules = _modules()
    return {module: _imported(path, module, modules) for module, path in modules.items()}


def _circles(graph):
    """The strongly connected components of more than one module (Tarjan's algorithm)."""
    index, low, stack, on_stack, circles = {}, {}, [], set(), []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in graph[node]:
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = set()
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.add(member)
                if member == node:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return circles


def test_the_circle_finder_finds_a_circle():
    assert _circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _circles({"a": {"b"}, "b": set()}) == []


def test_no_import_circle_counting_deferred_imports():
    assert _circles(_graph()) == []


def test_the_library_imports_no_front_end():
    graph = _graph()
    reaching_up = {module: sorted(t for t in targets if t.startswith("activecontour_app"))
                   for module, targets in graph.items() if module.startswith("activecontour.")}
    assert {module: up for module, up in reaching_up.items() if up} == {}


def test_the_library_imports_no_gui_at_module_level():
    for module, path in _modules().items():
        if module.split(".")[0] != "activecontour":
            continue
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                names = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
                assert not any(name.split(".")[0] in {"matplotlib", "tkinter", "PyQt5", "PySide6"}
                               for name in names), module
