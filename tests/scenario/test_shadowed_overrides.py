"""An override of a preset-like field that the scenario's own fields hide is applied or refused, never silently
ignored (issue 26 section 7: ``--set plant.params.friction.model=modes6`` on cart.yaml changed nothing)."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any, Literal

import pytest
from pydantic import Field, model_validator

from netsim.cli import main
from netsim.registry import register
from netsim.scenario import ScenarioError, check_scenario, load_scenario
from netsim.scenario.safe_yaml import load_file
from netsim.units import StrictModel

ROOT = Path(__file__).resolve().parents[2]
CART = ROOT / "scenarios" / "cart.yaml"
FRICTION = "plant.params.friction"

# the presets as models/cart/friction.py's docstring states them
MODES6 = {"variation": 0.3, "wavelength": 0.1, "speedup": 3.0, "modes": 6, "spread": 0.5}
INBAND = {"variation": 0.3, "wavelength": 3.3, "speedup": 9.0, "modes": 1, "spread": 0.1}


def _friction(scenario: Any) -> dict[str, Any]:
    return scenario.plant.validated_params().friction.model_dump()


def _cart() -> dict[str, Any]:
    raw, _ = load_file(CART)
    return raw


def test_cart_yaml_spells_out_the_inband_preset() -> None:
    """The situation of the issue: the file gives every preset field, with inband's values."""
    given = _cart()["plant"]["params"]["friction"]
    assert {k: given[k] for k in INBAND} == INBAND


@pytest.mark.parametrize("preset, fields", [("modes6", MODES6),
                                            ("constant", {"variation": 0.0, "wavelength": 1.0, "speedup": 0.0,
                                                          "modes": 1, "spread": 0.0})])
def test_a_preset_override_takes_effect_over_fields_that_spell_out_the_old_preset(preset: str,
                                                                                  fields: dict[str, Any]) -> None:
    friction = _friction(load_scenario(CART, {f"{FRICTION}.model": preset}))
    assert friction["model"] == preset
    assert {k: friction[k] for k in fields} == fields
    assert friction["coulomb"] == 2.0  # not a preset field: as the file gives it


def test_the_cli_set_takes_effect(tmp_path: Path) -> None:
    """``netsim run --set`` goes through load_scenario: the resolved scenario.yaml of a run shows modes6."""
    out = tmp_path / "run"
    code = main(["run", str(CART), "--set", f"{FRICTION}.model=modes6", "--set", "duration=20 ms", "--out", str(out),
                 "--quiet"])
    assert code == 0
    written, _ = load_file(out / "scenario.yaml")
    friction = written["plant"]["params"]["friction"]
    assert friction["model"] == "modes6" and {k: friction[k] for k in MODES6} == MODES6


def test_a_preset_override_hidden_by_a_field_of_the_files_own_is_refused(tmp_path: Path) -> None:
    raw = _cart()
    raw["plant"]["params"]["friction"]["wavelength"] = 2.0  # not inband's 3.3: the file's own choice
    problems = check_scenario(raw, {f"{FRICTION}.model": "modes6"})
    assert [p.path for p in problems] == [f"{FRICTION}.model"]
    message = problems[0].message
    assert "shadowed" in message and "wavelength: 2.0" in message
    assert f"{FRICTION}.wavelength=0.1" in message  # what modes6 would give it
    assert "speedup" not in message  # spelled out as inband: follows the override, not in the way
    with pytest.raises(ScenarioError):
        load_scenario(raw, {f"{FRICTION}.model": "modes6"})


def test_the_cli_refuses_a_hidden_preset_override_with_its_line(tmp_path: Path, capsys: Any) -> None:
    text = CART.read_text(encoding="utf-8").replace("wavelength: 3.3", "wavelength: 2.0")
    assert "wavelength: 2.0" in text
    path = tmp_path / "cart_own.yaml"
    path.write_text(text, encoding="utf-8")
    code = main(["validate", str(path), "--set", f"{FRICTION}.model=modes6"])
    err = capsys.readouterr()
    assert code != 0
    line = next(i for i, row in enumerate(text.splitlines(), 1) if row.strip().startswith("friction:"))  # the friction mapping's line
    assert f"{path}:{line}: {FRICTION}.model:" in err.out + err.err


