"""Count how much of netsim/ and models/ is typed with ``Any`` (issue 28's measure; the type check is .ci/mypy).

Prints, over every ``.py`` file of the two folders:

* the annotations (parameters, returns, annotated assignments and fields) and the share of them that contain
  ``Any`` anywhere (``Any``, ``dict[str, Any]``, ``typing.Any``, or the word inside a string annotation);
* how many parameters or fields named ``scenario`` and ``job`` are annotated with a bare ``Any``.

Run from the checkout: ``python .ci/typing_counts.py`` (``--files`` lists the bare-``Any`` names per file).
"""
from __future__ import annotations

import ast
import re
import sys
from collections import Counter
from pathlib import Path

FOLDERS = ("netsim", "models")
NAMED = ("scenario", "job")
_ANY_WORD = re.compile(r"\bAny\b")


def mentions_any(node: ast.expr) -> bool:
    """Whether an annotation contains ``Any`` (a name, ``typing.Any``, or the word in a string annotation)."""
    for sub in ast.walk(node):
        if isinstance(sub, ast.Name) and sub.id == "Any":
            return True
        if isinstance(sub, ast.Attribute) and sub.attr == "Any":
            return True
        if isinstance(sub, ast.Constant) and isinstance(sub.value, str) and _ANY_WORD.search(sub.value):
            return True
    return False


def is_bare_any(node: ast.expr) -> bool:
    """Whether an annotation is exactly ``Any`` (``Any``, ``typing.Any`` or ``"Any"``)."""
    if isinstance(node, ast.Name):
        return node.id == "Any"
    if isinstance(node, ast.Attribute):
        return node.attr == "Any"
    return isinstance(node, ast.Constant) and node.value == "Any"


def annotations(tree: ast.AST) -> list[tuple[str, ast.expr]]:
    """Every ``(name, annotation)`` of a module: parameters, returns (named ``return``) and annotated targets."""
    found: list[tuple[str, ast.expr]] = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            a = node.args
            for arg in [*a.posonlyargs, *a.args, *a.kwonlyargs, *filter(None, [a.vararg, a.kwarg])]:
                if arg.annotation is not None:
                    found.append((arg.arg, arg.annotation))
            if node.returns is not None:
                found.append(("return", node.returns))
        elif isinstance(node, ast.AnnAssign):
            target = node.target
            name = target.id if isinstance(target, ast.Name) else getattr(target, "attr", "")
            found.append((name, node.annotation))
    return found


def count(root: Path) -> tuple[int, int, Counter[str], Counter[tuple[str, str]]]:
    """Totals over the folders of ``root``: annotations, those with ``Any``, bare-``Any`` names, per file too."""
    total = with_any = 0
    named: Counter[str] = Counter()
    per_file: Counter[tuple[str, str]] = Counter()
    for folder in FOLDERS:
        for path in sorted((root / folder).rglob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
            for name, ann in annotations(tree):
                total += 1
                with_any += mentions_any(ann)
                if name in NAMED and is_bare_any(ann):
                    named[name] += 1
                    per_file[(str(path.relative_to(root)), name)] += 1
    return total, with_any, named, per_file


def main(argv: list[str]) -> int:
    root = Path(__file__).resolve().parents[1]
    total, with_any, named, per_file = count(root)
    print(f"annotations: {total}, containing Any: {with_any} ({100 * with_any / max(total, 1):.1f} %)")
    for name in NAMED:
        print(f"{name}: Any  {named[name]}")
    if "--files" in argv:
        for (path, name), n in sorted(per_file.items()):
            print(f"  {path}: {name}: Any x{n}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
