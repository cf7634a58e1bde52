"""The growth and bound checks of netsim.results.verdict on synthetic error signals: an unstable loop (exponential growth,
a growing oscillation) is found; a converging loop, a step response, a square-wave reference, a bounded limit
cycle, noise and a rise from rest are not (issue 26 section 1)."""

from __future__ import annotations

import types

import numpy as np
import pandas as pd
import pytest

from netsim.scenario.schema_verdict import VerdictSettings
from netsim.status import EXIT_FAILED, UNSTABLE, count_statuses, kind_of
from netsim.timebase import S
from netsim.results.verdict import apply_finding, find_growth, judge_signals, window_envelope

T_END = 2.0  # s: the default window is 2 s / 20 = 0.1 s
T = np.round(np.arange(0.0, T_END + 1e-9, 1e-3), 9)  # 1 ms record grid


def _judge(r: np.ndarray, y: np.ndarray, verdict: object = None, extra: dict | None = None):
    """judge_signals on a run whose signals table holds r and y, with a control_error metric on them."""
    cols = {"time_s": T, "r": r, "y": y, **(extra or {})}
    result = types.SimpleNamespace(signals=pd.DataFrame(cols))
    scenario = types.SimpleNamespace(
        metrics=[types.SimpleNamespace(type="control_error", params={"reference": "r", "output": "y"})],
        verdict=verdict, duration=int(T_END * S))
    return judge_signals(result, scenario, int(T_END * S))


def _square(period: float = 1.0) -> np.ndarray:
    return np.where((T % period) < period / 2, 1.0, -1.0)


def test_a_loop_whose_error_grows_exponentially_is_unstable():
    # the levitated ball: 0.5 mm growing to 330 mm in 1 s is exp(6.5 t); here over the second half
    y = np.where(T < 1.0, 0.5, 0.5 * np.exp(6.5 * (T - 1.0)))
    found, notes = _judge(np.zeros_like(T), y)
    assert found is not None and not notes
    # the envelope passes the loop's scale 0.5 (|y(0)|) right after t = 1 s, where the growth starts
    assert 1.0 < found.t_s < 1.05
    assert "the error r - y grew" in found.text


def test_a_growing_oscillation_slower_than_the_window_is_unstable():
    # 2 Hz oscillation (|y| peaks every 0.25 s: a 0.1 s window often holds no peak) growing 7.4x per second
    # (exp(2 t): 1.22x per 0.1 s, above the default 1.15): the 0.4 s windows see it
    y = 0.2 * np.exp(2.0 * T) * np.sin(2 * np.pi * 2.0 * T)
    found, _ = _judge(np.zeros_like(T), y)
    assert found is not None


def test_a_converging_loop_is_not_flagged():
    y = 1.0 - np.exp(-5 * T) * np.cos(20 * T)  # damped step response to r = 1
    assert _judge(np.ones_like(T), y)[0] is None


def test_a_step_response_from_rest_to_a_new_level_is_not_flagged():
    r = np.where(T >= 0.3, 2.0, 0.0)
    y = np.where(T >= 0.3, 2.0 * (1 - np.exp(-8 * (T - 0.3))), 0.0)
    assert _judge(r, y)[0] is None


def test_a_square_wave_reference_is_not_flagged():
    r = _square()
    # a first-order loop (time constant 50 ms) that settles after each edge, with a small noise floor
    y = np.empty_like(T)
    y[0] = 0.0
    for k in range(1, len(T)):
        y[k] = y[k - 1] + (r[k - 1] - y[k - 1]) * (1 - np.exp(-1e-3 / 0.05))
    y += np.random.default_rng(1).normal(0, 1e-4, len(T))
    assert _judge(r, y)[0] is None


def test_a_bounded_limit_cycle_is_not_flagged():
    y = 0.05 * np.sign(np.sin(2 * np.pi * 7.0 * T))  # a relay-like cycle about r = 0, present from the start
    assert _judge(np.zeros_like(T), y)[0] is None


def test_noise_about_the_reference_is_not_flagged():
    y = 1.0 + np.random.default_rng(2).normal(0, 0.01, len(T))
    assert _judge(np.ones_like(T), y)[0] is None


