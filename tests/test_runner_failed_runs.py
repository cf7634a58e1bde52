"""A run that fails with an error keeps its tables but writes no metrics.csv (no numbers for a run that failed)."""

from __future__ import annotations

from typing import Any

import json
import pytest

from netsim.errors import ConfigError
from netsim.registry import register
from netsim.runner import run
from netsim.units import StrictModel


@register("program", "zzr_fails_at_third_job", "runner test: raises a ConfigError in its third job")
class _FailsAtThirdJob:
    class Params(StrictModel):
        pass

    def __init__(self, ctx: Any, params: Any) -> None:
        self.n = 0

    def __call__(self, job: Any):
        self.n += 1
        if self.n == 3:
            raise ConfigError("the third job cannot go on: change nothing, this is a test")
        yield job.execute(1_000_000)


def _scenario() -> dict:
    return {"name": "fails", "seed": 1, "duration": "100 ms", "nodes": {"cpu": {"tasks": [
        {"name": "t", "program": "zzr_fails_at_third_job", "period": "10 ms", "priority": 1}]}}}


def test_a_run_that_fails_writes_its_tables_and_meta_but_no_metrics(tmp_path):
    with pytest.raises(ConfigError, match="third job") as info:
        run(_scenario(), out=tmp_path / "run")
    folder = info.value.run_folder
    meta = json.loads((folder / "meta.json").read_text())
    assert meta["status"] == "error" and "third job" in meta["error"]
    assert (folder / "jobs.csv").exists() and (folder / "signals.csv").exists()
    assert not (folder / "metrics.csv").exists()  # the first two jobs ran, but the run failed: no metrics
