"""RunResult.to_timeresponse (issue 27 s2): python-control's TimeResponseData holding the recorded arrays, with the
plant's port and state names as labels."""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np
import pytest

import netsim

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def pendulum():
    # record: null records everything: the plant's outputs on its grid, its held input and its state at events
    return netsim.run(ROOT / "scenarios" / "pendulum_lqr.yaml", overrides={"duration": "0.05 s", "record": None})


def test_outputs_inputs_and_states_are_the_recorded_plant_columns(pendulum):
    resp = pendulum.to_timeresponse()
    sig = pendulum.signals
    assert isinstance(resp, control.TimeResponseData) and resp.sysname == "pendulum_lqr"
    np.testing.assert_array_equal(resp.time, sig["time_s"].to_numpy())
    # the Furuta pendulum model's ports and states (models: outputs theta, alpha; input u; 4 states)
    assert resp.output_labels == ["theta", "alpha"] and resp.input_labels == ["u"]
    assert resp.state_labels == ["theta", "theta_dot", "alpha", "alpha_dot"]
    np.testing.assert_array_equal(resp.outputs, sig[["theta", "alpha"]].to_numpy().T)
    np.testing.assert_array_equal(np.atleast_2d(resp.inputs), sig[["pendulum.u[0]"]].to_numpy().T)
    np.testing.assert_array_equal(resp.states, sig[[f"pendulum.x[{i}]" for i in range(4)]].to_numpy().T)
    assert np.isfinite(resp.outputs[:, 1:]).all() and np.nanmax(np.abs(resp.states)) > 0  # not an empty run


def test_without_the_plant_columns_the_io_channels_stand_in(tmp_path):
    result = netsim.run(ROOT / "scenarios" / "dc_servo_can.yaml", overrides={"duration": "0.1 s"})  # record: [r, y, u]
    resp = result.to_timeresponse()
    assert resp.output_labels == ["y"] and resp.input_labels == ["u"] and resp.nstates == 0
    np.testing.assert_array_equal(resp.outputs, result.signals["y"].to_numpy())
    np.testing.assert_array_equal(resp.inputs, result.signals["u"].to_numpy())
    assert resp.states.shape == (0, len(result.signals))
    # a folder read back has the same scenario: the same response
    result.to_csv(tmp_path / "run")
    back = netsim.RunResult.read(tmp_path / "run").to_timeresponse()
    np.testing.assert_array_equal(back.outputs, resp.outputs)


def test_named_columns_replace_the_defaults_and_unknown_ones_are_refused(pendulum):
    resp = pendulum.to_timeresponse(outputs=["theta_m", "alpha_m"], inputs=["u"], states=[])
    assert resp.output_labels == ["theta_m", "alpha_m"] and resp.nstates == 0
    np.testing.assert_array_equal(resp.outputs[1], pendulum.signals["alpha_m"].to_numpy())
    with pytest.raises(KeyError, match="no recorded signal 'nope'"):
        pendulum.to_timeresponse(outputs=["nope"])
    with pytest.raises(ValueError, match="no plant output was recorded"):
        netsim.RunResult().to_timeresponse()
