"""The 2WD cart's sensor schedule lives in one place, the IR sensors' ``on`` windows (issue 26 section 7).

* the ``unicycle`` metric reads the blackout from those windows (it assumed the 4 s - 6 s turn);
* the filter's trajectory ``phases`` refuse the ``front``/``side`` flags that never did anything.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import netsim
from netsim.models.unicycle.metrics import blackout_window
from netsim.scenario.loader import check_scenario

SCENARIO = Path(__file__).resolve().parents[3] / "scenarios" / "unicycle_ekf.yaml"
# both sensors off from 5 s to 7 s (the turn stays at 4 s - 6 s); the front one on again from 7 s
SHIFTED = {"nodes.front.tasks[0].params.on": [["0 s", "5 s"], ["7 s", "11 s"]],
           "nodes.side.tasks[0].params.on": [["0 s", "5 s"]]}


def _scenario(front, side, duration="10 s"):
    def task(on):
        return {"program": "ir_sensor", "params": {"on": on}}
    return {"duration": duration, "nodes": {"front": {"tasks": [task(front)]}, "side": {"tasks": [task(side)]},
                                            "ekf": {"tasks": [{"program": "unicycle_ekf", "params": {}}]}}}


def test_the_blackout_is_the_first_interval_in_which_no_sensor_is_on():
    assert blackout_window(_scenario([["0 s", "4 s"], ["6 s", "11 s"]], [["0 s", "4 s"]])) == (4.0, 6.0)
    assert blackout_window(_scenario([["0 s", "5 s"], ["7 s", "11 s"]], [["0 s", "5 s"]])) == (5.0, 7.0)
    # the side sensor bridges part of the front one's gap: the blackout is where both are off
    assert blackout_window(_scenario([["0 s", "4 s"], ["6 s", "11 s"]], [["0 s", "4.5 s"]])) == (4.5, 6.0)
    # never on again: the blackout lasts to the end of the run
    assert blackout_window(_scenario([["0 s", "4 s"]], [["0 s", "3 s"]])) == (4.0, 10.0)
    # a sensor always on (on: null): no blackout
    assert blackout_window(_scenario(None, [["0 s", "4 s"]])) is None
    # no IR sensor task: the trajectory's turn phase (the standalone studies' case)
    assert blackout_window({"duration": "10 s", "nodes": {}}) == "turn"


def test_the_metric_measures_the_blackout_the_scenario_schedules():
    r = netsim.run(SCENARIO, overrides=SHIFTED)
    assert r.status == "ok"
    sig = r.signals
    sig = sig[sig["detP"].notna()]
    t = sig["time_s"].to_numpy()
    detP = sig["detP"].to_numpy()
    sd_x = sig["sd[0]"].to_numpy()
    # independently: with samples every 10 ms the last sample before the blackout is 4.99 s, its last one 6.99 s
    i0 = int(np.flatnonzero(np.isclose(t, 4.99))[0])
    i1 = int(np.flatnonzero(np.isclose(t, 6.99))[0])
    assert r.metrics["control.ekf.filter.fused_front"] == 250 + 150  # 50 Hz in [0, 5) and [7, 10]: the schedule acts
    want_ratio = detP[i1] / detP[i0]
    want_monotone = float(np.all(detP[i0 + 1:i1 + 1] > detP[i0:i1]))
    back = np.flatnonzero(sd_x[i1 + 1:] <= sd_x[i0])
    want_recovery = t[i1 + 1 + back[0]] - t[i1] if back.size else math.nan
    m = r.metrics
    assert m["unicycle.detP_ratio_turn"] == pytest.approx(want_ratio, rel=1e-12)
    assert m["unicycle.detP_monotone_turn"] == want_monotone == 1.0  # nothing measured in the blackout: P grows
    assert m["unicycle.recovery_x_s"] == pytest.approx(want_recovery, rel=1e-12, nan_ok=True)
    # the fixed 4 s - 6 s window would have seen the first second of measurements: det P fell there
    k4, k6 = int(np.flatnonzero(np.isclose(t, 3.99))[0]), int(np.flatnonzero(np.isclose(t, 5.99))[0])
    assert not np.all(np.diff(detP[k4:k6 + 1]) > 0)


def test_a_trajectory_phase_refuses_the_sensor_flags_and_says_where_the_schedule_is():
    phases = [{"duration": "4 s", "v": 0.03, "w": 0.0},
              {"duration": "2 s", "v": 0.02, "w": 0.785, "front": False, "side": False},
              {"duration": "4 s", "v": 0.015, "w": 0.0}]
    problems = check_scenario(SCENARIO, {"nodes.ekf.tasks[0].params.phases": phases})
    errors = [p for p in problems if p.severity == "error"]
    assert len(errors) == 1, problems
    assert errors[0].path == "nodes.ekf.tasks[0].params.phases[1]"
    assert "'front'" in errors[0].message and "'on' windows" in errors[0].message
    with pytest.raises(Exception, match="'on' windows"):
        netsim.run(SCENARIO, overrides={"nodes.ekf.tasks[0].params.phases": phases})
    # without the flags the same phases are accepted
    plain = [{k: v for k, v in ph.items() if k not in ("front", "side")} for ph in phases]
    assert not [p for p in check_scenario(SCENARIO, {"nodes.ekf.tasks[0].params.phases": plain})
                if p.severity == "error"]
