"""Parameters a program hands to another plugin (a controller design's ``design_params``) are checked at validate."""

from __future__ import annotations

from pathlib import Path

from netsim.scenario import check_scenario

HDD1 = Path(__file__).resolve().parents[2] / "scenarios" / "hdd_case1.yaml"
DP = "nodes.controller.tasks[0].params.design_params"


def _errors(overrides):
    return {p.path: p.message for p in check_scenario(HDD1, overrides) if p.is_error}


def test_design_params_are_checked_with_the_designs_params_model():
    # found by the fuzz test: validate said valid, run failed while building the controller
    errors = _errors({f"{DP}.dob": {"bogus": 1}})
    assert list(errors) == [f"{DP}.dob"], errors


def test_an_unknown_design_param_is_refused_at_its_path():
    errors = _errors({f"{DP}.dobb": True})
    assert f"{DP}.dobb" in errors and "unknown key 'dobb'" in errors[f"{DP}.dobb"]


def test_the_shipped_design_params_are_valid():
    assert _errors({}) == {}
