"""Shipped scenarios by name (issue 27 section 1): ``netsim run dc_servo_can``, ``netsim scenarios``, and a
one-line did-you-mean for a name that is neither a file nor a shipped scenario."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from netsim import shipped
from netsim.cli import main
from netsim.errors import ConfigError

ROOT = Path(__file__).resolve().parents[2]
CHECKOUT_SCENARIOS = ROOT / "scenarios"


def test_run_takes_a_shipped_scenarios_name_from_any_working_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)  # no scenarios/ folder here
    code = main(["run", "dc_servo_can", "--set", "duration=50 ms", "--out", "run", "-q"])
    assert code == 0, capsys.readouterr().err
    resolved = yaml.safe_load((tmp_path / "run" / "scenario.yaml").read_text())
    assert resolved["name"] == "dc_servo_can"
    assert json.loads((tmp_path / "run" / "meta.json").read_text())["status"] == "ok"


def test_an_unknown_name_is_one_line_naming_the_closest_shipped_scenario(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code = main(["run", "dc_servo_cna"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1
    assert "'dc_servo_cna' is neither a file nor a shipped scenario" in err and "did you mean 'dc_servo_can'?" in err


def test_sweep_takes_a_shipped_sweeps_name_and_refuses_a_misspelt_one(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", "hdd_gpi_swep"]) == 2
    assert "did you mean 'hdd_gpi_sweep'?" in capsys.readouterr().err
    assert main(["validate", "hdd_gpi_sweep_case4", "dc_servo_ideal"]) == 0  # the sweep's base: resolves beside it
    assert capsys.readouterr().out.splitlines()[-2:] == ["hdd_gpi_sweep_case4: valid", "dc_servo_ideal: valid"]


def test_validate_counts_an_unknown_name_as_a_problem_and_checks_the_rest(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["validate", "nope_not_shipped", "dc_servo_ideal"]) == 1
    captured = capsys.readouterr()
    assert "'nope_not_shipped' is neither a file nor a shipped scenario" in captured.out
    assert "dc_servo_ideal: valid" in captured.out
    assert "1 problem in total" in captured.err


def test_a_file_in_the_working_folder_comes_before_a_shipped_scenario_of_the_same_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "dc_servo_can").write_text("name: mine\n")
    assert shipped.resolve("dc_servo_can") == "dc_servo_can"
    assert Path(shipped.resolve("dc_servo_ideal")).samefile(CHECKOUT_SCENARIOS / "dc_servo_ideal.yaml")
    assert shipped.resolve("missing.yaml") == "missing.yaml"  # no such file, none shipped: left to 'file not found'
    assert Path(shipped.resolve("dc_servo_ideal.yaml")).samefile(CHECKOUT_SCENARIOS / "dc_servo_ideal.yaml")
    assert shipped.resolve("dc_servo_can") == "dc_servo_can"  # still the working folder's file


def test_scenarios_lists_every_shipped_file_with_its_kind_and_summary(capsys):
    assert main(["scenarios"]) == 0
    lines = capsys.readouterr().out.splitlines()
    expected = sorted(p.stem for p in CHECKOUT_SCENARIOS.glob("*.yaml"))  # the checkout's folder, read here
    assert [line.split()[0] for line in lines] == expected
    rows = {line.split()[0]: line.split(None, 2) for line in lines}
    assert all(len(row) == 3 and row[2] for row in rows.values()), "every line has a summary"
    assert rows["hdd_gpi_sweep"][1] == "sweep" and rows["dc_servo_can"][1] == "scenario"
    described = yaml.safe_load((CHECKOUT_SCENARIOS / "dc_servo_can.yaml").read_text())["description"]
    assert rows["dc_servo_can"][2] == described


def test_scenarios_path_is_the_folder_the_names_resolve_in(capsys):
    assert main(["scenarios", "--path"]) == 0
    assert Path(capsys.readouterr().out.strip()).samefile(CHECKOUT_SCENARIOS)  # the editable install's folder


def test_scenario_path_names_the_closest_shipped_scenario_for_a_typo():
    with pytest.raises(ConfigError, match=r"'hdd_case7' is not a shipped scenario; did you mean 'hdd_case[1-6]'\?"):
        shipped.scenario_path("hdd_case7")
    with pytest.raises(ConfigError):
        shipped.scenario_path("../setup")  # a path is not a name


def _without_dask(monkeypatch):
    """Make ``distributed`` unfindable, as in an install without netsim[dask]."""
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a, **k: None if name == "distributed" else real(name, *a, **k))


def test_sweep_on_dask_without_the_dask_extra_names_the_extra(tmp_path, monkeypatch, capsys):
    _without_dask(monkeypatch)
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", "hdd_gpi_sweep_case4", "--dask-local"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "pip install 'netsim[dask]'" in err
    assert not (tmp_path / "reports").exists()  # refused before anything ran


def test_run_sweep_from_python_on_dask_without_the_extra_names_it(tmp_path, monkeypatch):
    # the Python API gave a bare ModuleNotFoundError for 'distributed'; it now says which extra to install
    import netsim
    from netsim.errors import ConfigError

    _without_dask(monkeypatch)
    sweep = shipped.scenario_path("hdd_gpi_sweep_case4")
    with pytest.raises(ConfigError, match=r"pip install 'netsim\[dask\]'"):
        netsim.run_sweep(sweep, out=tmp_path / "s", local_dask=True)
