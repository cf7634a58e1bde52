"""An io channel's ``saturation: [low, high]`` with an integer too large for a float is refused at its path.

Found by tests/fuzz: pendulum_lqr with a huge integer in ``io.u.saturation[1]`` crashed ``netsim validate`` with
"OverflowError: int too large to convert to float" (the schema's [low, high] check converted it to a float).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from netsim.scenario import check_scenario

ROOT = Path(__file__).resolve().parents[2]
HUGE = 10**400  # beyond a double's range (about 1.8e308): float(HUGE) raises OverflowError


def _errors(file: str, overrides: dict) -> list[tuple[str, str]]:
    return [(p.path, p.message) for p in check_scenario(ROOT / "scenarios" / file, overrides) if p.is_error]


@pytest.mark.parametrize(("value", "index"), [([-3, HUGE], 1), ([-HUGE, 3], 0), ([HUGE, HUGE + 1], 0)])
def test_a_dac_saturation_bound_too_large_for_a_float_is_refused_at_its_index(value, index):
    errors = _errors("pendulum_lqr.yaml", {"io.u.saturation": value})
    assert errors[0] == (f"io.u.saturation[{index}]", "an integer of 401 digits is beyond netsim's limit for "
                                                      "numbers (|x| <= 1e+15); write a smaller value")
    assert all(path.startswith("io.u.saturation[") for path, _ in errors)


def test_an_adc_saturation_bound_too_large_for_a_float_is_refused_at_its_index():
    assert _errors("dc_servo_flexray.yaml", {"io.y.saturation": [0, HUGE]}) == [
        ("io.y.saturation[1]", "an integer of 401 digits is beyond netsim's limit for numbers (|x| <= 1e+15); "
                               "write a smaller value")]
