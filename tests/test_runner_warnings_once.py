"""A warning that loading the scenario already logged is not logged again by the run (it was printed twice)."""

import json

from netsim.cli import main


def test_the_unstable_nominal_loop_warning_is_printed_once_and_kept_in_meta(tmp_path, capsys):
    # pendulum_hold_still runs its loop with a zero gain on purpose: validate's static check warns that the
    # nominal loop is unstable, and the run used to log the same finding a second time
    out = tmp_path / "run"
    assert main(["run", "scenarios/pendulum_hold_still.yaml", "--out", str(out), "--set", "duration=0.2 s"]) == 0
    err = capsys.readouterr().err
    assert err.count("the nominal closed loop") == 1, err
    warnings = json.loads((out / "meta.json").read_text())["warnings"]
    assert sum("the nominal closed loop" in w for w in warnings) == 1, warnings
