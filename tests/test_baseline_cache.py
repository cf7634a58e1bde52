"""The runner's in-process baseline cache: shared only where the baseline run is provably the same."""

import logging
from pathlib import Path

import pandas as pd
import pytest
import yaml

import netsim.runner as runner
from netsim.programs.event_triggered import EtController, EtSensor
from netsim.build.builder import build
from netsim.scenario.loader import load_scenario

SCEN = Path(__file__).resolve().parents[1] / "scenarios"
SIGMA_S = "nodes.sensor.handlers[0].params.sigma_s"


@pytest.fixture(autouse=True)
def _empty_cache():
    runner.clear_baseline_cache()
    yield
    runner.clear_baseline_cache()


def _metrics(**kw) -> pd.Series:
    logging.disable(logging.WARNING)
    try:
        return runner.run(SCEN / "hdd_case3.yaml", write=False, **kw).metrics
    finally:
        logging.disable(logging.NOTSET)


def test_cached_baseline_gives_the_metrics_of_a_fresh_one():
    ov = {SIGMA_S: 1e-4}
    runner.run(SCEN / "hdd_case3.yaml", write=False, seed=3)  # fills the cache (other seed, other sigma_s)
    assert len(runner._BASELINES) == 1
    cached = _metrics(seed=11, overrides=ov)
    assert len(runner._BASELINES) == 1  # the point reused the entry: sigma_s is inert in the TTS baseline
    runner.clear_baseline_cache()
    fresh = _metrics(seed=11, overrides=ov)
    pd.testing.assert_series_equal(cached, fresh, check_exact=True)


def test_deterministic_baseline_does_not_use_its_seed_but_a_noisy_one_does():
    quiet = build(load_scenario(SCEN / "hdd_case1.yaml"))
    quiet.run()
    noisy = build(load_scenario(SCEN / "hdd_case4.yaml"))  # measurement noise and disturbance streams
    noisy.run()
    assert not quiet.used_seed()
    assert noisy.used_seed()


def _noisy_baseline(seed: int):
    """hdd_case3 whose baseline keeps a measurement noise (so the baseline run draws random numbers)."""
    raw = yaml.safe_load((SCEN / "hdd_case3.yaml").read_text())
    raw["io"]["ys"]["noise_std"] = 1e-3
    raw["baseline"]["overrides"].pop("io.ys.noise_std")
    raw["seed"] = seed
    return load_scenario(raw).baseline_scenario()


def test_seed_dependent_baseline_is_not_shared_between_seeds():
    b1, b2 = _noisy_baseline(1), _noisy_baseline(2)
    r1 = runner._baseline(b1)
    r2 = runner._baseline(b2)
    (entries,) = runner._BASELINES.values()  # one key (the seed is not part of it) ...
    assert sorted(entries) == [1, 2]  # ... but one entry per seed
    assert not r1.signals["y_meas"].equals(r2.signals["y_meas"])  # different noise draws
    again = runner._baseline(_noisy_baseline(1))
    pd.testing.assert_frame_equal(again.signals, r1.signals, check_exact=True)


def test_canonical_params_reset_only_inert_thresholds():
    assert EtSensor.canonical_params({"trigger": "time", "sigma_s": 0.3, "delta_s": 0.2, "norm": "2"}) == {
        "trigger": "time", "sigma_s": 0.0, "delta_s": 0.0, "norm": "squared"}
    assert EtSensor.canonical_params({"trigger": "pet", "sigma_s": 0.3, "delta_s": 0.2, "norm": "2"})["sigma_s"] == 0.3
    assert EtSensor.canonical_params({"trigger": "send_on_delta", "sigma_s": 0.3, "delta_s": 0.2})["delta_s"] == 0.2
    assert EtController.canonical_params({"controller_et": False, "sigma_c": 0.5, "delta_c": 0.1}) == {
        "controller_et": False, "sigma_c": 0.0, "delta_c": 0.0}
    assert EtController.canonical_params({"controller_et": True, "sigma_c": 0.5})["sigma_c"] == 0.5
    # a value the disabled trigger would still refuse at build time is kept (the build must still fail)
    assert EtController.canonical_params({"controller_et": False, "sigma_c": float("inf")})["sigma_c"] == float("inf")


def test_a_metric_cannot_corrupt_the_cached_baseline():
    sc = load_scenario(SCEN / "hdd_case3.yaml")
    first = runner._baseline(sc.baseline_scenario())
    col = first.signals.columns[1]
    first.signals.loc[:, col] = -123.0  # a careless metric writing into the baseline
    second = runner._baseline(sc.baseline_scenario())
    assert not (second.signals[col] == -123.0).all()
