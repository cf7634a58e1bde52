"""A loop that runs away on its own scale is 'diverged', though the plant's absolute bound was never reached."""

from __future__ import annotations

import numpy as np
import pytest

from netsim.divergence import first_non_finite, first_runaway_error
from netsim.runner import run


def test_first_non_finite_names_the_earliest_bad_sample():
    times = {"a": [0, 10, 20], "b": [0, 5, 15]}
    values = {"a": [0.0, 1.0, float("nan")], "b": [1.0, 2.0, float("inf")]}
    assert first_non_finite(times, values) == (15, "b")
    assert first_non_finite({"a": [0]}, {"a": [1.0]}) is None


def test_runaway_error_is_judged_against_the_loop_scale():
    t = np.array([0.0, 1.0, 2.0, 3.0])
    r = np.array([2.0, 2.0, 2.0, 2.0])  # scale = max |r| = 2
    y = np.array([0.0, 100.0, -1999.0, -2500.0])  # |e| = 2, 98, 2001, 2502
    assert first_runaway_error(t, r, y, 1000.0) == (2.0, 2001.0, 2.0)  # 2001 > 1000 * 2 first at t = 2
    assert first_runaway_error(t, r, y, 2000.0) is None  # 2502 < 2000 * 2
    assert first_runaway_error(t, np.zeros(4), np.zeros(4), 10.0) is None  # scale 0: not judged


def test_the_radio_servo_with_heavy_interference_is_reported_diverged(tmp_path):
    # dc_servo_zigbee with the interfering traffic at share 0.5: the loop's error grows to 8e8 (reference
    # amplitude 1) while the plant's absolute bound (1e12) is never reached; the run used to say "ok"
    res = run("scenarios/dc_servo_zigbee.yaml", out=tmp_path / "r", overrides={
        "duration": "1 s", "nodes.interference.tasks[0].params.share": 0.5})
    assert res.status.startswith("diverged at t = ")
    assert "diverged_above" in res.meta["error"]
    t = float(res.status.split("=")[1].split()[0])
    e = (res.signals["r"] - res.signals["y"]).abs()
    first = float(res.signals["time_s"][int(np.argmax((e > 1000.0).to_numpy()))])  # scale: |r| = 1
    assert t == pytest.approx(first)
    ok = run("scenarios/dc_servo_zigbee.yaml", out=tmp_path / "ok", overrides={"duration": "1 s"})
    assert ok.ok  # without interference the loop tracks: not flagged
