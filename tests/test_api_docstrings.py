"""The public API's docstrings (issue 27 s2), checked as python-control's docstrings_test.py checks its own: each
public callable's docstring is parsed by numpydoc, every signature parameter is documented with a type (and no
documented parameter is missing from the signature), and there is a Returns and an Examples section. The public
API: every callable in ``netsim.__all__`` and the public methods and properties of ``RunResult``. Their examples
run too (those not marked ``+SKIP``)."""

from __future__ import annotations

import doctest
import inspect
import typing
import warnings
from pathlib import Path

import pandas as pd
import pytest

import netsim
from netsim.results import RunResult

docscrape = pytest.importorskip("numpydoc.docscrape")

ROOT = Path(__file__).resolve().parents[1]


def _public() -> list[tuple[str, object, str]]:
    """``(qualified name, object, kind)`` with kind ``function``, ``class``, ``method`` or ``property``."""
    found = []
    for name in netsim.__all__:
        obj = getattr(netsim, name)
        if inspect.isclass(obj):
            found.append((f"netsim.{name}", obj, "class"))
        elif callable(obj):
            found.append((f"netsim.{name}", obj, "function"))
    for name, member in vars(RunResult).items():
        if name.startswith("_"):
            continue
        if isinstance(member, property):
            found.append((f"RunResult.{name}", member, "property"))
        elif isinstance(member, (classmethod, staticmethod)) or inspect.isfunction(member):
            found.append((f"RunResult.{name}", getattr(RunResult, name), "method"))
    return found


PUBLIC = _public()


def _parse(obj: object) -> typing.Any:
    text = inspect.getdoc(obj.fget if isinstance(obj, property) else obj) or ""
    assert text.strip(), "no docstring"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpydoc warns on an unknown section or a malformed one
        return docscrape.NumpyDocString(text)


def _signature_params(obj: object) -> list[str]:
    sig = inspect.signature(obj)
    return [p for p in sig.parameters if p not in ("self", "cls") and not p.startswith("_")]


def test_the_public_api_is_what_the_test_covers():
    names = {n for n, _, _ in PUBLIC}
    assert {"netsim.run", "netsim.load_scenario", "netsim.run_sweep", "netsim.make_report", "netsim.RunResult",
            "RunResult.plot", "RunResult.to_timeresponse", "RunResult.read", "RunResult.status"} <= names


@pytest.mark.parametrize("name, obj, kind", PUBLIC, ids=[n for n, _, _ in PUBLIC])
def test_every_parameter_is_documented_with_a_type_and_there_are_returns_and_examples(name, obj, kind):
    doc = _parse(obj)
    assert doc["Summary"], f"{name}: no summary line"
    assert doc["Examples"], f"{name}: no Examples section"
    if kind == "property":
        return
    documented = {}
    for param in doc["Parameters"]:
        for each in param.name.split(","):
            documented[each.strip()] = param.type
    params = _signature_params(obj)
    missing = [p for p in params if p not in documented]
    assert not missing, f"{name}: parameters not documented: {missing}"
    untyped = [p for p in params if not documented[p].strip()]
    assert not untyped, f"{name}: parameters documented without a type: {untyped}"
    stale = [p for p in documented if p not in params]
    assert not stale, f"{name}: documented parameters not in the signature: {stale}"
    if kind != "class":
        assert doc["Returns"] and doc["Returns"][0].type.strip(), f"{name}: no typed Returns section"


def test_the_public_functions_and_methods_are_annotated():
    from control import TimeResponseData
    from matplotlib.figure import Figure

    from netsim.scenario.schema import Scenario
    from netsim.sweep import SweepResult

    names = {"RunResult": RunResult, "Figure": Figure, "TimeResponseData": TimeResponseData, "Scenario": Scenario,
             "SweepResult": SweepResult}
    returns = {}
    for name, obj, kind in PUBLIC:
        if kind in ("function", "method"):
            returns[name] = typing.get_type_hints(obj, localns=names)["return"]
    assert returns["netsim.run"] is RunResult and returns["RunResult.read"] is RunResult
    assert returns["netsim.load_scenario"] is Scenario and returns["netsim.run_sweep"] is SweepResult
    assert returns["netsim.make_report"] == dict[str, pd.DataFrame]
    assert returns["RunResult.plot"] is returns["RunResult.plot_schedule"] is returns["RunResult.plot_network"] \
        is Figure
    assert returns["RunResult.to_timeresponse"] is TimeResponseData
    assert all(r is not typing.Any for r in returns.values()), returns


@pytest.mark.parametrize("name, obj, kind", PUBLIC, ids=[n for n, _, _ in PUBLIC])
def test_the_examples_run(name, obj, kind, monkeypatch, tmp_path):
    monkeypatch.chdir(ROOT)
    target = obj.fget if isinstance(obj, property) else obj
    globs = {"netsim": netsim, "pd": pd, "RunResult": RunResult}
    finder = doctest.DocTestFinder(recurse=False)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    for test in finder.find(target, name, globs=globs):
        runner.run(test)
    assert runner.failures == 0, f"{name}: {runner.failures} example(s) failed"
