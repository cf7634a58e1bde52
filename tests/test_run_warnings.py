"""A run that is 'ok' but overloaded says so: saturated networks, large drops, tasks that never ran."""

from __future__ import annotations

import pandas as pd

from netsim.run_warnings import load_warnings
from netsim.runner import run


def test_warnings_name_the_saturated_network_its_drops_and_the_idle_task():
    metrics = {"net.can.utilization": 0.999, "net.can.copies": 400.0, "net.can.dropped": 100.0,
               "net.can.dropped.queue_full": 100.0, "net.can.dropped.lost": 0.0,
               "net.eth.utilization": 0.2, "net.eth.copies": 1000.0, "net.eth.dropped": 5.0}
    jobs = pd.DataFrame({"node": ["a"], "task": ["t1"]})
    nodes = {"a": type("N", (), {"tasks": [type("T", (), {"name": "t1", "release": None})(),
                                           type("T", (), {"name": "t2", "release": "on_message:can"})()]})()}
    out = load_warnings(metrics, jobs, nodes, ["can", "eth"])
    assert len(out) == 3  # eth: 0.5 % dropped, under the 1 % threshold; 20 % busy
    assert "'can' is saturated: busy 99.9 %" in out[0]
    assert "dropped 100 of 400 message copies (25.0 %: queue_full 100)" in out[1]
    assert "task a.t2 (released on_message:can) never ran" in out[2]


def test_a_can_bus_flooded_by_interference_warns_though_the_run_is_ok(tmp_path):
    # dc_servo_can with the interfering node sending 80-bit frames at top priority every 0.5 ms: 80 bits at
    # 80 kbit/s = 1 ms per frame, so the interference alone offers 2x what the bus carries; the queue bound drops
    # frames, and the servo's frames never win arbitration: the controller and actuator never run
    res = run("scenarios/dc_servo_can.yaml", out=tmp_path / "r", overrides={
        "nodes.interference.tasks[0].params.share": 1.0,
        "nodes.interference.tasks[0].period": "0.5 ms"})
    assert res.ok
    text = "\n".join(res.meta["warnings"])
    assert "network 'can' is saturated" in text and "queue_full" in text
    assert "task controller.control (released on_message:can) never ran" in text


def test_a_warning_logged_by_a_metric_is_kept_in_meta_json(tmp_path):
    # hdd_case3 with the other cases' h = 100 and their 1 Gbit/s network (the report's "h 100" variant): eq (22)
    # holds packets back for longer than h periods, and et_control logs that the actuator played past its packet
    res = run("scenarios/hdd_case3.yaml", out=tmp_path / "r", overrides={
        "nodes.controller.tasks[0].params.design_params.h": 100,
        "networks.net.bitrate": "1 Gbit/s", "networks.net.max_frame_bits": None})
    assert res.metrics["et.played_past_packet"] > 0
    assert any("past the end of its packet" in w for w in res.meta["warnings"])
