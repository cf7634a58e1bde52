"""Sweeps end to end with an injected point function: executors agree byte for byte, resume, failures, bad input.

The point functions here are module-level fakes (picklable for the process pool, which forks this process):
their metrics are closed-form functions of the point's scenario values and seed, so every expected number
is computed in the test from the sweep file, never by the code under test.
"""

from __future__ import annotations

import math
import shutil
import socket
import threading
from pathlib import Path

import pytest
import yaml

from netsim.errors import ConfigError
from netsim.sweep import SchedulerUnreachable, derive_seed, load_sweep, run_sweep

REPO = Path(__file__).resolve().parents[1]
PID = "nodes.computer.tasks[0].params"

# ---------------------------------------------------------------------------------------------- fake points
_calls: list[int] = []
_interrupt_at: list[int] = []  # interrupt (Ctrl-C) at this call number, once


def _params(raw):
    return raw["nodes"]["computer"]["tasks"][0]["params"]


def fake_point(raw, out, seed):
    """Deterministic metrics of the point's K, Ti (and Td, tied to Ti) and seed; fails for K == 3."""
    p = _params(raw)
    K, Ti, Td = float(p["K"]), float(p["Ti"]), float(p["Td"])
    _calls.append(seed)
    if _interrupt_at and len(_calls) == _interrupt_at[0]:
        _interrupt_at.clear()
        raise KeyboardInterrupt
    if K == 3.0:
        raise ValueError("controller K = 3 diverges (test failure)")
    (Path(out) / "ran.txt").write_text(str(seed))
    return {
        "GPI": (math.log10(K) + 0.5) ** 2 + (Ti - 0.2) ** 2 + (seed % 1000) * 1e-9,
        "Uc": K / (1.0 + K),
        "tied": float(Td == Ti),
        "seed_mod": float(seed % 100003),
    }


# ---------------------------------------------------------------------------------------------- fixtures
def _write_sweep(folder: Path, *, replicates: int = 1, surface: bool = False) -> Path:
    base = yaml.safe_load((REPO / "scenarios" / "dc_servo_ideal.yaml").read_text())
    base["name"] = "sweep_base"
    (folder / "base.yaml").write_text(yaml.safe_dump(base, sort_keys=False))
    text = f"""
sweep: demo
base: base.yaml
seed: 42
mode: product
factors:
  K:
    paths: [{PID}.K]
    values: [0.1, 0.3, 1.0, 3.0]
  Ti:
    paths: [{PID}.Ti, {PID}.Td]
    linspace: {{start: 0.05, stop: 0.35, num: 3}}
replicates: {replicates}
"""
    if surface:
        text += "surface: {x: K, y: Ti, z: GPI}\n"
    path = folder / "sweep.yaml"
    path.write_text(text)
    return path


@pytest.fixture()
def sweep_file(tmp_path: Path) -> Path:
    _calls.clear()
    _interrupt_at.clear()
    return _write_sweep(tmp_path, replicates=2)


# ---------------------------------------------------------------------------------------------- executors
def test_serial_pool_and_dask_summaries_are_byte_identical(sweep_file: Path, tmp_path: Path) -> None:
    serial = run_sweep(sweep_file, out=tmp_path / "serial", workers=1, point_fn=fake_point, progress=False)
    pool = run_sweep(sweep_file, out=tmp_path / "pool", workers=2, point_fn=fake_point, progress=False)
    dask = run_sweep(sweep_file, out=tmp_path / "dask", workers=2, local_dask=True,
                     cluster_kwargs={"processes": False}, point_fn=fake_point, progress=False)
    text = (tmp_path / "serial" / "summary.csv").read_bytes()
    assert (tmp_path / "pool" / "summary.csv").read_bytes() == text
    assert (tmp_path / "dask" / "summary.csv").read_bytes() == text
    assert "process pool" in pool.executor and "dask" in dask.executor and "serial" in serial.executor
    # 4 K x 3 Ti x 2 replicates; K = 3 fails in its 3 x 2 runs and does not stop the sweep
    assert serial.n_runs == 24 and serial.n_failed == 6 and serial.n_ok == 18


