"""netsim.results.folder: the one reader of run and sweep folders (issue 28).

Real folders are made by real runs of ``scenarios/dc_servo_ideal.yaml`` cut to 0.2 s. What the reader gives is
compared with what the run returned in memory (``netsim.run``'s RunResult, never read back from disk) and with
the sweep worker's own records (``point.json``), so no expected value comes from the reader itself.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from netsim.errors import ConfigError
from netsim.results import RunResult
from netsim.results.folder import FolderRefused, RunFolder, SweepFolder, read_summary
from netsim.sweep.run import SweepResult

REPO = Path(__file__).resolve().parents[2]
PID = "nodes.computer.tasks[0].params"


def _base() -> dict:
    raw = yaml.safe_load((REPO / "scenarios" / "dc_servo_ideal.yaml").read_text())
    raw["duration"] = "0.2 s"  # 20 control periods: a real run in a fraction of a second
    return raw


@pytest.fixture(scope="module")
def real_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[RunResult, Path]:
    from netsim.runner import run

    out = tmp_path_factory.mktemp("run") / "servo"
    result = run(_base(), out=out, seed=3, write=True)
    return result, out


@pytest.fixture(scope="module")
def swept(tmp_path_factory: pytest.TempPathFactory) -> SweepResult:
    from netsim.sweep import run_sweep

    folder = tmp_path_factory.mktemp("sweep")
    (folder / "base.yaml").write_text(yaml.safe_dump(_base(), sort_keys=False))
    (folder / "s.yaml").write_text(f"sweep: reader\nbase: base.yaml\nseed: 5\n"
                                   f"factors:\n  K: {{paths: ['{PID}.K'], values: [0.5, 2.0]}}\n")
    return run_sweep(folder / "s.yaml", out=folder / "out", workers=1, progress=False)


@pytest.fixture(scope="module")
def real_sweep(swept: SweepResult) -> Path:
    return swept.out_dir


# ---------------------------------------------------------------------------------------------- run folders
def test_a_run_folder_reads_back_what_the_run_returned(real_run: tuple[RunResult, Path]) -> None:
    result, path = real_run
    run = RunFolder.open(path)
    assert run.status == "ok" and run.name == "dc_servo_ideal" and run.meta["seed"] == 3
    assert run.metrics().equals(result.metrics.astype(float))
    pd.testing.assert_frame_equal(run.signals(), result.signals, check_dtype=False)
    jobs = run.jobs()
    assert jobs is not None and len(jobs) == len(result.jobs) > 0
    assert np.array_equal(jobs["response_s"].to_numpy(float), result.jobs["response_s"].to_numpy(float),
                          equal_nan=True)
    assert jobs["deadline_met"].dtype == "boolean"  # the nullable boolean the jobs table has in memory
    assert run.traces == {"jobs": "full", "messages": "full", "schedule": "on"}
    assert run.scenario() is not None and run.scenario()["name"] == "dc_servo_ideal"
    assert math.isclose(run.duration_s, 0.2)
    # reading chosen columns reads only those
    assert list(run.signals(columns=["time_s"]).columns) == ["time_s"]


def test_run_result_read_equals_the_folder_reader(real_run: tuple[RunResult, Path]) -> None:
    _, path = real_run
    back, run = RunResult.read(path), RunFolder(path)
    assert back.metrics.equals(run.metrics()) and back.meta == run.meta
    pd.testing.assert_frame_equal(back.jobs, run.jobs())


def _copy(src: Path, dst: Path) -> Path:
    import shutil

    shutil.copytree(src, dst)
    return dst


def test_an_incomplete_run_folder_is_refused_in_one_line(real_run: tuple[RunResult, Path], tmp_path: Path) -> None:
    path = _copy(real_run[1], tmp_path / "killed")
    (path / "meta.json").unlink()  # a run killed before it wrote meta.json (written last)
    for read in (RunFolder.open, RunResult.read):
        with pytest.raises(FolderRefused, match="incomplete run folder") as info:
            read(path)
        assert "\n" not in str(info.value)
    assert RunFolder(path).is_incomplete and not RunFolder(path).is_complete


def test_a_damaged_meta_json_is_refused(real_run: tuple[RunResult, Path], tmp_path: Path) -> None:
    path = _copy(real_run[1], tmp_path / "torn")
    (path / "meta.json").write_text('{"status": "ok", "scen')
    with pytest.raises(FolderRefused, match="meta.json' is not a readable JSON object"):
        RunFolder.open(path)


def test_a_metrics_only_folder_reads_with_empty_tables(real_run: tuple[RunResult, Path], tmp_path: Path) -> None:
    path = tmp_path / "m"
    path.mkdir()
    for name in ("metrics.csv", "meta.json"):  # what a sweep's `runs: metrics` keeps
        (path / name).write_bytes((real_run[1] / name).read_bytes())
    back = RunResult.read(path)  # was FileNotFoundError: signals.csv
    assert back.metrics.equals(real_run[0].metrics.astype(float)) and list(back.signals.columns) == ["time_s"]
    assert back.traces == {"jobs": "off", "messages": "off", "schedule": "off"}


# ---------------------------------------------------------------------------------------------- sweep folders
def test_a_sweep_folder_reads_its_summary_and_runs(real_sweep: Path) -> None:
    sweep = SweepFolder.open(real_sweep)
    assert sweep.name == "reader" and sweep.factors == ["K"]
    summary = sweep.summary()
    assert list(summary["K"]) == [0.5, 2.0] and list(summary["status"]) == ["ok", "ok"]
    runs = sweep.runs()
    assert [r.values for r in runs] == [{"K": 0.5}, {"K": 2.0}]
    for r, (_, row) in zip(runs, summary.iterrows()):
        record = json.loads((r.folder.path / "point.json").read_text())  # the worker's own record
        assert record["index"] == r.index == row["index"] and record["seed"] == row["seed"]
        for name, value in record["metrics"].items():
            assert row[name] == value and r.folder.metric_values()[name] == value
    sweep.verify()  # untouched: nothing refused


def test_a_sweep_point_changed_after_the_sweep_is_refused(real_sweep: Path, tmp_path: Path) -> None:
    from netsim.report import report

    path = _copy(real_sweep, tmp_path / "edited")
    point = SweepFolder.open(path).runs()[1].folder.path
    text = (point / "metrics.csv").read_text()
    (point / "metrics.csv").write_text(text.replace("metric,value\n", "metric,value\net.GPI,0.0\n"))
    with pytest.raises(FolderRefused, match=r"metrics.csv was changed after the sweep wrote it") as info:
        RunFolder.open(point)
    assert "\n" not in str(info.value)
    with pytest.raises(ConfigError, match="is not what the sweep wrote"):
        report(path, out=tmp_path / "r", plots=False)  # the report read the edited number before
    (point / "planted.txt").write_text("x")
    with pytest.raises(FolderRefused, match="planted.txt was added"):
        RunFolder.open(point)


def test_a_sweep_result_reads_its_folder_through_the_reader(swept: SweepResult) -> None:
    pd.testing.assert_frame_equal(swept.summary, swept.folder.summary())
    assert [r.folder.path for r in swept.folder.runs()] == [swept.out_dir / f for f in swept.summary["folder"]]


def test_a_folder_that_is_no_sweep_or_an_unfinished_one_is_refused(real_sweep: Path, tmp_path: Path) -> None:
    (tmp_path / "none").mkdir()
    with pytest.raises(FolderRefused, match="is not a sweep folder"):
        SweepFolder.open(tmp_path / "none")
    path = _copy(real_sweep, tmp_path / "cut")
    (path / "summary.csv").unlink()
    with pytest.raises(FolderRefused, match="has no summary.csv .*run the sweep again: it resumes"):
        SweepFolder.open(path)


def test_summary_metric_columns_holding_nan_are_numbers_and_empty_text_is_empty(tmp_path: Path) -> None:
    # netsim.sweep.summary writes a NaN metric as "nan" and no error as an empty cell
    from netsim.sweep.summary import write_summary

    rows = [{"index": 0, "replicate": 0, "values": {"K": 0.5, "law": "pid"}, "metrics": {"y.ISE": math.nan},
             "status": "ok", "seed": 1, "error": "", "folder": "points/0"},
            {"index": 1, "replicate": 0, "values": {"K": 2.0, "law": "lqr"}, "metrics": {"y.ISE": 0.25},
             "status": "error", "seed": 2, "error": "ValueError: x", "folder": "points/1"}]
    frame = read_summary(write_summary(tmp_path / "summary.csv", ["K", "law"], rows))
    assert frame["y.ISE"].dtype == np.float64 and math.isnan(frame["y.ISE"][0]) and frame["y.ISE"][1] == 0.25
    assert list(frame["error"]) == ["", "ValueError: x"] and list(frame["law"]) == ["pid", "lqr"]
    assert list(frame["index"]) == [0, 1] and frame["index"].dtype == np.int64


def test_report_on_a_sweep_without_its_summary_says_to_resume(real_sweep: Path, tmp_path: Path) -> None:
    from netsim.report import report

    path = _copy(real_sweep, tmp_path / "cut")
    (path / "summary.csv").unlink()  # the sweep was killed before it wrote summary.csv
    with pytest.raises(ConfigError, match="has no summary.csv .*it resumes"):  # was: 'is not a run folder'
        report(path, out=tmp_path / "r", plots=False)


def test_a_batch_folder_skips_an_incomplete_run_with_a_warning(real_run: tuple[RunResult, Path], tmp_path: Path,
                                                               caplog: pytest.LogCaptureFixture) -> None:
    from netsim.report import find_runs
    from netsim.results.folder import run_folders_in

    batch = tmp_path / "batch"
    _copy(real_run[1], batch / "b_done")
    (_copy(real_run[1], batch / "a_killed") / "meta.json").unlink()
    with caplog.at_level("WARNING", logger="netsim.results.folder"):
        found = run_folders_in(batch)
    assert [r.path.name for r in found] == ["b_done"]
    assert "skipping incomplete run folder" in caplog.text and "a_killed" in caplog.text
    kind, runs = find_runs(batch)
    assert kind == "batch" and [(case, run.path) for case, run, _ in runs] == [("b_done", batch / "b_done")]
