"""A plugin position names a registered plugin, never an arbitrary callable or module (issue 14 A)."""

from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

from netsim.scenario import check_scenario

#: (YAML path of the plugin position, how to put a name there)
POSITIONS = [
    ("plant.model", lambda raw, v: raw["plant"].update(model=v)),
    ("signals.r.type", lambda raw, v: raw["signals"]["r"].update(type=v)),
    ("nodes.computer.tasks[0].program", lambda raw, v: raw["nodes"]["computer"]["tasks"][0].update(program=v)),
    ("metrics[0].type", lambda raw, v: raw["metrics"][0].update(type=v)),
    ("nodes.computer.policy", lambda raw, v: raw["nodes"]["computer"].update(policy=v)),
    ("networks.net.type", lambda raw, v: raw.update(networks={"net": {"type": v, "nodes": ["computer"]}})),
]


@pytest.fixture
def calls(monkeypatch):
    """Replace subprocess.Popen, os.system and shutil.rmtree by recorders (the same names, in their modules)."""
    seen = []

    def recorder(name):
        def fn(*args, **kwargs):
            seen.append(name)
        return fn

    monkeypatch.setattr(subprocess, "Popen", recorder("Popen"))
    monkeypatch.setattr("os.system", recorder("system"))
    monkeypatch.setattr(shutil, "rmtree", recorder("rmtree"))
    return seen


def _errors(raw):
    return {p.path: p.message for p in check_scenario(raw) if p.is_error}


@pytest.mark.parametrize("where,put", POSITIONS, ids=[p[0] for p in POSITIONS])
@pytest.mark.parametrize("target", ["subprocess:Popen", "os:system", "shutil:rmtree"])
def test_an_arbitrary_callable_is_refused_without_being_called(scenario, calls, where, put, target):
    raw = scenario()
    put(raw, target)
    errors = _errors(raw)
    assert where in errors, errors
    assert "registered" in errors[where]
    assert calls == []


@pytest.mark.parametrize("where,put", POSITIONS, ids=[p[0] for p in POSITIONS])
def test_a_module_is_not_imported_to_resolve_a_path(tmp_path, monkeypatch, scenario, where, put):
    marker = tmp_path / "imported"
    (tmp_path / "zzt_sec_side_effect.py").write_text(f"open({str(marker)!r}, 'w').close()\nclass Thing: pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    raw = scenario()
    put(raw, "zzt_sec_side_effect:Thing")
    errors = _errors(raw)
    assert "netsim does not import" in errors.get(where, ""), errors
    assert not marker.exists()
    assert "zzt_sec_side_effect" not in sys.modules


def test_a_standard_module_not_yet_imported_stays_unimported(scenario):
    # 'this' prints the Zen of Python when imported: a visible side effect of a module nobody imports
    assert "this" not in sys.modules
    raw = scenario()
    raw["plant"]["model"] = "this:s"
    assert "netsim does not import" in _errors(raw)["plant.model"]
    assert "this" not in sys.modules


def test_run_refuses_the_same_without_calling(tmp_path, scenario, calls):
    from netsim.runner import run
    from netsim.scenario import ScenarioError

    raw = scenario()
    raw["metrics"][0]["type"] = "os:system"
    with pytest.raises(ScenarioError, match="registered"):
        run(raw, out=tmp_path / "run")
    assert calls == [] and not (tmp_path / "run").exists()


def test_a_registered_class_may_still_be_named_by_its_path(scenario):
    raw = scenario()
    raw["nodes"]["computer"]["policy"] = "netsim.kernel.policies:FixedPriority"  # a Policy subclass
    assert _errors(raw) == {}


def test_an_abstract_base_class_is_refused_at_validate(scenario):
    # it passed validate and raised TypeError (a traceback) when the run built the kernel
    raw = scenario()
    raw["nodes"]["computer"]["policy"] = "netsim.kernel.policies:Policy"
    assert "abstract base class" in _errors(raw)["nodes.computer.policy"]
