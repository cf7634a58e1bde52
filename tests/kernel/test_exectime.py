"""Execution-time models and their YAML specs."""

from __future__ import annotations

import numpy as np
import pytest

from netsim.errors import ConfigError
from netsim.kernel import ExecTime
from netsim.timebase import US


def rng():
    return np.random.Generator(np.random.PCG64(12345))


def test_from_spec_constant_string_and_seconds():
    assert ExecTime.from_spec("0.5 ms").draw(rng()) == 500 * US
    with pytest.raises(ConfigError, match="add a unit"):  # issue 13 C: a bare number is refused, not seconds
        ExecTime.from_spec(0.002)
    assert ExecTime.from_spec({"dist": "constant", "value": "3 us"}).draw(rng()) == 3 * US


def test_uniform_draws_stay_in_bounds_and_cover_them():
    et = ExecTime.from_spec({"dist": "uniform", "low": "0.4 ms", "high": "0.6 ms"})
    g = rng()
    draws = np.array([et.draw(g) for _ in range(4000)])
    assert draws.min() >= 400 * US and draws.max() <= 600 * US
    # mean of U[0.4, 0.6] ms is 0.5 ms; standard error ~ 0.2/sqrt(12)/sqrt(4000) ms ~ 0.9 us
    assert abs(draws.mean() - 500 * US) < 5 * US


def test_normal_is_clipped_to_min_and_max():
    et = ExecTime.from_spec({"dist": "normal", "mean": "1 ms", "std": "1 ms", "min": "0.5 ms", "max": "1.2 ms"})
    g = rng()
    draws = np.array([et.draw(g) for _ in range(2000)])
    assert draws.min() == 500 * US and draws.max() == 1200 * US


def test_empirical_draws_only_given_values():
    et = ExecTime.from_spec({"dist": "empirical", "values": ["1 us", "2 us", "5 us"]})
    g = rng()
    assert {et.draw(g) for _ in range(300)} == {1 * US, 2 * US, 5 * US}


def test_function_model_depends_on_job_data():
    class FakeJob:
        data = 7

    et = ExecTime.function(lambda job: job.data * US)
    assert et.draw(rng(), FakeJob()) == 7 * US


def test_same_stream_same_draws():
    et = ExecTime.uniform(0, 10**6)
    assert [et.draw(rng()) for _ in range(3)] == [et.draw(rng()) for _ in range(3)]


@pytest.mark.parametrize(
    ("spec", "match"),
    [
        ({"dist": "unifrom", "low": 1, "high": 2}, "did you mean 'uniform'"),
        ({"dist": "uniform", "low": "1 ms"}, "needs 'high'"),
        ({"dist": "uniform", "lo": "1 ms", "high": "2 ms"}, "did you mean 'low'"),
        ({"dist": "uniform", "low": "2 ms", "high": "1 ms"}, "low <= high"),
        ({"dist": "empirical", "values": []}, "at least one"),
        ("1 msec", "did you mean 'ms'"),
        (None, "missing"),
    ],
)
def test_bad_specs_are_reported(spec, match):
    with pytest.raises(ConfigError, match=match):
        ExecTime.from_spec(spec)