def test_summary_rows_carry_factor_values_seeds_and_metrics(sweep_file: Path, tmp_path: Path) -> None:
    res = run_sweep(sweep_file, out=tmp_path / "o", workers=1, point_fn=fake_point, progress=False)
    df = res.summary
    assert list(df.columns[:4]) == ["index", "replicate", "K", "Ti"]
    assert list(df["index"]) == list(range(24))
    # product order: K slowest, then Ti, replicate innermost
    assert list(df["K"][:6]) == [0.1] * 6 and list(df["Ti"][:6]) == [0.05, 0.05, 0.2, 0.2, 0.35, 0.35]
    spec = load_sweep(sweep_file).spec
    for row in df.itertuples():
        seed = derive_seed(spec.seed, {"K": row.K, "Ti": row.Ti}, row.replicate)
        assert row.seed == seed
        if row.K == 3.0:
            assert row.status == "error" and "K = 3 diverges" in row.error and math.isnan(row.GPI)
            continue
        assert row.status == "ok" and row.tied == 1.0  # Td was tied to Ti
        expected = (math.log10(row.K) + 0.5) ** 2 + (row.Ti - 0.2) ** 2 + (seed % 1000) * 1e-9
        assert row.GPI == expected
        assert (tmp_path / "o" / row.folder / "ran.txt").read_text() == str(seed)
    assert df["seed"].nunique() == 24  # replicates get different seeds


def test_scheduler_address_runs_on_a_dask_cluster(sweep_file: Path, tmp_path: Path) -> None:
    from distributed import LocalCluster

    ref = run_sweep(sweep_file, out=tmp_path / "ref", workers=1, point_fn=fake_point, progress=False)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tcp",
                      dashboard_address=None) as cluster:
        res = run_sweep(sweep_file, out=tmp_path / "tcp", scheduler=cluster.scheduler_address,
                        point_fn=fake_point, progress=False)
    assert cluster.scheduler_address in res.executor
    assert (tmp_path / "tcp" / "summary.csv").read_bytes() == ref.summary_path.read_bytes()


def test_surface_section_writes_the_optimum_of_the_summary(tmp_path: Path) -> None:
    import pandas as pd

    path = _write_sweep(tmp_path, surface=True)
    res = run_sweep(path, out=tmp_path / "o", workers=1, point_fn=fake_point, progress=False)
    ok = res.summary[res.summary["status"] == "ok"]
    best = ok.loc[ok["GPI"].idxmin()]  # arg-min computed here from summary.csv
    assert (res.optimum["x_value"], res.optimum["y_value"]) == (best["K"], best["Ti"])
    assert res.optimum["z_value"] == best["GPI"]
    assert (tmp_path / "o" / "surface.png").stat().st_size > 10_000
    cells = pd.read_csv(tmp_path / "o" / "surface.csv")
    assert len(cells) == 12 and cells["GPI"].isna().sum() == 3  # K = 3 failed: 3 empty cells


# ---------------------------------------------------------------------------------------------- resume
def test_interrupted_then_resumed_sweep_equals_uninterrupted(sweep_file: Path, tmp_path: Path) -> None:
    ref = run_sweep(sweep_file, out=tmp_path / "ref", workers=1, point_fn=fake_point, progress=False)
    _calls.clear()
    _interrupt_at.append(9)  # Ctrl-C during the 9th run: 8 finished
    cut = run_sweep(sweep_file, out=tmp_path / "cut", workers=1, point_fn=fake_point, progress=False)
    assert cut.interrupted and cut.n_pending == 24 - 8
    assert (tmp_path / "cut" / "summary.csv").read_text().count(",pending,") == 16
    _calls.clear()
    done = run_sweep(sweep_file, out=tmp_path / "cut", workers=2, point_fn=fake_point, progress=False)
    assert not done.interrupted and done.n_resumed == 8 and done.n_executed == 16
    assert (tmp_path / "cut" / "summary.csv").read_bytes() == ref.summary_path.read_bytes()


def test_rerun_skips_finished_points_and_retries_failed_ones(sweep_file: Path, tmp_path: Path) -> None:
    run_sweep(sweep_file, out=tmp_path / "o", workers=1, point_fn=fake_point, progress=False)
    _calls.clear()
    again = run_sweep(sweep_file, out=tmp_path / "o", workers=1, point_fn=fake_point, progress=False)
    assert again.n_resumed == 18 and again.n_executed == 6 and len(_calls) == 6  # only the K = 3 runs


