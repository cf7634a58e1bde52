"""``netsim list KIND NAME`` prints one plugin's parameters (types, defaults, units) from its ``Params`` model."""

from __future__ import annotations

import re

from pydantic import Field

from netsim.cli import main
from netsim.registry import TIME_UNIT, param_rows, register
from netsim.units import Duration, StrictModel


class _Gains(StrictModel):
    kp: float = Field(1.5, json_schema_extra={"unit": "V/rad"}, description="proportional gain")
    poles: list[float] = Field(default_factory=lambda: [0.5, 0.25])


@register("controller", "zzl_law", "list test: a law with a nested model")
class _Law:
    class Params(StrictModel):
        wc: float = Field(json_schema_extra={"unit": "rad/s"}, description="crossover\n   frequency")
        period: Duration | None = None
        gains: _Gains = Field(default_factory=_Gains)
        mode: str = "fast"


def _rows(text: str) -> dict[str, list[str]]:
    """The parameter table: name -> [type, default, unit, description] (columns are 2+ spaces apart)."""
    lines = text.splitlines()
    start = lines.index("parameters:") + 2  # the header line follows
    rows = {}
    for line in lines[start:]:
        if not line.startswith("  "):
            break
        cells = re.split(r"\s{2,}", line.strip())
        rows[cells[0]] = cells[1:]
    return rows


def test_a_network_lists_its_parameters_with_types_defaults_and_units(capsys):
    assert main(["list", "network", "can"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0] == "can (network): CAN bus (CSMA/AMP): priority arbitration, non-preemptive frames"
    assert "defined in: netsim.network.can:CanBus" in out
    rows = _rows(out)
    assert rows["bitrate"][:3] == ["bit rate", "required", "bit/s"]
    assert rows["pre_delay"][:3] == ["time", "0 ns", TIME_UNIT]
    assert rows["utilization_bin"][:3] == ["duration", "10 ms", TIME_UNIT]
    assert rows["queue_discipline"] == ["'fifo' | 'priority'", "'priority'"]  # CAN's own default (fifo elsewhere)
    assert "times are written with their unit: 20 us, 1.5 ms, 2 s" in out


def test_a_program_lists_literal_choices_and_descriptions(capsys):
    assert main(["list", "programs", "et_sensor"]) == 0
    rows = _rows(capsys.readouterr().out)
    assert rows["trigger"] == ["'time' | 'pet' | 'send_on_delta'", "'pet'"]
    assert rows["k_max"] == ["int | null", "null", "safety condition eq (7): send at least every k_max periods"]
    assert rows["period"][:2] == ["duration", "required"]


def test_declared_units_nested_models_and_factories_are_shown(capsys):
    assert main(["list", "controller", "zzl_law"]) == 0
    rows = _rows(capsys.readouterr().out)
    assert rows["wc"] == ["float", "required", "rad/s", "crossover frequency"]
    assert rows["period"] == ["duration | null", "null", TIME_UNIT]
    assert rows["gains"] == ["_Gains", "{'kp': 1.5, 'poles': [0.5, 0.25]}"]
    assert rows["gains.kp"] == ["float", "1.5", "V/rad", "proportional gain"]
    assert rows["gains.poles"] == ["list[float]", "[0.5, 0.25]"]
    assert list(rows) == ["wc", "period", "gains", "gains.kp", "gains.poles", "mode"]


def test_param_rows_match_the_model_field_for_field():
    rows = param_rows(_Law.Params)
    assert [r.name for r in rows] == ["wc", "period", "gains", "gains.kp", "gains.poles", "mode"]
    assert rows[-1].default == "'fast'" and rows[-1].unit == ""


def test_an_alias_shows_the_name_asked_for_and_the_other_names(capsys):
    assert main(["list", "network", "ideal"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("ideal (network): ideal link")
    assert lines[1] == "also named: link"


def test_a_plugin_without_params_says_so(capsys):
    assert main(["list", "policy", "edf"]) == 0
    assert "parameters: none declared (it has no Params model)" in capsys.readouterr().out


def test_an_unknown_plugin_name_is_a_usage_error_with_a_suggestion(capsys):
    assert main(["list", "network", "cann"]) == 2
    assert capsys.readouterr().err == "netsim: error: unknown network 'cann'; did you mean 'can'?\n"


def test_trigger_is_no_longer_a_kind(capsys):
    assert main(["list", "triggers"]) == 2
    assert "unknown kind 'triggers'" in capsys.readouterr().err
