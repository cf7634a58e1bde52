"""Generated sweep grids give round decimal values, so a point's seed does not hang on numpy's last bit.

Before the fix, a factor's ``logspace``/``linspace`` values were numpy's floats as computed; with the numpy of
this project's venv, ``np.logspace(-9, -1, 11)[5]`` is ``9.999999999999999e-06``, so the ``sigma_s = 1e-5``
row of the HDD Case 4 sweep drew other noise than with a numpy giving ``1e-05``.
"""

from __future__ import annotations

import numpy as np
import pytest

import netsim.sweep.spec as spec_module
from netsim.sweep.spec import SweepSpec, derive_seed, expand_points


def _spec(factor: dict) -> SweepSpec:
    return SweepSpec.model_validate({"sweep": "grid", "base": "case.yaml", "seed": 5, "factors": {"s": {"paths": ["a.b"], **factor}}})


@pytest.mark.parametrize("direction", [-np.inf, np.inf])
def test_logspace_one_ulp_off_gives_the_round_value_and_the_literal_seed(monkeypatch, direction):
    # a numpy whose power function is one unit in the last place off: 10**-5 comes out as the float just
    # below (9.999999999999999e-06, this venv's numpy 2.4) or just above 1e-05
    off = float(np.nextafter(1e-05, direction))
    assert off != 1e-05
    monkeypatch.setattr(spec_module.np, "logspace", lambda *a, **k: np.array([off]))
    point = expand_points(_spec({"logspace": {"start": -5, "stop": -5, "num": 1}}))[0]
    assert repr(point.values["s"]) == "1e-05"
    literal = expand_points(_spec({"values": [1e-05]}))[0]
    assert point.seed == literal.seed == derive_seed(5, {"s": 1e-05}, 0)


def test_logspace_gives_the_round_decimals_with_this_numpy():
    levels = _spec({"logspace": {"start": -9, "stop": -1, "num": 11}}).factors["s"].levels()
    # 10**(-9 + 0.8 i), written to 12 significant digits by hand: 1e-9, 6.30957344480e-9, ...
    assert levels[0] == 1e-09 and levels[5] == 1e-05 and levels[10] == 0.1
    assert levels[1] == 6.3095734448e-09


def test_linspace_values_are_rounded_to_twelve_digits():
    # np.linspace(0, 1, 11)[3] is 0.30000000000000004 (3 * 0.1 in binary); the grid's point is 0.3
    assert np.linspace(0, 1, 11)[3] != 0.3
    levels = _spec({"linspace": {"start": 0, "stop": 1, "num": 11}}).factors["s"].levels()
    assert levels[3] == 0.3
    assert expand_points(_spec({"linspace": {"start": 0, "stop": 1, "num": 11}}))[3].seed == derive_seed(5, {"s": 0.3}, 0)


@pytest.mark.parametrize("value", [0.30000000000000004, 9.999999999999999e-06])
def test_listed_values_are_taken_as_given(value):
    point = expand_points(_spec({"values": [value]}))[0]
    assert point.values["s"] == value
    assert point.seed == derive_seed(5, {"s": value}, 0)
