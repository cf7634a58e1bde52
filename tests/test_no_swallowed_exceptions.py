"""No exception is swallowed without a reason (issue 15 C): read from the sources of netsim/ and models/.

A handler is *silent* when it catches ``Exception``/``BaseException``/everything without re-raising, or when
its body only passes, continues or returns a constant. Each silent handler says why on its ``except`` line
(or its body's line) in a comment, e.g. ``except OSError:  # no /proc on this system: not an x86 Linux``;
``# noqa: BLE001`` alone is no reason. :data:`REVIEWED` lists the silent handlers that were read and found
correct before this test existed (keyed by function and exception types, so moving a module keeps its entry);
a new silent handler without a comment fails the test.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path


ROOT = Path(__file__).resolve().parents[1]
BROAD = {"Exception", "BaseException", "<bare>"}

#: (function, caught types): silent handlers read in issue 15 and kept, each a fallback its function exists for.
REVIEWED = {
    ("cpu_has_avx2_fma", "OSError"),  # no /proc/cpuinfo: not a Linux x86 machine, no BLAS pin
    ("_print_metrics", "AttributeError"),  # a result without a metrics mapping prints no metrics
    ("_terminate_as_interrupt", "ValueError, OSError"),  # signals can be set only from the main thread
    ("run", "Exception"),  # runner: a metrics failure becomes the run's recorded failure (assigned, not dropped)
    ("write_atomic", "OSError"),  # removing the temporary file after a failed write; the write error is raised
    ("call_problem", "TypeError, ValueError"),  # no inspectable signature: the call cannot be checked in advance
    ("_ns", "TimeParseError, TypeError"),  # limits: a malformed time is validate's problem to report
    ("_time_or_none", "TimeParseError, TypeError"),  # same, in validate's cross-checks
    ("line_of", "ConfigError"),  # a path that does not parse has no line
    ("_baseline", "ConfigError"),  # a problem path that does not parse is not an override's
    ("_walk", "TypeError"),  # an unhashable YAML key has no line to index (the schema reports the key)
    ("_lookup", "ConfigError"),  # static build: an unknown plugin is validate's problem
    ("node", "Exception"),  # validate: a policy that fails to load becomes a problem at its path
    ("is_sweep_file", "OSError, YamlRefused"),  # an unreadable file is not a sweep file (read again, reported)
    ("_line", "ConfigError"),  # sweep: no line for a path that does not parse
    ("read_record", "OSError, ValueError"),  # a missing or torn point.json: the point is run again
    ("verified_record", "OSError, ValueError, TypeError, KeyError"),  # no readable manifest: the point is rerun
    ("verified_record", "OSError"),  # a file gone while its digest is taken: not verified, the point is rerun
    ("_run_hash", "OSError, ValueError, TypeError, AttributeError"),  # no readable meta.json: hash the inputs
    ("_finished", "ConfigError"),  # a point whose scenario no longer loads is not finished
    ("_drive", "SchedulerLost"),  # the caller handles a lost Dask scheduler from the returned "lost"
    ("_from_config", "FileNotFoundError"),  # no user configuration file: plugins are not allowed
}

#: Silent handlers that hide real errors, left to the owner of the file (issue 15 C); the strict xfail below
#: fails as soon as one is fixed, so the entry is removed with the fix.


def _types(node: ast.expr | None) -> list[str]:
    if node is None:
        return ["<bare>"]
    if isinstance(node, ast.Tuple):
        return [n for e in node.elts for n in _types(e)]
    if isinstance(node, ast.Name):
        return [node.id]
    if isinstance(node, ast.Attribute):
        return [node.attr]
    return [ast.unparse(node)]


def _reason(line: str) -> str:
    """The comment of a source line without ``noqa``/``pragma`` markers (empty when it gives no reason)."""
    if "#" not in line:
        return ""
    comment = line.split("#", 1)[1]
    comment = re.sub(r"noqa(:\s*[A-Z0-9, ]+)?|pragma:\s*no cover", "", comment)
    return comment.strip(" -:,")


def _silent_handlers(source: str) -> list[tuple[str, str, int]]:
    """``(function, caught types, line)`` of the silent handlers in ``source`` that give no reason."""
    tree = ast.parse(source)
    lines = source.splitlines()
    owner: dict[int, str] = {}
    for fn in ast.walk(tree):
        if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for inner in ast.walk(fn):
                owner[id(inner)] = fn.name  # the innermost function wins: ast.walk visits outer ones first
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.ExceptHandler):
            continue
        types = _types(node.type)
        reraises = any(isinstance(n, ast.Raise) for n in ast.walk(node))
        trivial = all(isinstance(s, (ast.Pass, ast.Continue))
                      or (isinstance(s, ast.Return) and (s.value is None or isinstance(s.value, ast.Constant)))
                      for s in node.body)
        silent = (bool(BROAD & set(types)) and not reraises) or trivial
        why = _reason(lines[node.lineno - 1]) or any(_reason(lines[s.lineno - 1]) for s in node.body)
        if silent and not why:
            found.append((owner.get(id(node), "<module>"), ", ".join(types), node.lineno))
    return found


def test_the_checker_finds_a_silent_handler_and_accepts_a_reason():
    source = (
        "def f():\n    try:\n        g()\n    except Exception:  # noqa: BLE001\n        pass\n"
        "def h():\n    try:\n        g()\n    except KeyError:  # an absent key means the default\n        return None\n"
        "def k():\n    try:\n        g()\n    except:\n        log()\n"
        "def m():\n    try:\n        g()\n    except Exception:\n        cleanup()\n        raise\n"
    )
    assert _silent_handlers(source) == [("f", "Exception", 4), ("k", "<bare>", 14)]


def _tree_handlers() -> list[tuple[str, str, str]]:
    """``(function, types, "path:line")`` of every silent handler without a reason in netsim/ and models/."""
    return [(function, types, f"{path.relative_to(ROOT)}:{line}")
            for top in ("netsim", "models") for path in sorted((ROOT / top).rglob("*.py"))
            for function, types, line in _silent_handlers(path.read_text(encoding="utf-8"))]


def test_no_new_silent_exception_handler_in_netsim_or_models():
    new = [f"{where}: in {function}(): except {types}" for function, types, where in _tree_handlers()
           if (function, types) not in REVIEWED]
    assert new == [], ("exceptions swallowed without a reason; re-raise, report them, or say why on the except "
                       "line:\n" + "\n".join(new))
