"""An io channel's optional ``unit:`` (issue 27 section 4: figure axes name the unit of what a channel reads or
drives): it loads, survives the resolved scenario, and leaves a scenario without units resolved as before."""

from __future__ import annotations

from pathlib import Path

import pytest

from netsim.scenario import dump_resolved, load_scenario, scenario_hash
from netsim.scenario.problems import ScenarioError

SCEN = Path(__file__).resolve().parents[2] / "scenarios" / "pendulum_lqr.yaml"
UNITS = {"io.theta_m.unit": "rad", "io.alpha_m.unit": "rad", "io.u.unit": "V"}
#: the scenario declares these units itself: with each one unset it is the scenario as it was before it had units
NO_UNITS = {path: None for path in UNITS}


def test_a_channel_unit_round_trips_through_the_resolved_scenario(tmp_path: Path) -> None:
    sc = load_scenario(SCEN, overrides=UNITS)
    io = sc.resolved_dict()["io"]
    assert (io["theta_m"]["unit"], io["alpha_m"]["unit"], io["u"]["unit"]) == ("rad", "rad", "V")
    path = tmp_path / "resolved.yaml"
    path.write_text(dump_resolved(sc))
    again = load_scenario(path)
    assert again.resolved_dict() == sc.resolved_dict()
    assert again.io["u"].unit == "V"


def test_an_encoder_takes_a_unit_too() -> None:
    sc = load_scenario(SCEN, overrides={"io.theta_m": {"type": "encoder", "output": "theta", "step": 0.003,
                                                         "tick": "1 ms", "unit": "rad"}})
    assert sc.resolved_dict()["io"]["theta_m"]["unit"] == "rad"


def test_a_scenario_without_units_resolves_without_the_key() -> None:
    # the golden digests and sweep folders hash the resolved scenario: an unset unit must not appear in it
    io = load_scenario(SCEN, overrides=NO_UNITS).resolved_dict()["io"]
    assert all("unit" not in ch for ch in io.values())


def test_a_unit_changes_the_scenario_hash() -> None:
    assert scenario_hash(load_scenario(SCEN, overrides=UNITS)) != scenario_hash(load_scenario(SCEN, overrides=NO_UNITS))


@pytest.mark.parametrize("bad", ["", 5])
def test_an_empty_or_non_text_unit_is_refused_at_its_path(bad: object) -> None:
    with pytest.raises(ScenarioError, match=r"io\.u\.unit"):
        load_scenario(SCEN, overrides={"io.u.unit": bad})
