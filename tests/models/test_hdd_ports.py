"""The HDD plant declares its ports (validation reads them instead of building the plant, issue 19)."""

from __future__ import annotations

from netsim.models.hdd import HddPlantParams, hdd_plant


def test_declared_ports_are_the_built_plants() -> None:
    built = hdd_plant(HddPlantParams())
    assert list(built.input_names) == hdd_plant.input_names  # type: ignore[attr-defined]
    assert list(built.output_names) == hdd_plant.output_names  # type: ignore[attr-defined]


def test_validation_names_a_port_the_plant_lacks() -> None:
    from pathlib import Path

    from netsim.scenario.loader import read_yaml
    from netsim.scenario.validate import check_raw

    raw = read_yaml(Path(__file__).resolve().parents[2] / "scenarios" / "hdd_case1.yaml")[0]
    raw["io"]["ys"]["output"] = "z"
    problems = check_raw(raw)[0]
    assert any(p.path == "io.ys.output" and "no output 'z'" in p.message and "y" in p.message for p in problems)
