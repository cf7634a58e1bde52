"""netsim.distributions: one family of random times for execution times, jitter, inter-arrivals and link delays."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import TypeAdapter

from netsim.distributions import (Constant, Distribution, DistributionSpec, Empirical, Exponential, Normal,
                                  ShiftedGamma, Uniform)
from netsim.kernel import ExecTime
from netsim.network.link import Link
from netsim.scenario.schema import TaskSpec
from netsim.timebase import MS, US

SPEC = TypeAdapter(DistributionSpec)

FORMS = [
    ("2 ms", Constant),
    ({"dist": "uniform", "low": "1 ms", "high": "3 ms"}, Uniform),
    ({"dist": "normal", "mean": "1 ms", "std": "0.1 ms", "max": "2 ms"}, Normal),
    ({"dist": "exponential", "mean": "2 ms", "shift": "0.5 ms"}, Exponential),
    ({"dist": "shifted_gamma", "shape": 2.0, "scale": "1 ms"}, ShiftedGamma),
    ({"dist": "empirical", "values": ["1 ms", "4 ms"]}, Empirical),
]


@pytest.mark.parametrize(("form", "cls"), FORMS)
def test_execution_jitter_and_link_delay_read_the_same_yaml_into_the_same_family(form, cls):
    task = TaskSpec.model_validate({"name": "t", "program": "idle", "period": "10 ms", "execution": form,
                                    "release_jitter": form})
    delay = Link.Params.model_validate({"nodes": ["a", "b"], "delay": form}).delay
    assert isinstance(task.execution_time(), cls) and isinstance(task.release_jitter, cls) and isinstance(delay, cls)
    assert task.execution_time() == task.release_jitter == delay
    assert ExecTime is Distribution  # the kernel's execution times are the same family


def test_upper_bounds_are_the_largest_draw_or_none_when_unbounded():
    bounds = [SPEC.validate_python(form).upper_bound() for form, _ in FORMS]
    # constant: its value; uniform: high; normal: max; exponential and gamma: unbounded; empirical: largest value
    assert bounds == [2 * MS, 3 * MS, 2 * MS, None, None, 4 * MS]
    assert SPEC.validate_python({"dist": "normal", "mean": "1 ms", "std": "0.1 ms"}).upper_bound() is None


def _rng() -> np.random.Generator:
    return np.random.Generator(np.random.PCG64(7))


def test_draws_are_the_documented_numpy_calls_on_the_given_stream():
    # each expected value computed here from the same numpy call the module's notes name, on an equal stream
    g = _rng()
    assert SPEC.validate_python(FORMS[1][0]).draw(_rng()) == int(g.integers(MS, 3 * MS + 1))
    g = _rng()
    x = 1 * MS + 100 * US * float(g.standard_normal())
    assert SPEC.validate_python(FORMS[2][0]).draw(_rng()) == int(round(min(max(x, 0), 2 * MS)))
    g = _rng()
    assert SPEC.validate_python(FORMS[3][0]).draw(_rng()) == 500 * US + int(round(float(g.exponential(2e6))))
    g = _rng()
    assert SPEC.validate_python(FORMS[4][0]).draw(_rng()) == int(round(g.gamma(2.0, 1e6)))
    g = _rng()
    assert SPEC.validate_python(FORMS[5][0]).draw(_rng()) == [MS, 4 * MS][int(g.integers(0, 2))]
    g = _rng()
    assert SPEC.validate_python("2 ms").draw(g) == 2 * MS and g.bit_generator.state == _rng().bit_generator.state


@pytest.mark.parametrize(("form", "cls"), FORMS)
def test_a_sampler_draws_what_draw_draws(form, cls):
    dist = SPEC.validate_python(form)
    a, b = _rng(), _rng()
    sample = dist.sampler(b)
    assert [dist.draw(a) for _ in range(20)] == [sample() for _ in range(20)]


def test_a_bare_execution_time_resolves_as_the_time_and_inline_empirical_values_alone():
    task = TaskSpec.model_validate({"name": "t", "program": "idle", "period": "10 ms", "execution": "0.5 ms",
                                    "release_jitter": {"dist": "empirical", "values": ["1 ms"]}})
    data = task.model_dump(mode="json")
    assert data["execution"] == "500 us"
    assert data["release_jitter"] == {"dist": "empirical", "values": ["1 ms"]}


def test_a_jitter_read_from_a_missing_file_is_refused_at_its_yaml_path(tmp_path):
    from netsim.scenario import check_scenario

    raw = {"name": "j", "duration": "1 s", "nodes": {"cpu": {"tasks": [
        {"name": "t", "program": "idle", "period": "10 ms", "priority": 1,
         "release_jitter": {"dist": "empirical", "file": str(tmp_path / "none.csv")}}]}}}
    errors = {p.path: p.message for p in check_scenario(raw) if p.severity == "error"}
    assert list(errors) == ["nodes.cpu.tasks[0].release_jitter"] and "does not exist" in errors[list(errors)[0]]


def test_an_execution_time_read_from_a_missing_file_is_refused_by_validate(tmp_path):
    from netsim.scenario import check_scenario, load_scenario

    raw = {"name": "j", "duration": "10 ms", "nodes": {"cpu": {"tasks": [
        {"name": "t", "program": "idle", "period": "10 ms", "priority": 1,
         "execution": {"dist": "empirical", "file": str(tmp_path / "times.csv")}}]}}}
    errors = {p.path: p.message for p in check_scenario(raw) if p.severity == "error"}
    assert list(errors) == ["nodes.cpu.tasks[0].execution"] and "does not exist" in errors[list(errors)[0]]
    (tmp_path / "times.csv").write_text("0.001\n0.003\n")  # seconds, the default unit
    assert load_scenario(raw).nodes["cpu"].tasks[0].execution_time().upper_bound() == 3 * MS
