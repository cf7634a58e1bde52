"""Runner: run folders, divergence recorded with the tables written, overrides, seeds, baseline."""

import json
import math

import pandas as pd
import pytest

from netsim.runner import run


def _unstable(duration="3 s"):
    # dc_servo with a = -20: the velocity grows as e^{20 t} without control (pole at s = +20).
    return {
        "name": "unstable",
        "duration": duration,
        "plant": {"model": "dc_servo", "params": {"gain": 1000, "a": -20}, "x0": [0.0, 1.0], "record_grid": "1 ms"},
        "record": ["y"],
    }


def test_divergence_is_recorded_as_status_with_csvs_up_to_that_time(tmp_path):
    result = run(_unstable(), out=tmp_path / "run")
    # the plant's divergence bound is 1e12 on the state norm; |x| ~ omega0 e^{20 t} -> t = ln(1e12)/20 = 1.3816 s,
    # detected at the next 1 ms grid sample
    t_div = math.log(1e12) / 20
    assert result.status.startswith("diverged at t = ")
    assert not result.ok
    meta = json.loads((tmp_path / "run" / "meta.json").read_text())
    assert meta["status"] == result.status and meta["error"]
    assert t_div <= meta["t_end_s"] <= t_div + 0.0011
    sig = pd.read_csv(tmp_path / "run" / "signals.csv")
    assert sig["time_s"].iloc[-1] <= meta["t_end_s"] + 1e-12
    assert sig["time_s"].iloc[-1] >= t_div - 0.0011
    assert (tmp_path / "run" / "metrics.csv").exists()


def test_overrides_and_seed_reach_the_scenario_and_meta(tmp_path):
    result = run(_unstable(), out=tmp_path / "r", seed=42, overrides={"duration": "0.25 s"})
    assert result.ok
    assert result.meta["seed"] == 42
    assert result.meta["t_end_s"] == 0.25
    assert result.scenario["seed"] == 42 and result.scenario["duration"] == "250 ms"
    assert len(result.meta["scenario_hash"]) == 64
    assert "numpy" in result.meta["versions"]
    # the 1 ms grid gives samples at 0, 1 ms, ..., 250 ms
    assert len(result.signals) == 251


def test_default_run_folder_is_reports_name_runid(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = run(_unstable("10 ms"))
    folders = list((tmp_path / "reports" / "unstable").iterdir())
    assert len(folders) == 1
    assert folders[0].name.endswith(result.meta["scenario_hash"][:8])
    assert (folders[0] / "scenario.yaml").exists()


def test_write_false_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    run(_unstable("10 ms"), write=False)
    assert not (tmp_path / "reports").exists()


def test_invalid_scenario_raises_with_every_problem(tmp_path):
    from netsim.scenario.problems import ScenarioError

    bad = _unstable()
    bad["duraton"] = "1 s"
    with pytest.raises(ScenarioError, match="duraton"):
        run(bad, out=tmp_path / "x")


def test_baseline_run_is_passed_to_metrics(tmp_path):
    from netsim.registry import register

    @register("metric", "test_runner_final_ratio", "test helper: final y over the baseline's final y")
    def final_ratio(result, params, baseline):
        return {"ratio": float(result.signals["y"].iloc[-1] / baseline.signals["y"].iloc[-1])}

    sc = {"name": "base", "duration": "5 ms",
          "plant": {"model": "dc_servo", "x0": [1.0, 0.0], "record_grid": "1 ms"},
          "metrics": [{"type": "test_runner_final_ratio"}],
          "baseline": {"overrides": {"plant.x0": [4.0, 0.0]}}}
    result = run(sc, out=tmp_path / "r")
    # no input: the angle stays at x0[0], so the ratio is 1/4
    assert result.metrics["ratio"] == pytest.approx(0.25)
    assert result.meta["baseline"] == {"status": "ok"}


def test_run_point_writes_the_folder_and_returns_metrics(tmp_path):
    from netsim.runner import run_point

    metrics = run_point(_unstable("0.1 s"), tmp_path / "p", seed=3)
    assert isinstance(metrics, dict)
    meta = json.loads((tmp_path / "p" / "meta.json").read_text())
    assert meta["seed"] == 3 and meta["status"] == "ok"


def test_record_names_nothing_recorded_are_reported_in_meta(tmp_path):
    result = run(
        "scenarios/dc_servo_ideal.yaml",
        out=tmp_path / "run",
        overrides={"duration": "50 ms", "record": ["y", "r", "yy"]},
    )
    assert result.meta["warnings"] == ["record: nothing recorded 'yy' (recorded signals: r, y)"]
    assert json.loads((tmp_path / "run" / "meta.json").read_text())["warnings"] == result.meta["warnings"]
    assert list(result.signals.columns) == ["time_s", "y", "r"]


def test_out_that_is_a_file_is_refused_before_anything_runs(tmp_path, monkeypatch):
    from netsim import runner
    from netsim.errors import ConfigError

    def must_not_run(*args, **kwargs):
        raise AssertionError("simulated although the run folder cannot be written")

    monkeypatch.setattr(runner, "simulate", must_not_run)
    afile = tmp_path / "afile"
    afile.write_text("")
    with pytest.raises(ConfigError, match=r"output '.*afile' is a file, not a folder"):
        run(_unstable("10 ms"), out=afile)
    with pytest.raises(ConfigError, match=r"cannot create run folder '.*afile/sub': '.*afile' is a file"):
        run(_unstable("10 ms"), out=afile / "sub")
    assert afile.read_text() == ""


def test_a_run_that_fails_after_writing_names_its_partial_folder(tmp_path):
    from netsim.errors import SimulationError
    from netsim.registry import register

    @register("metric", "test_runner_broken", "test helper: a metric that fails")
    def broken(result, params, baseline):
        raise SimulationError("broken metric")

    sc = {**_unstable("10 ms"), "metrics": [{"type": "test_runner_broken"}]}
    with pytest.raises(SimulationError) as info:
        run(sc, out=tmp_path / "partial")
    assert info.value.run_folder == tmp_path / "partial"
    meta = json.loads((tmp_path / "partial" / "meta.json").read_text())
    assert meta["status"] == "error" and "broken metric" in meta["error"]


def test_running_a_sweep_file_is_refused_naming_run_sweep(tmp_path):
    from netsim.errors import ConfigError

    with pytest.raises(ConfigError, match="this is a sweep file"):
        run("scenarios/hdd_gpi_sweep.yaml", out=tmp_path / "x")
    assert not (tmp_path / "x").exists()


def test_progress_callback_sees_simulated_time_and_changes_no_result(tmp_path):
    from netsim.timebase import MS

    scenario = "scenarios/dc_servo_can.yaml"
    overrides = {"duration": "0.3 s", "nodes.interference.tasks[0].params.share": 0.5}  # random traffic too
    calls = []
    plain = run(scenario, out=tmp_path / "plain", overrides=overrides)
    watched = run(scenario, out=tmp_path / "watched", overrides=overrides,
                  progress=lambda t, total: calls.append((t, total)))
    for name in ("scenario.yaml", "signals.csv", "jobs.csv", "messages.csv", "metrics.csv"):
        assert (tmp_path / "watched" / name).read_bytes() == (tmp_path / "plain" / name).read_bytes(), name
    assert watched.meta["events"] == plain.meta["events"]  # no extra event was scheduled
    # a report at the start and after every 1 % of the 300 ms: 0, 3 ms, 6 ms, ..., 300 ms
    assert calls == [(k * 3 * MS, 300 * MS) for k in range(101)]
