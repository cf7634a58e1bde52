"""Code from a scenario's plugins: files runs only when the user allows it (issue 14 A)."""

from __future__ import annotations

import textwrap

import pytest

from netsim.cli import main
from netsim.scenario import check_scenario, load_scenario
from netsim.trust import ENV_VAR

PLUGIN = """
from pathlib import Path

Path({marker!r}).write_text("ran")

from netsim.registry import register
from netsim.programs import Idle


@register("program", {name!r}, "a program from a plugin file (security test)")
class FromFile(Idle):
    pass
"""


@pytest.fixture
def plugin_scenario(tmp_path, scenario, monkeypatch, write_yaml):
    """(scenario file naming plugins/p.py, the marker that file writes when it runs); no user setting allows."""
    monkeypatch.delenv(ENV_VAR, raising=False)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    name = f"zzt_sec_{tmp_path.name.replace('-', '_')}"  # a fresh file (and name) per test: files run once
    marker = tmp_path / "marker"
    (tmp_path / "plugins").mkdir()
    (tmp_path / "plugins" / "p.py").write_text(textwrap.dedent(PLUGIN.format(marker=str(marker), name=name)))
    raw = scenario()
    raw["plugins"] = ["plugins/p.py"]  # relative to the scenario file
    raw["nodes"]["computer"]["tasks"].append({"name": "extra", "program": name, "period": "10 ms",
                                              "priority": 2, "execution": "1 ms"})
    return write_yaml(tmp_path / "s.yaml", raw), marker


def test_validate_refuses_and_runs_nothing_without_permission(plugin_scenario, capsys):
    path, marker = plugin_scenario
    assert main(["validate", str(path)]) != 0
    out = capsys.readouterr().out
    assert f"this scenario loads code from {path.parent / 'plugins' / 'p.py'}; rerun with --allow-plugins" in out
    assert not marker.exists()


def test_run_refuses_and_writes_nothing_without_permission(plugin_scenario, tmp_path, capsys):
    path, marker = plugin_scenario
    assert main(["run", str(path), "--out", str(tmp_path / "run"), "--no-progress"]) != 0
    assert "this scenario loads code from" in capsys.readouterr().err
    assert not marker.exists() and not (tmp_path / "run").exists()


def test_allow_plugins_on_the_command_line_loads_the_file(plugin_scenario, capsys):
    path, marker = plugin_scenario
    assert main(["validate", "--allow-plugins", str(path)]) == 0
    assert "valid" in capsys.readouterr().out
    assert marker.read_text() == "ran"


def test_allow_plugins_in_python(plugin_scenario, tmp_path):
    import netsim

    path, marker = plugin_scenario
    result = netsim.run(str(path), out=tmp_path / "run", allow_plugins=True)
    assert result.ok and marker.exists() and (tmp_path / "run" / "meta.json").exists()


def test_the_user_config_file_allows(plugin_scenario, tmp_path):
    path, marker = plugin_scenario
    (tmp_path / "config" / "netsim").mkdir(parents=True)
    (tmp_path / "config" / "netsim" / "config.toml").write_text("allow_plugins = true\n")
    assert load_scenario(path).name == "sec_servo"
    assert marker.exists()


def test_an_explicit_false_wins_over_the_environment(plugin_scenario, monkeypatch):
    path, marker = plugin_scenario
    monkeypatch.setenv(ENV_VAR, "1")
    problems = [p for p in check_scenario(path, allow_plugins=False) if p.is_error]
    assert "plugins[0]" in [p.path for p in problems]
    assert not marker.exists()


def test_the_cli_flag_does_not_outlive_the_command(plugin_scenario, capsys):
    import os

    path, _ = plugin_scenario
    assert main(["validate", "--allow-plugins", str(path)]) == 0
    assert ENV_VAR not in os.environ


def test_a_plugin_entry_that_is_not_a_python_file_is_refused(tmp_path, scenario, write_yaml):
    (tmp_path / "data.txt").write_text("x")
    raw = scenario()
    raw["plugins"] = ["data.txt", "missing.py"]
    problems = {p.path: p.message for p in check_scenario(write_yaml(tmp_path / "s.yaml", raw), allow_plugins=True)
                if p.is_error}
    assert "ending in .py" in problems["plugins[0]"]
    assert "plugin file not found" in problems["plugins[1]"]


def test_batch_and_sweep_pass_the_permission_to_their_workers(plugin_scenario, tmp_path):
    import csv

    path, marker = plugin_scenario
    assert main(["batch", str(path), "--out", str(tmp_path / "b1"), "--no-progress", "--workers", "1"]) != 0
    with open(tmp_path / "b1" / "summary.csv") as fh:
        assert "this scenario loads code from" in next(csv.DictReader(fh))["error"]
    assert not marker.exists()
    sweep = tmp_path / "sw.yaml"
    sweep.write_text("sweep: sw\nbase: s.yaml\nfactors:\n  dur: {paths: [duration], values: [50 ms, 60 ms]}\n")
    assert main(["sweep", str(sweep), "--out", str(tmp_path / "sw1"), "--no-progress", "--workers", "1"]) != 0
    assert not marker.exists()
    assert main(["sweep", "--allow-plugins", str(sweep), "--out", str(tmp_path / "sw2"), "--no-progress",
                 "--workers", "2"]) == 0
    assert marker.exists()
    assert main(["batch", "--allow-plugins", str(path), "--out", str(tmp_path / "b2"), "--no-progress",
                 "--workers", "2"]) == 0


def test_a_refused_plugin_file_is_the_only_problem_reported(plugin_scenario):
    path, _ = plugin_scenario
    problems = [p for p in check_scenario(path) if p.is_error]
    assert [p.path for p in problems] == ["plugins[0]"]  # not also "unknown program" for what the file registers


def test_a_plugin_file_name_too_long_for_the_file_system_is_a_problem_not_a_traceback(scenario):
    raw = scenario()
    raw["plugins"] = ["k" * 1_000_000 + ".py"]
    (problem,) = [p for p in check_scenario(raw, allow_plugins=True) if p.is_error]
    assert problem.path == "plugins[0]" and "cannot use this plugin file name" in problem.message
