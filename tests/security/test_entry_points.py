"""Installed packages bring plugins through ``netsim.plugins`` entry points (issue 14 A)."""

from __future__ import annotations

from importlib import metadata

from netsim import registry
from netsim.scenario import check_scenario


def test_an_entry_point_module_registers_plugins_usable_by_name_and_path(tmp_path, monkeypatch, scenario):
    (tmp_path / "zzt_ep_pkg.py").write_text(
        "from netsim.registry import register\nfrom netsim.programs import Idle\n\n"
        "@register('program', 'zzt_ep_program')\nclass EpProgram(Idle):\n    pass\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    point = metadata.EntryPoint(name="zzt", value="zzt_ep_pkg", group=registry.ENTRY_POINT_GROUP)
    real = metadata.entry_points
    monkeypatch.setattr(metadata, "entry_points",
                        lambda **kw: [point] if kw.get("group") == registry.ENTRY_POINT_GROUP else real(**kw))
    monkeypatch.setattr(registry, "_PLUGINS_LOADED", False)
    monkeypatch.setattr(registry, "_PLUGIN_FAILURES", [])
    monkeypatch.setattr(registry, "_ENTRY_POINT_MODULES", [])
    raw = scenario()
    raw["nodes"]["computer"]["tasks"].append({"name": "extra", "program": "zzt_ep_program", "period": "10 ms",
                                              "priority": 2, "execution": "1 ms"})
    assert [p for p in check_scenario(raw) if p.is_error] == []
    raw["nodes"]["computer"]["tasks"][1]["program"] = "zzt_ep_pkg:EpProgram"  # the same, by its path
    assert [p for p in check_scenario(raw) if p.is_error] == []
