"""A sweep with ``runs: metrics`` (issue 19): each run folder holds metrics.csv and meta.json only, with the same
metrics and summary as ``runs: full``, and a rerun resumes it."""

from __future__ import annotations

from pathlib import Path

import yaml

from netsim.sweep import load_sweep, run_sweep

REPO = Path(__file__).resolve().parents[1]
PID = "nodes.computer.tasks[0].params"


def _sweep(folder: Path, runs: str | None) -> Path:
    base = yaml.safe_load((REPO / "scenarios" / "dc_servo_ideal.yaml").read_text())
    base["duration"] = "0.3 s"
    (folder / "base.yaml").write_text(yaml.safe_dump(base, sort_keys=False))
    text = f"sweep: small\nbase: base.yaml\nseed: 3\nfactors:\n  K:\n    paths: [{PID}.K]\n    values: [0.5, 2.0]\n"
    if runs is not None:
        text += f"runs: {runs}\n"
    (folder / "sweep.yaml").write_text(text)
    return folder / "sweep.yaml"


def test_runs_metrics_writes_metrics_and_meta_only_with_the_same_summary(tmp_path: Path) -> None:
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    full = run_sweep(_sweep(tmp_path / "a", None), out=tmp_path / "full", workers=1, progress=False)
    small = run_sweep(_sweep(tmp_path / "b", "metrics"), out=tmp_path / "small", workers=1, progress=False)
    assert load_sweep(tmp_path / "a" / "sweep.yaml").spec.runs == "full"  # the default
    assert full.n_ok == small.n_ok == 2
    for index in range(2):
        point = next((tmp_path / "small" / "points").glob(f"{index:05d}-*"))
        assert sorted(p.name for p in point.iterdir()) == ["manifest.json", "meta.json", "metrics.csv", "point.json"]
        same = next((tmp_path / "full" / "points").glob(f"{index:05d}-*"))
        assert (point / "metrics.csv").read_bytes() == (same / "metrics.csv").read_bytes()
        assert {p.name for p in same.iterdir()} >= {"scenario.yaml", "signals.csv", "jobs.csv", "messages.csv"}
    summary = (tmp_path / "small" / "summary.csv").read_text().replace("small", "X")
    assert summary.splitlines()[1:] and summary == (tmp_path / "full" / "summary.csv").read_text().replace(
        "full", "X")
    again = run_sweep(_sweep(tmp_path / "b", "metrics"), out=tmp_path / "small", workers=1, progress=False)
    assert again.n_resumed == 2  # finished points are recognised from point.json and meta.json