@pytest.mark.parametrize("tau", [0.05, 0.2, 1.0, 5.0])
def test_a_rise_from_rest_to_an_offset_is_not_flagged(tau):
    # a load disturbance at t = 0 on a loop without integral action: the error rises to an offset of 3 (above the
    # reference 1) along 1 - exp(-t / tau); the longest tau is nearly a ramp over the run
    y = 1.0 - 3.0 * (1 - np.exp(-T / tau))
    assert _judge(np.ones_like(T), y)[0] is None


def test_a_ramp_from_rest_is_not_flagged():
    assert _judge(np.zeros_like(T), 5.0 * T + 1e-3)[0] is None


def test_growth_that_comes_back_is_a_transient_not_an_instability():
    # grows 20x over half a second, then decays back to where it began
    bump = np.exp(-((T - 1.0) / 0.25) ** 2)
    y = 0.05 + 0.95 * bump
    assert _judge(np.zeros_like(T), y)[0] is None


def test_the_growth_thresholds_are_the_scenario_s():
    # exp(1.2 t): 1.13x per 0.1 s window, below the default 1.15, found with growth_ratio 1.1
    y = 0.5 * np.exp(1.2 * T)
    assert _judge(np.zeros_like(T), y)[0] is None
    assert _judge(np.zeros_like(T), y, VerdictSettings(growth_ratio=1.1))[0] is not None
    assert _judge(np.zeros_like(T), 0.5 * np.exp(6.5 * T), VerdictSettings(growth=False))[0] is None


def test_a_bound_is_a_signal_leaving_its_operating_region_at_its_first_sample_past_it():
    alpha = np.where(T < 0.7, 0.01, 3.0)  # bounded, but fallen at t = 0.7 s
    found, _ = _judge(np.zeros_like(T), np.zeros_like(T), VerdictSettings(bound={"alpha": 1.0}), {"alpha": alpha})
    assert found is not None and found.t_s == pytest.approx(0.7)
    assert "verdict.bound.alpha" in found.text


def test_a_verdict_name_nothing_recorded_is_a_warning():
    _, notes = _judge(np.zeros_like(T), np.zeros_like(T), VerdictSettings(bound={"alpah": 1.0}, signals=["yy"]))
    assert any("verdict.bound.alpah" in n for n in notes) and any("verdict.signals" in n for n in notes)


def test_verdict_false_switches_every_check_off():
    from pydantic import TypeAdapter

    from netsim.scenario.schema_verdict import VerdictSpec

    off = TypeAdapter(VerdictSpec).validate_python(False)
    assert not off.growth and not off.metrics
    assert TypeAdapter(VerdictSpec).validate_python("off") == off


def test_window_envelope_is_the_largest_magnitude_per_window():
    t = np.array([0, 1, 5, 10, 12, 19, 25], dtype=np.int64)
    v = np.array([1.0, -3.0, 2.0, np.nan, -0.5, 0.25, 9.0])
    env = window_envelope([(t[:3], v[:3]), (t[3:], v[3:])], 10, 2)
    assert env.tolist() == [3.0, 0.5]  # 25 is past the second window


def test_find_growth_needs_the_growth_to_pass_the_scale():
    env = np.array([1e-3, 2e-3, 4e-3, 8e-3, 1.6e-2, 3.2e-2])  # doubling, but far below the loop's scale 1
    assert find_growth(env, 1.0, 4, 1.15) is None
    assert find_growth(env, 1e-2, 4, 1.15) is not None


def test_an_unstable_status_is_not_ok_and_fails_the_command():
    meta = {"status": "ok", "error": "", "warnings": []}
    scenario = types.SimpleNamespace(verdict=None)
    apply_finding(meta, types.SimpleNamespace(t_s=0.25, text="grew"), scenario)
    assert meta["status"] == "unstable at t = 0.25 s" and meta["error"] == "grew"
    assert kind_of(meta["status"]) == UNSTABLE
    counts = count_statuses(["ok", meta["status"]])
    assert counts.exit_code() == EXIT_FAILED and counts.describe("scenario") == "1 of 2 scenarios ok, 1 unstable"


def test_action_warn_keeps_the_status_and_adds_a_warning():
    meta = {"status": "ok", "error": "", "warnings": []}
    apply_finding(meta, types.SimpleNamespace(t_s=0.25, text="grew"), types.SimpleNamespace(
        verdict=VerdictSettings(action="warn")))
    assert meta["status"] == "ok" and meta["warnings"][0].startswith("unstable at t = 0.25 s: grew")
