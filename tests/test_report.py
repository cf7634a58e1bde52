"""Report tables: values recomputed independently from the run's own CSV files, and folder kinds.

The HDD test runs Case 3 of Cuenca et al. (a 9.28 ms simulation) and recomputes Uc, Ua, Cc and GPI from
``messages.csv`` with eqs (26)-(29) of the paper, counting sensor->controller and controller->actuator
messages by sender/receiver (not by the tags the metric uses).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pandas as pd
import pytest
import yaml

from netsim.errors import ConfigError
from netsim.registry import register
from netsim.report import NETWORK_COLUMNS, TASK_COLUMNS, UTILIZATION_COLUMNS, report

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def hdd_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from netsim.runner import run

    raw = yaml.safe_load((REPO / "scenarios" / "hdd_case3.yaml").read_text())
    out = tmp_path_factory.mktemp("hdd3")
    run(raw, out=out, seed=1, write=True)
    return out


def test_hdd_report_equals_recomputation_from_messages(hdd_run: Path, tmp_path: Path) -> None:
    tables = report(hdd_run, out=tmp_path / "rep", plots=False)
    row = tables["utilization"].iloc[0]
    msgs = pd.read_csv(hdd_run / "messages.csv")
    T = 20e-6  # section 5: T = 20 us
    n_tts = 464  # section 5.1: N_TTS = 464 (9.28 ms / 20 us)
    window = msgs["sent_s"] < n_tts * T
    n_sc = int(((msgs["sender"] == "sensor") & (msgs["receiver"] == "controller") & window).sum())
    n_ca = int(((msgs["sender"] == "controller") & (msgs["receiver"] == "actuator") & window).sum())
    uc, ua = n_sc / n_tts, n_ca / n_tts  # eqs (26), (27)
    m, n = 2, 1  # eq (34): two slow modes interlaced (m = 2), one fast mode
    cc = uc * (1 - (m - 1) / (m + n)) * 100  # eq (28)
    gpi = 0.45 * uc + 0.45 * ua + 0.1 * row["NE_ratio"]  # eq (29), W1 = W2 = 0.45, W3 = 0.1
    assert 0 < n_sc < n_tts and 0 < n_ca < n_tts  # an event-triggered run: fewer sends than periods
    assert row["Nsc_count"] == n_sc and row["Nca_count"] == n_ca and row["NTTS_count"] == n_tts
    for got, want in [(row["Uc_ratio"], uc), (row["Ua_ratio"], ua), (row["Cc_pct"], cc), (row["GPI"], gpi)]:
        assert math.isclose(got, want, rel_tol=1e-9), (got, want)
    assert math.isclose(row["CS_pct"], 100 / 3, rel_tol=1e-9)  # eq (20): (m-1)/(m+n) = 33 %
    # the tables written as CSV read back equal to the returned ones
    back = pd.read_csv(tmp_path / "rep" / "utilization.csv")
    assert math.isclose(back["GPI"][0], gpi, rel_tol=1e-9)


def test_hdd_task_and_network_statistics_match_the_csv_files(hdd_run: Path, tmp_path: Path) -> None:
    tables = report(hdd_run, out=tmp_path / "rep", plots=True)
    jobs = pd.read_csv(hdd_run / "jobs.csv")
    msgs = pd.read_csv(hdd_run / "messages.csv")
    tasks, nets = tables["tasks"], tables["networks"]
    assert list(tasks.columns) == TASK_COLUMNS and list(nets.columns) == NETWORK_COLUMNS
    ctrl = tasks[(tasks["node"] == "controller") & (tasks["task"] == "control")].iloc[0]
    mine = jobs[(jobs["node"] == "controller") & (jobs["task"] == "control")]
    assert ctrl["jobs_count"] == len(mine)
    assert math.isclose(ctrl["response_max_s"], mine["response_s"].max(), rel_tol=1e-12)
    assert math.isclose(ctrl["cpu_util_ratio"], mine["cpu_time_s"].sum() / 9.28e-3, rel_tol=1e-9)
    net = nets.iloc[0]
    delivered = msgs[~msgs["dropped"].astype(bool)]
    assert net["messages_count"] == len(msgs) and net["delivered_count"] == len(delivered)
    assert math.isclose(net["delay_mean_s"], delivered["delay_s"].mean(), rel_tol=1e-9)
    assert math.isclose(net["bits_total"], msgs["bits"].sum(), rel_tol=1e-12)
    assert (tmp_path / "rep" / "utilization.png").exists() and (tmp_path / "rep" / "network_delays.png").exists()


# ---------------------------------------------------------------------------------------------- synthetic runs
def _fake_run(folder: Path, *, name: str, uc: float, gpi: float) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    pd.DataFrame({"metric": ["Uc", "Ua", "GPI", "cpu.ctrl.utilization"], "value": [uc, uc / 2, gpi, 0.25]}).to_csv(
        folder / "metrics.csv", index=False)
    pd.DataFrame({
        "node": ["ctrl", "ctrl", "ctrl"], "task": ["loop"] * 3, "job_id": [0, 1, 2],
        "release_s": [0.0, 0.01, 0.02], "start_s": [0.0, 0.01, 0.02], "finish_s": [0.002, 0.013, 0.022],
        "response_s": [0.002, 0.003, 0.002], "deadline_s": [0.01, 0.02, 0.03], "deadline_met": [True, True, False],
        "preemptions": [0, 1, 0], "cpu_time_s": [0.002, 0.002, 0.002], "killed": [False, False, False],
    }).to_csv(folder / "jobs.csv", index=False)
    pd.DataFrame({
        "msg_id": [0, 1, 2], "network": ["can"] * 3, "sender": ["s"] * 3, "receiver": ["c"] * 3, "tag": ["y"] * 3,
        "bits": [80, 80, 80], "priority": [0] * 3, "sent_s": [0.0, 0.01, 0.02], "tx_start_s": [0.0, 0.011, 0.02],
        "delivered_s": [0.001, 0.012, None], "dropped": [False, False, True], "drop_reason": ["", "", "lost"],
        "delay_s": [0.001, 0.002, None],
    }).to_csv(folder / "messages.csv", index=False)
    (folder / "meta.json").write_text(json.dumps({"scenario": name, "status": "ok", "duration_s": 0.03}))
    return folder


def test_batch_folder_gives_one_row_per_run_in_name_order(tmp_path: Path) -> None:
    _fake_run(tmp_path / "b" / "zeta", name="zeta", uc=0.5, gpi=0.4)
    _fake_run(tmp_path / "b" / "alpha", name="alpha", uc=0.2, gpi=0.3)
    tables = report(tmp_path / "b", plots=False)
    util = tables["utilization"]
    assert list(util.columns) == ["case", "status", *(c for _, c in UTILIZATION_COLUMNS)]
    assert list(util["case"]) == ["alpha", "zeta"] and list(util["Uc_ratio"]) == [0.2, 0.5]
    assert math.isnan(util["ISE"][0])  # not a metric of these runs: empty cell
    tasks = tables["tasks"]
    # 3 jobs, one missed its deadline, one preemption, 6 ms CPU over 30 ms
    assert list(tasks["deadline_misses_count"]) == [1, 1] and list(tasks["preemptions_count"]) == [1, 1]
    assert math.isclose(tasks["cpu_util_ratio"][0], 0.006 / 0.03)
    nets = tables["networks"]
    assert list(nets["dropped_count"]) == [1, 1] and math.isclose(nets["loss_ratio"][0], 1 / 3)
    assert math.isclose(nets["delay_mean_s"][0], 0.0015) and math.isclose(nets["wait_mean_s"][0], 0.001 / 3)
    assert list(tables["nodes"]["cpu_util_ratio"]) == [0.25, 0.25]
    assert (tmp_path / "b" / "report" / "tasks.csv").exists()


def fake_run_point(raw, out, seed):
    """Sweep point that writes a synthetic run folder; GPI has its minimum at K = 1, Ti = 0.2."""
    p = raw["nodes"]["computer"]["tasks"][0]["params"]
    K, Ti = float(p["K"]), float(p["Ti"])
    gpi = (K - 1.0) ** 2 + (Ti - 0.2) ** 2
    _fake_run(Path(out), name="pt", uc=K / 10, gpi=gpi)
    return {"Uc": K / 10, "GPI": gpi}


def test_sweep_folder_report_has_factor_columns_and_the_optimum(tmp_path: Path) -> None:
    from netsim.sweep import run_sweep

    base = yaml.safe_load((REPO / "scenarios" / "dc_servo_ideal.yaml").read_text())
    (tmp_path / "base.yaml").write_text(yaml.safe_dump(base, sort_keys=False))
    pid = "nodes.computer.tasks[0].params"
    (tmp_path / "s.yaml").write_text(f"""
