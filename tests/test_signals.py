"""Signals: values at given instants, jump instants, and parameter errors."""

import math

import pytest

from netsim.errors import ConfigError
from netsim.io.signals import make_signal
from netsim.timebase import MS, S


def test_square_wave_alternates_around_bias_and_lists_its_edges():
    sq = make_signal({"type": "square", "amplitude": 2.0, "period": "10 ms", "bias": 1.0})
    # high (bias + amplitude) for the first half period, low after
    assert sq(0) == 3.0
    assert sq(5 * MS - 1) == 3.0
    assert sq(5 * MS) == -1.0
    assert sq(10 * MS) == 3.0
    assert sq.breakpoints(0, 20 * MS) == [5 * MS, 10 * MS, 15 * MS, 20 * MS]
    assert sq.breakpoints(5 * MS, 12 * MS) == [10 * MS]


def test_square_duty_cycle_moves_the_falling_edge():
    sq = make_signal({"type": "square", "period": "1 s", "duty": 0.25})
    assert sq(249 * MS) == 1.0 and sq(250 * MS) == -1.0
    assert sq.breakpoints(0, 1 * S) == [250 * MS, 1 * S]


def test_step_switches_at_its_instant_and_only_there():
    st = make_signal({"type": "step", "at": "1 s", "value": 0.1, "initial": -0.5})
    assert st(S - 1) == -0.5
    assert st(S) == 0.1
    assert st.breakpoints(0, 2 * S) == [S]
    assert st.breakpoints(S, 2 * S) == []


def test_sine_and_ramp_match_their_formulas():
    si = make_signal({"type": "sine", "amplitude": 2.0, "frequency": 5.0, "phase": 0.3, "bias": 1.0})
    t = 37 * MS
    assert si(t) == pytest.approx(1.0 + 2.0 * math.sin(2 * math.pi * 5.0 * 0.037 + 0.3), rel=1e-12)
    assert not si.piecewise_constant
    ra = make_signal({"type": "ramp", "slope": 4.0, "start": "0.5 s", "initial": 1.0})
    assert ra(100 * MS) == 1.0
    assert ra(750 * MS) == pytest.approx(1.0 + 4.0 * 0.25)


def test_table_holds_or_interpolates():
    held = make_signal({"type": "table", "times": [0, "1 s", "2 s"], "values": [0.0, 1.0, 3.0]})
    assert held(1500 * MS) == 1.0
    assert held(5 * S) == 3.0
    assert held.breakpoints(0, 3 * S) == [S, 2 * S]
    lin = make_signal({"type": "table", "times": [0, "1 s", "2 s"], "values": [0.0, 1.0, 3.0], "interpolation": "linear"})
    assert lin(1500 * MS) == pytest.approx(2.0)
    assert lin.breakpoints(0, 3 * S) == []


def test_constant_and_nested_params_form():
    c = make_signal({"type": "constant", "params": {"value": 4.5}})
    assert c(123) == 4.5


@pytest.mark.parametrize(
    "spec, words",
    [
        ({"type": "squar", "period": "1 s"}, "did you mean 'square'"),
        ({"type": "square"}, "period"),
        ({"type": "square", "period": "1 s", "duty": 1.5}, "duty"),
        ({"type": "step", "at": "1 sec"}, "at"),
        ({"type": "table", "times": [0, "1 s"], "values": [1.0]}, "same length"),
        ({"type": "step", "colour": 3}, "colour"),
    ],
)
def test_bad_signal_specs_raise_config_error_naming_the_problem(spec, words):
    with pytest.raises(ConfigError, match=words):
        make_signal(spec)
