"""``cpu.<node>.utilization`` without a kernel trace (``output.schedule: off``, issue 26 section 7).

Before the fix a run whose last event came before the end of the run stopped with "utilization over a window
needs trace=True": netsim's event loop leaves the clock at the last entry it processed, and the untraced
utilization only accepted a window ending at the clock.
"""

from __future__ import annotations

import pytest

import netsim


def _scenario(duration: str, schedule: str) -> dict:
    return {
        "name": "idle_node",
        "duration": duration,
        "plant": {"model": "dc_servo", "params": {"gain": 1000, "a": 1}},
        "io": {"y": {"type": "adc", "output": 0}, "u": {"type": "dac", "input": 0}},
        "signals": {"r": {"type": "constant", "value": 1.0}},
        "networks": {"link": {"type": "ideal", "nodes": ["computer", "spare"]}},
        "nodes": {
            "computer": {"policy": "fp", "tasks": [
                {"name": "pid", "program": "periodic_controller", "period": "6 ms", "priority": 1,
                 "execution": "2 ms", "params": {"channel": "y", "output_channel": "u", "reference": "r",
                                                 "K": 0.96, "Ti": 0.12}}]},
            "spare": {"policy": "fp"},  # no task on the ideal link
        },
        "output": {"schedule": schedule},
    }


@pytest.mark.parametrize(
    ("duration", "busy_ms", "total_ms"),
    [
        # jobs released at 0, 6, ..., 96 ms (17 jobs), 2 ms each, all done by 98 ms: 34 ms busy of 100 ms
        ("100 ms", 34, 100),
        # the run ends at 97 ms while the job released at 96 ms runs: 16 * 2 + 1 = 33 ms busy of 97 ms
        ("97 ms", 33, 97),
    ],
)
def test_utilization_without_a_schedule_trace_counts_up_to_the_end_of_the_run(duration, busy_ms, total_ms):
    result = netsim.run(_scenario(duration, "off"))
    assert result.metrics["cpu.computer.utilization"] == pytest.approx(busy_ms / total_ms, rel=1e-12)
    assert result.metrics["cpu.spare.utilization"] == 0.0  # no job, no handler: never busy


def test_utilization_is_the_same_with_and_without_the_trace():
    traced = netsim.run(_scenario("97 ms", "on")).metrics
    untraced = netsim.run(_scenario("97 ms", "off")).metrics
    for node in ("computer", "spare"):
        key = f"cpu.{node}.utilization"
        assert untraced[key] == pytest.approx(traced[key], rel=1e-12)
