"""The recorded actuator value is what the DAC puts out (after saturation); what the program asked for is
recorded as '<channel>.command' when wanted (issue 21: `u` read +-600 with `saturation: [-1, 1]`)."""

from __future__ import annotations

import numpy as np

from netsim.runner import run


def _loop(record: list[str]) -> dict:
    # README's "Writing a scenario" loop with a 100x gain: the PID asks for far more than the DAC's +-1
    return {
        "name": "saturated", "seed": 1, "duration": "0.3 s",
        "plant": {"model": "dc_servo", "x0": [0, 0]},
        "io": {"y": {"type": "adc", "output": 0}, "u": {"type": "dac", "input": 0, "saturation": [-1, 1]}},
        "signals": {"r": {"type": "square", "amplitude": 1.0, "period": "1 s"}},
        "nodes": {"cpu": {"policy": "fp", "tasks": [
            {"name": "pid", "program": "periodic_controller", "period": "10 ms", "priority": 1, "execution": "2 ms",
             "params": {"channel": "y", "output_channel": "u", "reference": "r", "K": 96.0, "Ti": 0.12,
                        "Td": 0.049}}]}},
        "record": record,
    }


def test_recorded_u_is_the_saturated_output_and_the_command_has_its_own_name():
    result = run(_loop(["y", "u", "u.command", "r"]), write=False)
    u = result.signals["u"].dropna().to_numpy()
    cmd = result.signals["u.command"].dropna().to_numpy()
    assert np.abs(u).max() == 1.0  # saturation [-1, 1]
    assert np.abs(cmd).max() > 10.0  # K = 96 on a unit step: the request is far outside the range
    np.testing.assert_array_equal(u, np.clip(cmd, -1.0, 1.0))  # the same writes, before and after the DAC


def test_the_command_is_recorded_only_when_asked_for():
    result = run(_loop(["y", "u", "r"]), write=False)
    assert "u.command" not in result.signals.columns
    assert np.abs(result.signals["u"].dropna()).max() == 1.0