def test_changed_base_scenario_reruns_points(sweep_file: Path, tmp_path: Path) -> None:
    run_sweep(sweep_file, out=tmp_path / "o", workers=1, point_fn=fake_point, progress=False)
    base = yaml.safe_load((sweep_file.parent / "base.yaml").read_text())
    base["duration"] = "1 s"  # a different scenario: the scenario hash of every point changes
    (sweep_file.parent / "base.yaml").write_text(yaml.safe_dump(base, sort_keys=False))
    _calls.clear()
    again = run_sweep(sweep_file, out=tmp_path / "o", workers=1, point_fn=fake_point, progress=False)
    assert again.n_resumed == 0 and len(_calls) == 24


# ---------------------------------------------------------------------------------------------- bad input
def test_unknown_factor_path_is_refused_with_did_you_mean(tmp_path: Path) -> None:
    path = _write_sweep(tmp_path)
    path.write_text(path.read_text().replace(f"{PID}.Ti, ", f"{PID}.Tii, "))
    with pytest.raises(ConfigError) as err:
        load_sweep(path)
    assert "factors.Ti.paths[0]" in str(err.value) and "did you mean 'Ti'" in str(err.value)


def test_empty_factor_list_is_refused(tmp_path: Path) -> None:
    (tmp_path / "s.yaml").write_text("sweep: x\nbase: base.yaml\nfactors: {}\n")
    with pytest.raises(ConfigError, match="'factors' is empty"):
        load_sweep(tmp_path / "s.yaml")


def test_silent_scheduler_fails_fast_with_a_clear_message(sweep_file: Path, tmp_path: Path) -> None:
    silent = socket.socket()  # accepts connections, never answers: Client() alone would hang here
    silent.bind(("127.0.0.1", 0))
    silent.listen(8)
    address = f"tcp://127.0.0.1:{silent.getsockname()[1]}"
    outcome: list[BaseException] = []

    def attempt() -> None:
        try:
            run_sweep(sweep_file, out=tmp_path / "o", scheduler=address, connect_timeout=1.0,
                      point_fn=fake_point, progress=False)
        except BaseException as exc:  # noqa: BLE001
            outcome.append(exc)

    worker = threading.Thread(target=attempt, daemon=True)
    worker.start()
    worker.join(30)  # hang guard: the 1 s timeout must end the attempt long before this
    silent.close()
    assert not worker.is_alive(), "run_sweep hung on a scheduler that does not answer"
    assert len(outcome) == 1 and isinstance(outcome[0], SchedulerUnreachable)
    assert address in str(outcome[0]) and "within 1 s" in str(outcome[0])


