"""A pendulum disturbance std whose variance overflows a float is refused with what to write (fuzz figures).

``1e308 ** 2`` overflows a float (the largest is about 1.8e308), so the plant and the Kalman design cannot square
it; before, validate printed ``cannot build plant 'furuta_pendulum': (34, 'Numerical result out of range')``.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from netsim.models.pendulum.model import discretise, furuta_pendulum, PendulumParams, process_noise_cov
from netsim.errors import ConfigError
from netsim.scenario.loader import check_scenario
from tests.fuzz.mutations import message_has_fix

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "pendulum_lqr.yaml"


def test_a_huge_plant_disturbance_std_gets_one_message_at_its_path_with_a_fix():
    raw = yaml.safe_load(SCENARIO.read_text())
    raw["plant"]["params"]["disturbance_std"] = 1e308
    errs = [(p.path, p.message) for p in check_scenario(raw) if p.severity == "error"]
    assert [p for p, _ in errs] == ["plant.params.disturbance_std"], errs
    assert all(message_has_fix(m) for _, m in errs)


def test_the_plant_factory_refuses_an_overflowing_std_at_its_path():
    with pytest.raises(ConfigError) as info:
        furuta_pendulum(disturbance_std=1e200)
    assert info.value.path == "plant.params.disturbance_std"
    assert "write a std of at most 1e+15 V" in info.value.message


def test_the_kalman_noise_design_refuses_an_overflowing_std_with_a_fix():
    lin = discretise(PendulumParams(), h=0.005)
    with pytest.raises(ConfigError, match="variance too large for a float; write a std of at most"):
        process_noise_cov(lin, std=1e200, hold=0.001)
