"""Cost functions of Cuenca et al. eqs (20)-(29) and the et_control metric on hand-made run tables."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from netsim import registry
from netsim.errors import ConfigError
from netsim.metrics.et import (
    computation_saving_pct,
    controller_computation,
    et_control,
    gpi,
    ise,
    isep,
    sampling_efficiency,
    utilization,
)


def test_pure_cost_functions_against_hand_computation():
    assert ise([1, 1, 1], [0, 0.5, 1]) == pytest.approx(np.sqrt(1 + 0.25))
    assert isep([1, 2], [1, 0]) == pytest.approx(2.0)
    assert sampling_efficiency(0.54, 3.75) == pytest.approx(0.144)  # paper Case 2: 0.54/3.75 -> NE 0.14
    assert utilization(250, 464) == pytest.approx(0.5388, abs=1e-4)  # paper Case 2: Uc = 0.54
    assert computation_saving_pct(2, 1) == pytest.approx(33.333, abs=1e-3)  # eq (20), paper: CS = 33 %
    assert controller_computation(1.0, 2, 1) == pytest.approx(66.667, abs=1e-3)  # paper Case 1: Cc = 66 %
    assert controller_computation(0.26, 2, 1) == pytest.approx(17.33, abs=0.01)  # paper Case 3: Cc = 17 %
    assert gpi(0.5, 0.2, 0.1) == pytest.approx(0.45 * 0.5 + 0.45 * 0.2 + 0.1 * 0.1)


def test_bad_weights_and_zero_ise_are_refused():
    with pytest.raises(ConfigError, match="sum"):
        gpi(0.1, 0.1, 0.1, (0.5, 0.5, 0.5))
    with pytest.raises(ConfigError, match="ISE is 0"):
        sampling_efficiency(0.1, 0.0)


def _result(y, tags_times, T=1.0):
    t = np.arange(len(y)) * T
    sig = pd.DataFrame({"time_s": t, "r": np.ones(len(y)), "y": y})
    msgs = pd.DataFrame({"tag": [g for g, _ in tags_times], "sent_s": [s for _, s in tags_times],
                         "dropped": [False] * len(tags_times)})
    return SimpleNamespace(signals=sig, messages=msgs, meta={"duration_s": len(y) * T})


def test_et_control_counts_messages_by_tag_and_compares_with_baseline():
    T = 1.0
    base = _result([0.0, 0.5, 1.0, 1.0], [("y", k + 0.1) for k in range(4)] + [("u", k + 0.2) for k in range(4)])
    run = _result([0.0, 0.5, 0.8, 0.9], [("y", 0.1), ("y", 2.1), ("u", 0.2), ("y", 4.1)])  # 4.1: past N_TTS T
    m = et_control(run, {"period": f"{T} s"}, base)
    assert (m["et.N_TTS"], m["et.Nsc"], m["et.Nca"]) == (4, 2, 1)
    assert m["et.Uc"] == pytest.approx(0.5) and m["et.Ua"] == pytest.approx(0.25)
    assert m["et.ISE"] == pytest.approx(np.sqrt(1 + 0.25))  # the baseline's ISE, eq (23)
    assert m["et.ISEP"] == pytest.approx(np.sqrt(0.04 + 0.01))  # eq (24)
    assert m["et.NE"] == pytest.approx(m["et.ISEP"] / m["et.ISE"])
    assert m["et.Cc"] == pytest.approx(0.5 * (2 / 3) * 100)
    assert m["et.GPI"] == pytest.approx(0.45 * 0.5 + 0.45 * 0.25 + 0.1 * m["et.NE"])


def test_et_control_reports_unknown_parameters_and_missing_signals():
    run = _result([0.0, 1.0], [])
    with pytest.raises(ConfigError, match="unknown key 'sigma'"):
        et_control(run, {"period": "1 s", "sigma": 1}, None)
    with pytest.raises(ConfigError, match="not recorded"):
        et_control(run, {"period": "1 s", "output": "zz"}, None)


ROOT = Path(__file__).resolve().parents[1]


def _errors(path, overrides):
    from netsim.scenario import check_scenario

    return {p.path: p.message for p in check_scenario(path, overrides) if p.is_error}


def test_misspelt_et_control_parameter_is_found_by_validation_before_any_run():
    errors = _errors(ROOT / "scenarios" / "hdd_case2.yaml", {"metrics[0].params.perio": 2e-5})
    assert "metrics[0].params.perio" in errors and "unknown key 'perio'" in errors["metrics[0].params.perio"]


@pytest.mark.parametrize(
    ("weights", "needle"),
    [([0.5, 0.5, 0.5], "sum to 1"), ([1.2, -0.2, 0.0], "must not be negative"), ([0.5, 0.5], "")],
)
def test_et_control_weights_must_be_three_non_negative_numbers_summing_to_one(weights, needle):
    errors = _errors(ROOT / "scenarios" / "hdd_case2.yaml", {"metrics[0].params.weights": weights})
    assert [k for k in errors if k.startswith("metrics[0].params.weights")], errors
    assert needle in " ".join(errors.values())


def test_et_control_period_is_a_time_with_units():
    from netsim.metrics.et import EtControlParams
    from netsim.timebase import US

    assert EtControlParams.model_validate({"period": "20 us"}).period == 20 * US
    with pytest.raises(ValueError, match="add a unit"):  # issue 13 C: bare numbers are refused
        EtControlParams.model_validate({"period": 2e-5})
    with pytest.raises(ValueError):
        EtControlParams.model_validate({"period": "-1 ms"})


def test_every_registered_metric_has_a_params_model():
    from pydantic import BaseModel

    registry.load_plugins()
    # the project's own metrics (tests may register throw-away metrics of their own)
    names = {e.name for e in registry.entries("metric")
             if registry.lookup("metric", e.name).__module__.split(".")[0] in ("netsim", "models")}
    assert {"control_error", "latency", "et_control", "cart"} <= names
    missing = [n for n in sorted(names) if not (isinstance(getattr(registry.lookup("metric", n), "Params", None), type)
                                                and issubclass(registry.lookup("metric", n).Params, BaseModel))]
    assert missing == []


def test_et_control_horizon_measures_from_hand_made_tables():
    # 8 periods of T = 1 s; the actuator's tick records its past-the-packet flag at k + 0.5 (after its
    # execution), the controller records N at arrivals; u packets sent at k = 0, 1, 5
    T = 1.0
    t = np.arange(8) * T + 0.5
    flags = [0, 0, 0, 1, 1, 0, 0, 1]
    N = [1, np.nan, 3, np.nan, np.nan, 4, np.nan, 9]  # 9 at t = 7.5: inside the window
    sig = pd.DataFrame({"time_s": t, "r": 1.0, "y": 0.5, "u_past_end": flags, "N": N})
    msgs = pd.DataFrame({"tag": ["u", "u", "u", "u"], "sent_s": [0.2, 1.2, 5.2, 8.2], "dropped": [False] * 4})
    res = SimpleNamespace(signals=sig, messages=msgs, meta={"duration_s": 8.0})
    m = et_control(res, {"period": f"{T} s"}, None)
    assert m["et.played_past_packet"] == 3.0  # sum of the flags, one per period
    assert m["et.N_max"] == 9.0
    # runs of periods covered by one packet: 1 - 0, 5 - 1, 8 - 5 (the packet sent at 8.2 is past N_TTS)
    assert m["et.u_gap_max"] == 4.0


def test_et_control_leaves_horizon_measures_out_when_not_recorded():
    run = _result([0.0, 1.0], [("y", 0.1)])
    m = et_control(run, {"period": "1 s"}, None)
    assert not {"et.played_past_packet", "et.N_max", "et.u_gap_max"} & set(m)