def test_overriding_the_hiding_field_too_is_accepted() -> None:
    raw = _cart()
    raw["plant"]["params"]["friction"]["wavelength"] = 2.0
    friction = _friction(load_scenario(raw, {f"{FRICTION}.model": "modes6", f"{FRICTION}.wavelength": 0.5}))
    assert friction["wavelength"] == 0.5 and friction["modes"] == 6 and friction["speedup"] == 3.0


def test_replacing_the_whole_mapping_is_plain() -> None:
    friction = _friction(load_scenario(CART, {FRICTION: {"model": "modes6"}}))
    assert {k: friction[k] for k in MODES6} == MODES6 and friction["coulomb"] == 2.0  # coulomb: the default


def test_a_baseline_override_of_the_preset_takes_effect() -> None:
    raw = _cart()
    raw["baseline"] = {"overrides": {f"{FRICTION}.model": "modes6"}}
    scenario = load_scenario(raw)
    assert _friction(scenario)["wavelength"] == 3.3
    assert {k: _friction(scenario.baseline_scenario())[k] for k in MODES6} == MODES6


def test_a_hidden_baseline_override_is_refused() -> None:
    raw = _cart()
    raw["plant"]["params"]["friction"]["spread"] = 0.2
    raw["baseline"] = {"overrides": {f"{FRICTION}.model": "modes6"}}
    problems = check_scenario(raw)
    assert [p.path for p in problems] == ["baseline.overrides"]
    assert "spread: 0.2" in problems[0].message and "shadowed" in problems[0].message


# ------------------------------------------------------------------------------------------ any preset-like field
class _PresetParams(StrictModel):
    """A plant with a preset (``shape``) filling ``pole`` and ``gain``, and a number (``tau``) that gives the
    default of ``lag``."""

    shape: Literal["slow", "fast"] = "slow"
    pole: float = Field(1.0, gt=0)
    gain: float = 1.0
    tau: float = 1.0
    lag: float | None = None

    @model_validator(mode="before")
    @classmethod
    def _preset(cls, data: Any) -> Any:
        if isinstance(data, dict):
            data = {**({"pole": 10.0, "gain": 3.0} if data.get("shape") == "fast" else {"pole": 1.0, "gain": 1.0}),
                    **data}
            data.setdefault("lag", 2.0 * data.get("tau", 1.0))
        return data


@register("plant", "zzt_preset_plant", "test plant with a preset field")
class ZztPresetPlant:
    input_names = ["u", "d"]
    output_names = ["y"]
    Params = _PresetParams


def _with_plant(base: Any, params: dict[str, Any]) -> dict[str, Any]:
    raw = base()
    raw["plant"] = {"model": "zzt_preset_plant", "params": copy.deepcopy(params)}
    return raw


def test_any_plugin_preset_hidden_by_its_own_values_is_refused(base: Any) -> None:
    raw = _with_plant(base, {"shape": "slow", "pole": 5.0})
    problems = check_scenario(raw, {"plant.params.shape": "fast"})
    assert [p.path for p in problems] == ["plant.params.shape"]
    assert "pole: 5.0" in problems[0].message and "plant.params.pole=10.0" in problems[0].message


def test_a_preset_written_inline_is_checked_too(base: Any) -> None:
    raw = base()
    raw["plant"] = {"type": "zzt_preset_plant", "shape": "slow", "gain": 2.0}
    problems = check_scenario(raw, {"plant.shape": "fast"})
    assert [p.path for p in problems] == ["plant.shape"]
    assert "gain: 2.0" in problems[0].message and "plant.gain=3.0" in problems[0].message


def test_any_plugin_preset_spelled_out_follows_the_override(base: Any) -> None:
    raw = _with_plant(base, {"pole": 1.0, "gain": 1.0})  # the slow preset written out, shape left at its default
    params = load_scenario(raw, {"plant.params.shape": "fast"}).plant.validated_params()
    assert (params.pole, params.gain) == (10.0, 3.0)


def test_a_number_that_moves_a_default_is_not_a_preset(base: Any) -> None:
    """``tau`` is a value in its own right: an explicit ``lag`` stays as given (as a task's explicit deadline
    stays when its period is overridden)."""
    raw = _with_plant(base, {"tau": 1.0, "lag": 2.0})
    params = load_scenario(raw, {"plant.params.tau": 4.0}).plant.validated_params()
    assert (params.tau, params.lag) == (4.0, 2.0)
