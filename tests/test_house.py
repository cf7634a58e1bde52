"""The house rules of the code (issue 15): layers import only downwards, no import circles, modules stay small.

The import graph is read from the source with :mod:`ast` (module-level and function-level imports; imports under
``if TYPE_CHECKING:`` are type-only and left out), so these tests see every import a module can make, including
the lazy ones that keep ``netsim --help`` fast.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: netsim's layers, lowest first: a module may import its own layer and the layers below, never one above.
LAYERS: list[tuple[str, tuple[str, ...]]] = [
    ("foundation", ("netsim", "netsim.blas", "netsim.timebase", "netsim.errors", "netsim.units", "netsim.safe_write",
                    "netsim.status", "netsim.trust")),
    ("event loop and registry", ("netsim.env", "netsim.registry")),
    ("domain: kernels, networks, plants, I/O, algorithms, analysis",
     ("netsim.kernel", "netsim.network", "netsim.plant", "netsim.io", "netsim.control", "netsim.analysis",
      "netsim.energy")),
    ("programs and metrics", ("netsim.programs", "netsim.metrics")),
    ("scenarios and results", ("netsim.scenario", "netsim.results", "netsim.plotting", "netsim.divergence",
                               "netsim.run_warnings")),
    ("runs, reports, sweeps", ("netsim.runner", "netsim.report", "netsim.sweep", "netsim.casestudy")),
    ("case studies", ("netsim.models",)),
    ("command line", ("netsim.cli", "netsim.__main__")),
]

#: Longest module without a stated reason (DESIGN.md: "modules mostly under 500 lines").
MAX_LINES = 500


def _module_files() -> dict[str, Path]:
    files = {}
    for path in sorted([*(ROOT / "netsim").rglob("*.py"), *(ROOT / "models").rglob("*.py")]):
        parts = path.relative_to(ROOT).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        if parts[0] == "models":  # the checkout's models/ folder installs as netsim.models
            name = "netsim." + name
        files[name] = path
    return files


FILES = _module_files()


def _imports(path: Path) -> list[tuple[str, int]]:
    """``(module, line)`` for every netsim/models module that ``path`` imports (type-only imports left out)."""
    found: list[tuple[str, int]] = []

    class Visitor(ast.NodeVisitor):
        def visit_If(self, node: ast.If) -> None:
            if "TYPE_CHECKING" in ast.unparse(node.test):
                for child in node.orelse:
                    self.visit(child)
                return
            self.generic_visit(node)

        def visit_Import(self, node: ast.Import) -> None:
            found.extend((alias.name, node.lineno) for alias in node.names)

        def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
            if node.module is None or node.level:
                return
            found.append((node.module, node.lineno))
            found.extend((f"{node.module}.{alias.name}", node.lineno) for alias in node.names)

    Visitor().visit(ast.parse(path.read_text(encoding="utf-8")))
    return [(name, line) for name, line in found if name in FILES]


GRAPH = {name: _imports(path) for name, path in FILES.items()}


def _layer(module: str) -> int:
    best, rank = -1, -1
    for index, (_, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best:
                best, rank = len(prefix), index
    return rank


def test_every_module_has_a_layer() -> None:
    assert [m for m in FILES if _layer(m) < 0] == []


def test_no_module_imports_from_a_layer_above_it() -> None:
    upward = []
    for module, imports in GRAPH.items():
        for target, line in imports:
            if _layer(target) > _layer(module):
                upward.append(f"{FILES[module].relative_to(ROOT)}:{line}: {module} ({LAYERS[_layer(module)][0]}) "
                              f"imports {target} ({LAYERS[_layer(target)][0]})")
    assert upward == []


def _circles() -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan), over every non-type-only import."""
    graph = {m: sorted({t for t, _ in edges if t != m}) for m, edges in GRAPH.items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    circles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 10_000))
    try:
        for v in graph:
            if v not in index:
                visit(v)
    finally:
        sys.setrecursionlimit(limit)
    return circles


def test_no_import_circles() -> None:
    assert _circles() == []


def test_the_circle_finder_finds_a_planted_circle(monkeypatch: pytest.MonkeyPatch) -> None:
    # the check above must be able to fail: plant a -> b -> a and see it reported
    monkeypatch.setitem(GRAPH, "netsim.timebase", [*GRAPH["netsim.timebase"], ("netsim.units", 1)])
    assert any({"netsim.timebase", "netsim.units"} <= set(c) for c in _circles())


def test_netsim_never_imports_a_case_study() -> None:
    # models register themselves by name (registry); the engine knows no case study (DESIGN.md section 1)
    offenders = [f"{m} imports {t}" for m, edges in GRAPH.items()
                 if m.startswith("netsim") and not m.startswith("netsim.models")
                 for t, _ in edges if t == "netsim.models" or t.startswith("netsim.models.")]
    assert offenders == []


@pytest.mark.parametrize("module", sorted(FILES))
def test_a_module_over_500_lines_says_why_in_its_docstring(module: str) -> None:
    path = FILES[module]
    text = path.read_text(encoding="utf-8")
    lines = text.count("\n") + 1
    if lines <= MAX_LINES:
        return
    doc = ast.get_docstring(ast.parse(text)) or ""
    assert "Why this module is long:" in doc, (
        f"{path.relative_to(ROOT)} has {lines} lines: split it along its seams, or say in its docstring "
        f"'Why this module is long: ...'"
    )
