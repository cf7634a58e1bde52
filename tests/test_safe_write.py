"""Nothing finished is lost, nothing outside the run folder is written: atomic files, meta.json last, exclusive
folders, interrupted runs kept and marked."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

from netsim.errors import ConfigError
from netsim.registry import register
from netsim.report import report
from netsim.results import RunResult
from netsim.runner import run
from netsim.safe_write import make_unique_dir, write_atomic
from netsim.units import StrictModel

ROOT = Path(__file__).resolve().parents[1]


def test_planted_symlinks_in_the_run_folder_are_replaced_not_followed(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    folder = tmp_path / "run"
    folder.mkdir()
    for name in ("signals.csv", "meta.json", "scenario.yaml", ".signals.csv.%d.tmp" % os.getpid()):
        (folder / name).symlink_to(victim)
    result = RunResult(signals=pd.DataFrame({"time_s": [0.0, 1.0], "y": [1.0, 2.0]}), meta={"status": "ok"},
                       scenario={"name": "x"})
    result.to_csv(folder)
    assert victim.read_text() == "keep me"
    for name in ("signals.csv", "meta.json", "scenario.yaml"):
        assert not (folder / name).is_symlink() and (folder / name).is_file()
    assert json.loads((folder / "meta.json").read_text())["status"] == "ok"


def test_write_atomic_leaves_no_temporary_file_and_replaces_whole(tmp_path):
    path = tmp_path / "a.csv"
    write_atomic(path, "old\n")
    write_atomic(path, "new\n")
    assert path.read_text() == "new\n" and sorted(p.name for p in tmp_path.iterdir()) == ["a.csv"]


def test_two_runs_started_together_never_share_a_folder(tmp_path):
    with ThreadPoolExecutor(8) as pool:
        folders = list(pool.map(lambda _: make_unique_dir(tmp_path / "reports" / "x" / "stamp"), range(16)))
    assert len(set(folders)) == 16 and all(f.is_dir() for f in folders)


def test_report_refuses_a_folder_without_meta_json_as_incomplete(tmp_path):
    folder = tmp_path / "run"
    folder.mkdir()
    pd.DataFrame({"metric": ["a"], "value": [1.0]}).to_csv(folder / "metrics.csv", index=False)
    with pytest.raises(ConfigError, match="incomplete run folder"):
        report(folder, plots=False)


@register("program", "zzw_interrupted_at_third_job", "safe-write test: Ctrl-C arrives in the third job")
class _CtrlCAtThirdJob:
    class Params(StrictModel):
        pass

    def __init__(self, ctx: Any, params: Any) -> None:
        self.n = 0

    def __call__(self, job: Any):
        self.n += 1
        if self.n == 3:
            raise KeyboardInterrupt
        yield job.execute(1_000_000)


def test_a_run_interrupted_by_ctrl_c_keeps_its_tables_marked_interrupted(tmp_path):
    scenario = {"name": "cut", "seed": 1, "duration": "100 ms", "nodes": {"cpu": {"tasks": [
        {"name": "t", "program": "zzw_interrupted_at_third_job", "period": "10 ms", "priority": 1}]}}}
    with pytest.raises(KeyboardInterrupt) as info:
        run(scenario, out=tmp_path / "run")
    folder = info.value.run_folder
    meta = json.loads((folder / "meta.json").read_text())
    assert meta["status"] == "interrupted at t = 0.02 s"  # the third job is released at 20 ms
    jobs = pd.read_csv(folder / "jobs.csv")
    assert list(jobs["outcome"][:2]) == ["met", "met"]  # the jobs at 0 and 10 ms finished before the interrupt
    assert not (folder / "metrics.csv").exists()


@pytest.mark.skipif(sys.platform == "win32", reason="SIGTERM semantics")
def test_sigterm_during_netsim_run_exits_130_and_keeps_the_run_so_far(tmp_path):
    out = tmp_path / "run"
    # the CAN servo for 2000 s of simulated time takes minutes: SIGTERM arrives mid-simulation
    proc = subprocess.Popen([sys.executable, "-m", "netsim", "run", str(ROOT / "scenarios" / "dc_servo_can.yaml"),
                             "--set", "duration=2000 s", "--out", str(out), "--quiet"],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while not out.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        time.sleep(0.5)  # the simulation is running (its folder exists before it starts)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "interrupted" in err
    meta = json.loads((out / "meta.json").read_text())
    assert meta["status"].startswith("interrupted at t = ")
    assert len(pd.read_csv(out / "jobs.csv")) > 0
