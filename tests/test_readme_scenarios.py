"""README's "Scenarios shipped" table cannot go stale: it names every scenario and sweep ``netsim scenarios`` lists,
each in a row with a summary, and nothing that is not shipped; and its "What netsim models" list names the
features a user would otherwise find only in the scenario reference."""

from __future__ import annotations

import re
from pathlib import Path

from netsim.cli import main

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text(encoding="utf-8")


def _section(heading: str) -> str:
    """The text under ``heading`` (any level) up to the next heading of any level."""
    match = re.search(rf"^#+ {re.escape(heading)}\n(.*?)(?=^#+ |\Z)", README, flags=re.S | re.M)
    assert match, f"README.md has no '{heading}' section"
    return match.group(1)


def _table_rows(text: str) -> list[tuple[str, str]]:
    """(first cell, second cell) of each body row of the section's markdown table."""
    rows = []
    for line in text.splitlines():
        if line.startswith("|") and not line.startswith("|---") and not line.startswith("| file "):
            cells = [cell.strip() for cell in line.strip().strip("|").split(" | ")]
            rows.append((cells[0], cells[1] if len(cells) > 1 else ""))
    return rows


def _listed(capsys) -> dict[str, str]:
    """What ``netsim scenarios`` prints: name -> one-line summary."""
    assert main(["scenarios"]) == 0
    lines = capsys.readouterr().out.splitlines()
    return {parts[0]: parts[2] for parts in (line.split(None, 2) for line in lines)}


def test_the_scenarios_table_names_every_shipped_scenario_and_nothing_else(capsys):
    listed = _listed(capsys)
    rows = _table_rows(_section("Scenarios shipped"))
    in_table = {name for first, _ in rows for name in re.findall(r"`([\w-]+)\.yaml`", first)}
    assert len(listed) > 40, "netsim scenarios lists too few: the parsing is broken"  # 55 files when written
    missing = sorted(set(listed) - in_table)
    assert not missing, f"README's 'Scenarios shipped' table lacks {missing}"
    unknown = sorted(in_table - set(listed))
    assert not unknown, f"README's 'Scenarios shipped' table names {unknown}, which netsim scenarios does not list"


def test_each_row_of_the_scenarios_table_says_what_its_files_show():
    rows = _table_rows(_section("Scenarios shipped"))
    assert rows, "no table under 'Scenarios shipped'"
    for first, summary in rows:
        assert re.search(r"`[\w-]+\.yaml`", first), f"row without a file name: {first!r}"
        assert "..." not in first, f"a range of files hides names; list each: {first!r}"
        assert len(summary.split()) >= 4, f"row {first!r} has no one-line summary"


def test_what_netsim_models_names_the_scheduling_cpu_and_fmu_features():
    text = _section("What netsim models")
    # the keys a user writes for each feature (scenario reference: nodes.<n>.servers, .timetable, .cores, .speed)
    for needle in ("servers", "timetable", "cores", "speed", "FMI 2.0", "FMI 3.0", "CAN", "EDF"):
        assert needle in text, f"'What netsim models' does not mention {needle}"
