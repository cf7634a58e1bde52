"""``netsim sweep`` / ``netsim run`` with the wrong kind of file, and sweeps refused before any run."""

from __future__ import annotations

import sys
import types
from pathlib import Path

from netsim.cli import main

ROOT = Path(__file__).resolve().parents[2]
CAN = ROOT / "scenarios" / "dc_servo_can.yaml"


def test_sweep_with_an_invalid_probability_level_is_refused_listing_it(tmp_path, capsys):
    sweep = tmp_path / "share.yaml"
    sweep.write_text(f"sweep: share\nbase: {CAN}\nfactors:\n  share:\n"
                     "    paths: [nodes.interference.tasks[0].params.share]\n    values: [0.3, 7]\n")
    assert main(["sweep", str(sweep), "--out", str(tmp_path / "out"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert len(lines) == 2 and "Traceback" not in err
    assert lines[0].startswith(f"{sweep}:4: point (share=7): nodes.interference.tasks[0].params") and "7" in lines[0]  # line 4: factor 'share'
    assert lines[1] == f"netsim: error: sweep {sweep}: 1 problem; nothing was run"
    assert not (tmp_path / "out").exists()


def test_sweep_of_a_scenario_file_says_to_use_run(tmp_path, capsys):
    assert main(["sweep", str(CAN), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{CAN}: this is a scenario file" in err and f"run it with `netsim run {CAN}`" in err
    assert "validation error" not in err and "Field required" not in err and "Traceback" not in err
    assert len(err.splitlines()) <= 2 and not (tmp_path / "out").exists()


def test_run_of_a_sweep_file_says_to_use_sweep(tmp_path, capsys):
    sweep = ROOT / "scenarios" / "hdd_gpi_sweep.yaml"
    assert main(["run", str(sweep), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err == f"netsim: error: {sweep}: this is a sweep file; use `netsim sweep {sweep}`\n"
    assert not (tmp_path / "out").exists()
