"""How much Python the case-study reports take (issue 28: "models' report and prose code at most 2,000 lines").

The report and prose code is every module that runs a study for its report, quotes its numbers or writes its
text; the figure modules are counted apart (they draw, they do not write). The words are data in the
``models/**/*.md`` templates, which are not Python and are counted on their own line of the report.

Counted (lines, as ``wc -l``) at the start of this work: 3,929 (hdd_report 592, cart/report 460, cart/claims 353,
pendulum/report 871, pendulum/report_sweeps 271, unicycle/readme 303, readme_net 519, report 245, quoting 87,
studies 228). The prose moved to templates; what is left is mostly the computation of each quoted number, so the
issue's 2,000 is not reached: the ceiling below keeps the count from growing back, and the strict xfail turns
into a failure the day the target is met, so that the ceiling is then lowered to it.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: The report and prose modules named in issue 28's count.
LISTED = ("models/hdd_report.py", "models/cart/report.py", "models/cart/claims.py", "models/pendulum/report.py",
          "models/pendulum/report_sweeps.py", "models/unicycle/readme.py", "models/unicycle/readme_net.py",
          "models/unicycle/report.py", "models/unicycle/quoting.py", "models/unicycle/studies.py")
#: A module split out of them later is counted too: its name says report, readme, claims or quoting.
NAMED = re.compile(r"(report|readme|claims|quoting)[a-z_]*\.py$")
#: The count after issue 28's templates (lines): it may only go down.
CEILING = 3396
TARGET = 2000


def _lines(path: Path) -> int:
    return len(path.read_text(encoding="utf-8").splitlines())


def report_code() -> list[Path]:
    found = {ROOT / p for p in LISTED} | {p for p in (ROOT / "models").rglob("*.py") if NAMED.search(p.name)}
    return sorted(found)


def test_the_listed_report_modules_exist():
    # a renamed module would leave the count silently: each listed path must still be there
    assert [p for p in LISTED if not (ROOT / p).is_file()] == []


def test_report_and_prose_code_does_not_grow():
    counts = {str(p.relative_to(ROOT)): _lines(p) for p in report_code()}
    total = sum(counts.values())
    assert total <= CEILING, f"report and prose code is {total} lines (ceiling {CEILING}): {counts}"


@pytest.mark.xfail(strict=True, reason="issue 28's target (2,000 lines) is not met: the quoting code remains")
def test_report_and_prose_code_meets_the_issue_target():
    assert sum(_lines(p) for p in report_code()) <= TARGET


def test_templates_are_counted_apart_and_are_not_python():
    templates = sorted((ROOT / "models").rglob("*.md"))
    assert templates and all(not t.read_text(encoding="utf-8").lstrip().startswith(("import ", "from ", "def "))
                             for t in templates)