sweep: rep
base: base.yaml
factors:
  K: {{paths: ['{pid}.K'], values: [0.5, 1.0, 2.0]}}
  Ti: {{paths: ['{pid}.Ti'], values: [0.1, 0.2]}}
surface: {{x: K, y: Ti, z: GPI}}
""")
    run_sweep(tmp_path / "s.yaml", out=tmp_path / "o", workers=1, point_fn=fake_run_point, progress=False)
    tables = report(tmp_path / "o", out=tmp_path / "r", plots=False)
    util = tables["utilization"]
    assert list(util.columns[:6]) == ["case", "index", "replicate", "K", "Ti", "status"]
    assert list(util["index"]) == list(range(6))
    assert list(util["GPI"]) == [(k - 1) ** 2 + (t - 0.2) ** 2 for k in (0.5, 1.0, 2.0) for t in (0.1, 0.2)]
    opt = tables["optimum"].iloc[0]
    assert (opt["x_value"], opt["y_value"], opt["z_value"]) == (1.0, 0.2, 0.0)  # the analytic minimum
    assert len(tables["summary"]) == 6


@register("report", "sweep_test_report", "report used by tests/test_report.py")
def _test_report(out_dir, plots):
    return {"called": pd.DataFrame({"out": [str(out_dir)], "plots": [plots]})}


def test_registered_report_name_calls_the_case_study_function(tmp_path: Path) -> None:
    tables = report("sweep_test_report", out=tmp_path, plots=False)
    assert tables["called"]["out"][0] == str(tmp_path) and not tables["called"]["plots"][0]


def test_unknown_folder_or_report_name_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="neither a folder nor a registered report.*did you mean 'sweep_test_report'"):
        report("sweep_test_reprt", plots=False)
    (tmp_path / "empty").mkdir()
    with pytest.raises(ConfigError, match="is not a run folder"):
        report(tmp_path / "empty", plots=False)


def test_run_folders_with_legacy_metric_names_read_like_todays(tmp_path: Path) -> None:
    # before the <scope>.<measure> rule, et_control wrote "Uc", "GPI", ...; today it writes "et.Uc", "et.GPI"
    old = _fake_run(tmp_path / "b" / "old", name="old", uc=0.5, gpi=0.4)
    new = _fake_run(tmp_path / "b" / "new", name="new", uc=0.5, gpi=0.4)
    frame = pd.read_csv(new / "metrics.csv")
    frame["metric"] = [m if m.startswith("cpu.") else f"et.{m}" for m in frame["metric"]]
    frame.to_csv(new / "metrics.csv", index=False)
    util = report(tmp_path / "b", plots=False)["utilization"].set_index("case")
    assert (util.loc["new", "Uc_ratio"], util.loc["new", "GPI"]) == (0.5, 0.4)
    assert util.loc["old"].drop("status").equals(util.loc["new"].drop("status"))
