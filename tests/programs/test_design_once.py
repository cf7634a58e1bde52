"""A ``state_feedback`` task is validated once and designed once per run (issue 28, typed estimator and law parts).

Before: the weights sat in a ``dict[str, Any]`` and were validated again at each build; the static dry run of
``netsim validate``, its unstable-loop warning, the real build, the run's warning and ``design.json`` each built
the parts again: ``dc_servo_lqr_kalman`` solved the LQR Riccati equation 3 times and the filter's 3 times per
``netsim run`` and converted the estimator's ``Q`` 3 times. Now the validated parameters carry typed weights
(parsed once, in the scenario's one validation), the design made at validation is the one the run takes, and the
summaries share it.
"""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path
from typing import Any

import pytest

import netsim
from netsim.control import kalman, lqr
from netsim.control.weights import Matrix

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "dc_servo_lqr_kalman.yaml"


@pytest.fixture
def solves(monkeypatch: pytest.MonkeyPatch) -> Counter[str]:
    """Counts the filter DAREs (``kalman.steady_state_prior``), the LQR designs (``lqr.dlqr_gain``) and the
    conversions of the Kalman filter's ``Q`` to its matrix (``check_weight('Q', ...)`` in the filter)."""
    count: Counter[str] = Counter()

    def counted(name: str, real: Any) -> Any:
        def call(*args: Any, **kwargs: Any) -> Any:
            count[name] += 1
            return real(*args, **kwargs)
        return call

    monkeypatch.setattr(kalman, "steady_state_prior", counted("filter DARE", kalman.steady_state_prior))
    monkeypatch.setattr(lqr, "dlqr_gain", counted("LQR DARE", lqr.dlqr_gain))
    real_weight = kalman.check_weight

    def weight(name: str, *args: Any, **kwargs: Any) -> Any:
        count[f"filter {name} conversions"] += 1
        return real_weight(name, *args, **kwargs)

    monkeypatch.setattr(kalman, "check_weight", weight)
    return count


def test_a_run_solves_each_riccati_equation_once_and_parses_each_weight_once(solves: Counter[str],
                                                                             tmp_path: Path) -> None:
    parses = Matrix.parses
    netsim.run(str(SCENARIO), overrides={"duration": "0.1 s"}, out=tmp_path / "run")
    # the scenario's estimator {type: kalman, Q: [0, 0.01], R: 1.0e-6} and law {type: lqr, Q: [1, 0], R: 0.1}:
    # four weights, each parsed once by the one validation of the scenario
    assert Matrix.parses - parses == 4
    # validate's dry run designs the loop, its unstable-loop check summarises it (the time-varying filter's
    # steady-state gain: the filter DARE), the run takes that design, its warning and design.json reuse the summary
    assert solves == {"filter DARE": 1, "LQR DARE": 1, "filter Q conversions": 1, "filter R conversions": 1}
    design = json.loads((tmp_path / "run" / "design.json").read_text(encoding="utf-8"))
    assert design["tasks"]["controller.control"]["estimator"]["dare_prior_covariance"] is not None


def test_a_second_run_of_the_same_loaded_scenario_designs_anew(solves: Counter[str], tmp_path: Path) -> None:
    """The first run's estimator and law have stepped: the second run must not reuse them."""
    from netsim.scenario import load_scenario

    scenario = load_scenario(str(SCENARIO), {"duration": "0.1 s"})
    first = netsim.run(scenario, out=tmp_path / "a")
    second = netsim.run(scenario, out=tmp_path / "b")
    assert solves["LQR DARE"] == 2
    assert first.signals.equals(second.signals)
