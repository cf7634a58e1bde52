"""The 2WD cart scenario (scenarios/unicycle_ekf.yaml): sensors on their own nodes, fusion at sample times."""

from __future__ import annotations

from collections import deque
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import netsim
from netsim.models.unicycle.programs import UnicycleEkf
from netsim.programs.basic import ProgramContext

SCENARIO = Path(__file__).resolve().parents[3] / "scenarios" / "unicycle_ekf.yaml"
# sensors silent after 9 s so every sample has arrived by the end; commands on their own ideal link so that the
# truth does not depend on the sensor network
SEPARATE = {
    "nodes.front.tasks[0].params.on": [["0 s", "4 s"], ["6 s", "9 s"]],
    "networks.can.type": "link", "networks.can.bitrate": None,
    "networks.cmd": {"type": "link", "nodes": ["ekf", "drive"]},
    "nodes.ekf.tasks[0].params.network": "cmd", "nodes.drive.tasks[0].params.network": "cmd",
    "nodes.drive.tasks[0].release": "on_message:cmd",
}
LATE = {"networks.can.delay": {"dist": "uniform", "low": "0 ms", "high": "35 ms"}, "networks.can.reorder": True}


def _final(r):
    return r.to_pandas()[["xhat[0]", "xhat[1]", "xhat[2]"]].iloc[-1].to_numpy()


def test_scenario_runs_with_each_sensor_on_its_schedule():
    r = netsim.run(SCENARIO)
    m = r.metrics
    assert r.status == "ok"
    # front: 50 Hz in [0, 4) s and [6, 10] s = 200 + 200 samples; side: 25 Hz in [0, 4) s = 100 samples
    assert m["control.front.ir.sent"] == 400 and m["control.side.ir.sent"] == 100
    assert m["control.ekf.filter.fused_front"] == 400 and m["control.ekf.filter.fused_side"] == 100
    assert m["control.ekf.filter.steps"] == 1000
    sig = r.to_pandas()
    # the truth and the estimate agree within 4 sigma at the end (x, y, theta)
    err = sig[["x", "y", "theta"]].iloc[-1].to_numpy() - _final(r)
    sd = sig[["sd[0]", "sd[1]", "sd[2]"]].iloc[-1].to_numpy()
    assert np.all(np.abs(err) < 4 * sd)


def test_late_samples_are_fused_at_their_sample_time():
    on_time = netsim.run(SCENARIO, overrides=SEPARATE)
    late = netsim.run(SCENARIO, overrides={**SEPARATE, **LATE})
    ml = late.metrics
    assert ml["control.ekf.filter.late"] > 100  # many samples arrive after their sample's job
    assert ml["control.ekf.filter.fused_front"] == ml["control.front.ir.sent"]
    assert ml["control.ekf.filter.duplicates"] == 0 and ml["control.ekf.filter.stale"] == 0
    # re-filtering from the stored priors does the arithmetic of on-time fusion (the filter's reset symmetrises
    # P, hence rounding-level differences only)
    assert np.allclose(_final(on_time), _final(late), rtol=0, atol=1e-12)
    at_arrival = netsim.run(SCENARIO, overrides={**SEPARATE, **LATE,
                                                 "nodes.ekf.tasks[0].params.fuse_at": "arrival"})
    assert not np.allclose(_final(on_time), _final(at_arrival), atol=1e-6)


class _Kernel:
    def __init__(self):
        self.boxes = {"can": deque()}

    def inbox(self, network):
        return self.boxes.setdefault(network, deque())


def _program(history=50):
    kernel = _Kernel()
    ctx = ProgramContext(env=None, kernel=kernel, node="ekf", task="filter", execution=None, period=10_000_000,
                         spec=SimpleNamespace(offset=2_000_000))
    params = UnicycleEkf.Params(measurements=[{"source": "front", "network": "can", "sender": "front"}],
                                network="can", to="drive", record=False, history=history)
    return UnicycleEkf(ctx, params), kernel


def _job(prog, k):
    job = SimpleNamespace(release=2_000_000 + k * 10_000_000, send=lambda *a, **kw: ("send", a))
    gen = prog(job)
    with pytest.raises(StopIteration):
        while True:
            next(gen)


def _msg(t_ns, value):
    return SimpleNamespace(sender="front", tag="front", payload={"value": value, "t_ns": t_ns})


def test_a_sample_is_never_fused_twice_and_an_old_one_is_stale():
    prog, kernel = _program(history=5)
    _job(prog, 0)
    kernel.boxes["can"].extend([_msg(10_000_000, 0.2), _msg(10_000_000, 0.25)])  # the same sample twice
    _job(prog, 1)
    assert prog.counts["fused_front"] == 1 and prog.counts["duplicates"] == 1
    kernel.boxes["can"].append(_msg(10_000_000, 0.2))  # again, one sample later: still a duplicate
    _job(prog, 2)
    assert prog.counts["duplicates"] == 2 and prog.counts["late"] == 0
    for k in range(3, 12):
        _job(prog, k)
    kernel.boxes["can"].append(_msg(20_000_000, 0.2))  # sample 2, now 10 samples back with history 5
    _job(prog, 12)
    assert prog.counts["stale"] == 1 and prog.counts["fused_front"] == 1


def test_a_late_sample_changes_the_estimate_like_an_on_time_one():
    on_time, kb = _program()
    late, kl = _program()
    kb.boxes["can"].append(_msg(0, 0.15))
    for k in range(4):
        _job(on_time, k)
        if k == 2:
            kl.boxes["can"].append(_msg(0, 0.15))  # sample 0 arrives at the job of sample 2
        _job(late, k)
    assert late.counts["late"] == 1
    assert np.allclose(on_time.ekf.x, late.ekf.x, rtol=0, atol=1e-15)
    assert np.allclose(on_time.ekf.P, late.ekf.P, rtol=0, atol=1e-15)
