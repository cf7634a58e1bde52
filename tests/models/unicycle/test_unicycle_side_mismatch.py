"""The cart's side sensor (plant ``side``) and the filter's ``side_model`` disagreeing is warned about, not silent."""

from __future__ import annotations

import logging
from pathlib import Path

import netsim
from netsim.scenario.loader import check_scenario

SCENARIO = Path(__file__).resolve().parents[3] / "scenarios" / "unicycle_ekf.yaml"
MISMATCH = {"plant.params.side": "printed"}  # the filter keeps its default side_model: derived
SHORT = {"duration": "0.2 s"}


def test_validate_warns_at_the_filters_side_model_when_the_plant_differs():
    problems = check_scenario(SCENARIO, MISMATCH)
    warned = [p for p in problems if p.path == "nodes.ekf.tasks[0].params.side_model"]
    assert len(warned) == 1 and warned[0].severity == "warning"
    assert "'derived'" in warned[0].message and "'printed'" in warned[0].message
    assert "plant.params.side" in warned[0].message
    assert not [p for p in problems if p.severity == "error"]


def test_validate_is_quiet_when_they_agree():
    for overrides in ({}, {"plant.params.side": "printed", "nodes.ekf.tasks[0].params.side_model": "printed"}):
        assert not [p for p in check_scenario(SCENARIO, overrides) if "side_model" in p.path]


def test_a_run_logs_the_mismatch_and_keeps_it_in_its_warnings(caplog, tmp_path):
    with caplog.at_level(logging.WARNING):
        r = netsim.run(SCENARIO, overrides={**MISMATCH, **SHORT}, out=tmp_path / "run")
    assert r.status == "ok"  # a warning, not a refusal: the mismatch may be the experiment
    texts = [w for w in r.meta["warnings"] if "side_model" in w]
    assert len(texts) == 1 and "ekf.filter" in texts[0]
    assert any("side_model" in rec.getMessage() for rec in caplog.records)
    assert "side_model" in (tmp_path / "run" / "meta.json").read_text(encoding="utf-8")
    agree = netsim.run(SCENARIO, overrides=SHORT)
    assert not [w for w in agree.meta.get("warnings") or [] if "side_model" in w]
