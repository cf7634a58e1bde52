"""`netsim run`, `netsim batch` and `netsim sweep` apply one status rule: only "ok" succeeds; a diverged run
is kept and reported, and the command exits 1 (netsim.status)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest

from netsim.cli import main
from netsim.status import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, count_statuses, kind_of

ROOT = Path(__file__).resolve().parents[2]


def _diverging(tmp_path: Path) -> Path:
    # three_servos_dm.yaml: DM on an overloaded CPU loses its lowest-priority loop, which diverges at t = 1.48 s
    # (the scenario's own comment and the README); the run stops there with status "diverged at t = ...".
    path = tmp_path / "diverging.yaml"
    shutil.copy(ROOT / "scenarios" / "three_servos_dm.yaml", path)
    return path


def _fine(tmp_path: Path) -> Path:
    path = tmp_path / "fine.yaml"
    text = (ROOT / "scenarios" / "dc_servo_ideal.yaml").read_text(encoding="utf-8")
    path.write_text(text, encoding="utf-8")
    return path


def test_run_and_batch_both_exit_1_when_a_scenario_diverges(tmp_path, capsys):
    diverging, fine = _diverging(tmp_path), _fine(tmp_path)
    assert main(["run", str(diverging), "--out", str(tmp_path / "one"), "--quiet"]) == EXIT_FAILED
    assert "diverged at t =" in capsys.readouterr().out
    code = main(["batch", str(fine), str(diverging), "--out", str(tmp_path / "b"), "--workers", "1",
                 "--no-progress"])
    out = capsys.readouterr().out
    assert code == EXIT_FAILED
    assert "1 of 2 scenarios ok, 1 diverged" in out
    summary = pd.read_csv(tmp_path / "b" / "summary.csv")
    assert summary["status"].str.startswith("diverged").sum() == 1
    assert (tmp_path / "b" / "diverging" / "metrics.csv").exists()  # the diverged run's output is kept


def test_batch_of_ok_runs_exits_0(tmp_path, capsys):
    code = main(["batch", str(_fine(tmp_path)), "--out", str(tmp_path / "b"), "--workers", "1", "--no-progress"])
    assert code == EXIT_OK and "1 of 1 scenario ok" in capsys.readouterr().out


@pytest.mark.parametrize("status, kind", [("ok", "ok"), ("diverged at t = 1.48 s", "diverged"), ("error", "error"),
                                          ("pending", "pending"), ("", "error"), (None, "error")])
def test_status_kinds(status, kind):
    assert kind_of(status) == kind


def test_status_counts_give_the_exit_code_and_summary_line():
    counts = count_statuses(["ok", "diverged at t = 2 s", "error", "ok"])
    assert (counts.ok, counts.diverged, counts.error, counts.not_ok) == (2, 1, 1, 2)
    assert counts.describe("scenario") == "2 of 4 scenarios ok, 1 diverged, 1 failed"
    assert counts.exit_code() == EXIT_FAILED
    assert count_statuses(["ok"]).exit_code() == EXIT_OK
    assert count_statuses(["ok", "pending"]).exit_code(interrupted=True) == EXIT_INTERRUPTED
