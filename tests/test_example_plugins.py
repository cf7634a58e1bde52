"""The plugin examples of the README's "Writing a plugin" (examples/plugins/): a custom plant (water_tank), a
custom controller program (pi_antiwindup) and a custom medium (slotted_bus), loaded by a scenario's
``plugins:`` list with allow_plugins, give the numbers their models predict."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import netsim
from netsim.scenario import ScenarioError

ROOT = Path(__file__).resolve().parents[1]
LOOP = ROOT / "examples" / "plugins" / "tank_loop.yaml"


@pytest.fixture(scope="module")
def tank():
    return netsim.run(LOOP, allow_plugins=True)


def test_plugin_files_run_only_when_allowed():
    with pytest.raises(ScenarioError, match="allow-plugins"):
        netsim.run(LOOP, allow_plugins=False)


def test_the_custom_plant_and_controller_settle_at_the_tank_equilibrium(tank):
    assert tank.ok
    level, pump = tank.signal("level"), tank.signal("pump")
    assert level.iloc[-1] == pytest.approx(1.0, abs=1e-3)  # integral action: no steady-state error
    # equilibrium of A h' = k u - a sqrt(2 g h) at h = 1 m: u = (a / k) sqrt(2 g) = 0.1 * sqrt(19.62)
    assert pump.iloc[-1] == pytest.approx(0.1 * math.sqrt(2 * 9.81), abs=1e-3)
    # the pump command saturates at 1 early on and the integrator does not wind up: at most a 5 % overshoot
    assert pump.max() == 1.0 and level.max() < 1.05


def test_the_custom_medium_gives_each_frame_one_slot_on_the_slot_grid(tank):
    msgs = tank.messages
    assert len(msgs) == 300 and not msgs["dropped"].any()
    # the sensor sends at k s + 1 ms (its execution time); the frame waits for the next 50 ms slot boundary and
    # occupies that slot: delivered at k s + 100 ms, a delay of 99 ms
    np.testing.assert_allclose(msgs["tx_start_s"] % 1.0, 0.05, atol=1e-12)
    np.testing.assert_allclose(msgs["delay_s"], 0.099, atol=1e-12)
    assert tank.metrics["net.bus.utilization"] == pytest.approx(300 * 0.05 / 300.0)  # one 50 ms slot per second


def test_the_plugins_show_their_parameters_like_builtin_ones(tank):
    from netsim import registry

    rows = {r.name: r for r in registry.param_rows(registry.params_model(registry.lookup("plant", "water_tank")))}
    assert rows["area"].default == "1.0" and "m^2" in rows["area"].description
    slot = {r.name: r for r in registry.param_rows(registry.lookup("network", "slotted_bus").Params)}["slot"]
    assert slot.unit == registry.TIME_UNIT and slot.default == "1 ms"
