"""RunResult's public surface holds only what a user reads (issue 27 s2): the records and samples the tables are
built from, and the two accessors that read them without building a table, are private."""

from __future__ import annotations

from dataclasses import fields
from pathlib import Path

import netsim
from netsim.results import RunResult

ROOT = Path(__file__).resolve().parents[2]
INTERNAL = ("job_rows", "message_rows", "signal_source", "schedule_source", "table_rows", "signal_chunks")


def test_internal_fields_and_accessors_are_private():
    public = {f.name for f in fields(RunResult)} | {n for n in dir(RunResult) if not n.startswith("_")}
    assert not public & set(INTERNAL)
    assert {f"_{n}" for n in INTERNAL} <= {f.name for f in fields(RunResult)} | set(dir(RunResult))


def test_a_fresh_run_still_writes_its_tables_from_the_records(tmp_path):
    result = netsim.run(ROOT / "scenarios" / "dc_servo_can.yaml", overrides={"duration": "0.1 s"})
    assert result._table_rows("jobs") is not None and result._signal_chunks(["y"]) is not None
    result.to_csv(tmp_path / "run")
    back = RunResult.read(tmp_path / "run")
    assert back._table_rows("jobs") is None and len(back.jobs) == len(result.jobs) > 0
