"""The case-study reports run, cache and format through netsim.casestudy (issue 28): no report keeps a process
pool, a hashing cache or a number formatter of its own."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MODELS = sorted((ROOT / "models").rglob("*.py"))


def _imports(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
    return names


def _offenders(module: str) -> list[str]:
    return [str(p.relative_to(ROOT)) for p in MODELS if module in _imports(p)]


def test_no_case_study_keeps_a_process_pool_of_its_own():
    # netsim.casestudy.run_all (or netsim.sweep) runs the points; before, cart, pendulum and unicycle each had one
    assert _offenders("concurrent.futures") == []


def test_no_case_study_hashes_its_code_itself():
    # casestudy.code_fingerprint names a cache; before, cart/cache.py and unicycle/report.py each hashed with sha256
    assert _offenders("hashlib") == []


def test_the_reports_format_numbers_with_the_one_fmt():
    defined = []
    for path in MODELS:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef) and node.name in ("fmt", "_fmt", "_f"):
                body = [n for n in node.body if not (isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant))]
                calls = {c.func.id for c in ast.walk(node) if isinstance(c, ast.Call) and isinstance(c.func, ast.Name)}
                if len(body) != 1 or not calls & {"fmt", "_fmt"}:  # a one-line wrapper of casestudy.fmt is fine
                    defined.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name}")
    assert defined == []