def test_output_folder_holding_another_sweep_is_refused_unless_overwrite(sweep_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "o"
    run_sweep(sweep_file, out=out, workers=1, point_fn=fake_point, progress=False)
    other = sweep_file.read_text().replace("sweep: demo", "sweep: other")
    other_file = sweep_file.with_name("other.yaml")
    other_file.write_text(other)
    with pytest.raises(ConfigError, match="holds sweep 'demo', not sweep 'other'"):
        run_sweep(other_file, out=out, workers=1, point_fn=fake_point, progress=False)
    res = run_sweep(other_file, out=out, workers=1, point_fn=fake_point, progress=False, overwrite=True)
    assert res.n_resumed == 0 and res.name == "other"


def test_output_folder_with_foreign_files_is_refused(sweep_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "o"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    with pytest.raises(ConfigError, match="files that are not a sweep"):
        run_sweep(sweep_file, out=out, workers=1, point_fn=fake_point, progress=False)
    assert (out / "notes.txt").exists()


def test_cli_style_flow_list_paths_parse(tmp_path: Path) -> None:
    # the contract writes `paths: [a.b[0].c]`, which plain YAML rejects ('[' inside a flow list)
    path = _write_sweep(tmp_path)
    assert f"paths: [{PID}.Ti, {PID}.Td]" in path.read_text()
    sweep = load_sweep(path)
    assert sweep.spec.factors["Ti"].paths == [f"{PID}.Ti", f"{PID}.Td"]


def test_repository_sweep_files_load() -> None:
    for name in ("hdd_gpi_sweep.yaml", "cart_fig2.yaml", "cart_quant.yaml"):
        if (REPO / "scenarios" / name).exists():
            assert load_sweep(REPO / "scenarios" / name).points


def test_hdd_gpi_grid_contains_the_paper_thresholds() -> None:
    sweep = load_sweep(REPO / "scenarios" / "hdd_gpi_sweep.yaml")
    s = sorted({p.values["sigma_s"] for p in sweep.points})
    c = sorted({p.values["sigma_c"] for p in sweep.points})
    assert len(s) == 21 and len(c) == 21 and len(sweep.points) == 441
    # section 5: delta_s = sigma_s = 100e-7, delta_c = sigma_c = 1.32e-2 (optimum); Case 5: 1e-7 and 1e-4
    assert math.isclose(s[10], 1e-5, rel_tol=1e-12) and math.isclose(c[10], 1.32e-2, rel_tol=1e-12)
    assert math.isclose(s[5], 1e-7, rel_tol=1e-12) and math.isclose(c[0], 1e-4, rel_tol=1e-12)
    raw = sweep.point_raw(sweep.points[5 * 21])  # sigma_s index 5, sigma_c index 0
    sensor = raw["nodes"]["sensor"]["handlers"][0]["params"]
    ctrl = raw["nodes"]["controller"]["tasks"][0]["params"]
    assert sensor["sigma_s"] == sensor["delta_s"] == s[5] and ctrl["sigma_c"] == ctrl["delta_c"] == c[0]
    weights = raw["metrics"][0]["params"]["weights"]
    assert weights == [0.45, 0.45, 0.1]  # W1 = W2 = 0.45, W3 = 0.1 (section 5)


def test_overwrite_clears_previous_points(sweep_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "o"
    run_sweep(sweep_file, out=out, workers=1, point_fn=fake_point, progress=False)
    stale = out / "points" / "99999-stale"
    stale.mkdir()
    _calls.clear()
    run_sweep(sweep_file, out=out, workers=1, point_fn=fake_point, progress=False, overwrite=True)
    assert not stale.exists() and len(_calls) == 24
    shutil.rmtree(out)


def test_chunk_planner_batches_tiny_runs_and_sends_slow_runs_one_by_one() -> None:
    from netsim.sweep.run import ChunkPlanner

    assert ChunkPlanner(2, fixed=5).next_size(3) == 3
    tiny = ChunkPlanner(2)
    assert tiny.next_size(400) == 1  # nothing timed yet
    tiny.observe(0.004, 4)  # 1 ms per run: 0.25 s target -> 250, capped at 32, and 400 // (4 * 2) = 50
    assert tiny.next_size(400) == 32 and tiny.next_size(40) == 5
    slow = ChunkPlanner(2)
    slow.observe(3.0, 2)  # 1.5 s per run (an HDD point)
    assert slow.next_size(400) == 1


def test_invalid_factor_levels_are_refused_before_any_run(sweep_file: Path, tmp_path: Path) -> None:
    text = sweep_file.read_text().replace(
        "replicates:", "  period:\n    paths: [nodes.computer.tasks[0].period]\n"
        "    values: [6 ms, -1 ms, fast]\nreplicates:")
    sweep_file.write_text(text)
    with pytest.raises(ConfigError) as err:
        run_sweep(sweep_file, out=tmp_path / "out", workers=2, point_fn=fake_point, progress=False)
    problems = [str(p) for p in err.value.problems]
    # both bad levels are listed (each once), nothing ran, no output folder was made
    assert len(problems) == 2, problems
    assert any("period='-1 ms'" in p for p in problems) and any("period='fast'" in p for p in problems)
    assert "nothing was run" in str(err.value)
    assert _calls == [] and not (tmp_path / "out").exists()


def multiline_failure(raw, out, seed):
    """Fails every point with a two-problem, multi-line message (like a ScenarioError)."""
    raise ValueError("scenario has 2 problems:\n  a.b: first\n\n  c.d: second")


def test_summary_error_is_one_line_and_point_json_keeps_the_full_text(sweep_file: Path, tmp_path: Path) -> None:
    import json

    result = run_sweep(sweep_file, out=tmp_path / "o", workers=1, point_fn=multiline_failure, progress=False)
    lines = (tmp_path / "o" / "summary.csv").read_text().splitlines()
    assert len(lines) == 1 + result.n_runs  # the header and one line per run
    assert set(result.summary["error"]) == {"ValueError: scenario has 2 problems: a.b: first | c.d: second"}
    point = json.loads(next((tmp_path / "o" / "points").glob("*/point.json")).read_text())
    assert point["error"] == "ValueError: scenario has 2 problems:\n  a.b: first\n\n  c.d: second"
