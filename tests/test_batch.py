"""Batch: one row per scenario, a failing scenario becomes a row with its error and counts as failed."""

import pandas as pd
import yaml

from netsim.sweep.batch import expand_paths, run_batch


def _write(path, name, **extra):
    doc = {"name": name, "duration": "20 ms",
           "plant": {"model": "dc_servo", "x0": [1.0, 0.0], "record_grid": "1 ms"}}
    doc.update(extra)
    path.write_text(yaml.safe_dump(doc))
    return path


def test_batch_with_one_failing_scenario_reports_it_and_counts_it(tmp_path):
    scen = tmp_path / "scen"
    scen.mkdir()
    _write(scen / "a_good.yaml", "good")
    _write(scen / "b_bad.yaml", "bad", duraton="1 s")           # misspelt key
    (scen / "c_sweep.yaml").write_text("sweep: s\nbase: a_good.yaml\n")  # sweeps are skipped
    summary, n_failed = run_batch([scen], out=tmp_path / "out", workers=1, progress=False)
    assert n_failed == 1
    assert summary["scenario"].tolist() == ["good", "b_bad"]
    assert summary["status"].tolist() == ["ok", "error"]
    assert "duraton" in summary.loc[1, "error"]
    # metrics become columns; the failed row has none
    on_disk = pd.read_csv(tmp_path / "out" / "summary.csv")
    assert on_disk.columns[:6].tolist() == ["scenario", "path", "status", "error", "wall_time_s", "run_dir"]
    assert (tmp_path / "out" / "a_good" / "signals.csv").exists()


def test_batch_in_worker_processes_keeps_input_order(tmp_path):
    files = [_write(tmp_path / f"s{i}.yaml", f"s{i}") for i in range(3)]
    files.append(tmp_path / "missing.yaml")
    summary, n_failed = run_batch(files, out=tmp_path / "out", workers=2, progress=False)
    assert summary["scenario"].tolist() == ["s0", "s1", "s2", "missing"]
    assert n_failed == 1
    assert summary["status"].tolist()[:3] == ["ok", "ok", "ok"]


def test_expand_paths_keeps_files_and_sorts_folders(tmp_path):
    _write(tmp_path / "b.yaml", "b")
    _write(tmp_path / "a.yml", "a")
    single = tmp_path / "b.yaml"
    assert [p.name for p in expand_paths([tmp_path])] == ["a.yml", "b.yaml"]
    assert expand_paths([single]) == [single]
