"""The house rules of the code (issue 15): layers import only downwards, no import circles, modules stay small,
and README's "How the code is organised" names every room and case study and nothing that is gone (issue 28).

The import graph is read from the source with :mod:`ast` (module-level and function-level imports; imports under
``if TYPE_CHECKING:`` are type-only and left out), so these tests see every import a module can make, including
the lazy ones that keep ``netsim --help`` fast. The layers are the table in README.md's "How the code is
organised"; :data:`LAYERS` is the same table as prefixes.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import re
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
    ("scenarios, build and results", ("netsim.scenario", "netsim.build", "netsim.results", "netsim.plotting",
                                      "netsim.divergence", "netsim.run_warnings", "netsim.shipped")),
    ("runs, reports, sweeps", ("netsim.runner", "netsim.report", "netsim.sweep", "netsim.casestudy")),
    ("case studies", ("netsim.models",)),
    ("command line", ("netsim.cli", "netsim.__main__")),
]

#: Longest module without a stated reason ("modules mostly under 500 lines", the project's style rule).
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
    # models register themselves by name (registry); the engine knows no case study (README: "How the code is
    # organised")
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


# --------------------------------------------------------------------------------- README cannot go stale
README = (ROOT / "README.md").read_text(encoding="utf-8")

#: Dotted ``netsim.`` names in README that are not Python objects: the entry-point group plugins register under.
NOT_MODULES = {"netsim.plugins"}


def _section(text: str, heading: str) -> str:
    """The text under ``## heading`` up to the next ``## `` heading."""
    match = re.search(rf"^## {re.escape(heading)}\n(.*?)(?=^## |\Z)", text, re.MULTILINE | re.DOTALL)
    assert match, f"README.md has no '## {heading}' section"
    return match.group(1)


ORGANISATION = _section(README, "How the code is organised")


def _code_spans(text: str) -> list[str]:
    return re.findall(r"`([^`\n]+)`", text)


def _repo_paths(text: str) -> set[str]:
    """``netsim/...`` and ``models/...`` paths (not ones inside another path, like ``~/.config/netsim/x``)."""
    return set(re.findall(r"(?<![\w/.~$-])((?:netsim|models)/[\w*./-]*)", text))


def _room_paths(text: str) -> set[str]:
    """Code spans that are paths of a room, relative to netsim/ or a room (``plant/noise.py``, ``registry/``)."""
    return {span for span in _code_spans(text) if re.fullmatch(r"[\w*]+(/[\w*]+)*(\.py|/)", span)}


def _exists(path: str) -> bool:
    """A README path names something in the checkout: from its root, from netsim/, or (a bare file name) in a room."""
    path = path.rstrip(".")
    bases = [ROOT, ROOT / "netsim", ROOT / "models"]
    if "/" not in path.rstrip("/"):
        bases += [p for p in (ROOT / "netsim").iterdir() if p.is_dir()]
    return any(any(base.glob(path.rstrip("/"))) for base in bases)


def _dotted_exists(name: str) -> bool:
    """``netsim.a.b``: the longest prefix that is a module exists, and the rest is an attribute of it."""
    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        module = ".".join(parts[:cut])
        try:
            found = importlib.util.find_spec(module) is not None
        except ModuleNotFoundError:
            found = False
        if found:
            obj = importlib.import_module(module)
            for attr in parts[cut:]:
                if not hasattr(obj, attr):
                    return False
                obj = getattr(obj, attr)
            return True
    return False


def _case_studies() -> set[str]:
    """The case studies in models/: its packages and its modules, less a study's helpers (``hdd_report.py``)."""
    models = ROOT / "models"
    packages = {p.name for p in models.iterdir() if (p / "__init__.py").is_file()}
    modules = {p.stem for p in models.glob("*.py") if p.stem != "__init__"}
    studies = packages | modules
    return {s for s in studies if not any(s.startswith(other + "_") for other in studies - {s})}


def _rooms() -> set[str]:
    """netsim's rooms: each subpackage (``kernel/``) and each top-level module (``runner.py``)."""
    netsim_dir = ROOT / "netsim"
    packages = {f"{p.name}/" for p in netsim_dir.iterdir() if (p / "__init__.py").is_file()}
    modules = {p.name for p in netsim_dir.glob("*.py") if p.name != "__init__.py"}
    return packages | modules


def test_every_netsim_and_models_path_readme_names_exists() -> None:
    named = _repo_paths(README) | _room_paths(ORGANISATION)
    assert named, "the README names no path: the pattern is broken"
    assert sorted(p for p in named if not _exists(p)) == []


def test_every_dotted_netsim_name_readme_gives_is_a_module_or_an_attribute_of_one() -> None:
    names = {m for span in _code_spans(README) for m in re.findall(r"\bnetsim(?:\.[A-Za-z_]\w*)+", span)}
    names = {n for n in names if not re.search(r"\.(json|yaml|toml|md)$", n)} - NOT_MODULES
    assert "netsim.analysis.lqg" in names  # the extraction works
    assert sorted(n for n in names if not _dotted_exists(n)) == []


def test_readme_room_list_names_every_netsim_subpackage_and_module() -> None:
    listed = {p.removeprefix("netsim/") for p in _room_paths(ORGANISATION) | _repo_paths(ORGANISATION)}
    assert sorted(_rooms() - listed) == []


def test_readme_room_list_names_every_case_study_in_models() -> None:
    studies = _case_studies()
    assert {"hdd", "dc_servo", "cart", "pendulum", "unicycle"} <= studies  # the five of this checkout
    named = _repo_paths(ORGANISATION)
    assert sorted(s for s in studies if f"models/{s}.py" not in named and f"models/{s}/" not in named) == []


def test_the_readme_checks_can_fail() -> None:
    # a made-up room, path and module are reported
    assert not _exists("netsim/no_such_room/") and not _exists("plant/no_such_module.py")
    assert not _dotted_exists("netsim.analysis.no_such_module")
    assert _exists("plant/noise.py") and _exists("analyze*.py") and _exists("models/cart/")
