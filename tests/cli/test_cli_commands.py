"""The ``netsim`` commands call the engine entry points with the right arguments and never show tracebacks."""

from __future__ import annotations

import os
import subprocess
import sys
import types
from pathlib import Path

import pytest

from cli_files import write

import netsim
from netsim.cli import main
from netsim.errors import SimulationError
from netsim.scenario import Scenario

ROOT = Path(__file__).resolve().parents[2]


class _Calls:
    def __init__(self) -> None:
        self.calls: list[tuple[tuple, dict]] = []


def _fake_module(monkeypatch, name: str, attr: str, result=None, error: Exception | None = None) -> _Calls:
    """Install a fake ``netsim.<name>`` module whose ``attr`` records its calls."""
    rec = _Calls()

    def fn(*args, **kwargs):
        rec.calls.append((args, kwargs))
        if error is not None:
            raise error
        return result

    module = types.ModuleType(f"netsim.{name}")
    setattr(module, attr, fn)
    monkeypatch.setitem(sys.modules, f"netsim.{name}", module)
    return rec


_METRICS = {"cpu.a": 0.125, "task.a.t.jobs": 10.0, "task.a.t.deadline_misses": 1.0, "task.a.t.max_response_s": 0.002,
            "net.bus.messages": 8.0, "net.bus.loss_rate": 0.25, "net.bus.max_delay_s": 0.0015, "y.ISE": 0.5}


def _result(status: str = "ok", **meta):
    return types.SimpleNamespace(meta={"status": status, **meta}, metrics=dict(_METRICS), out_dir="/tmp/run-x")


def test_run_validates_applies_overrides_and_calls_the_runner(tmp_path, monkeypatch, capsys, good):
    rec = _fake_module(monkeypatch, "runner", "run", _result())
    path = write(tmp_path, "good.yaml", good)
    code = main(["run", str(path), "--out", str(tmp_path / "o"), "--seed", "5", "--plot",
                 "--set", "networks.net.bitrate=1 Mbit/s", "--set", "plant.x0=[2]"])
    assert code == 0
    (args, kwargs), = rec.calls
    scenario = args[0]
    assert isinstance(scenario, Scenario) and scenario.source == str(path)
    assert scenario.networks["net"].validated_params().bitrate == 1e6
    assert scenario.plant.x0 == [2.0]
    assert scenario.seed == 5  # --seed is applied with the --set values, before the one validation
    assert kwargs == {"out": str(tmp_path / "o"), "plot": True, "progress": None}  # no TTY: no bar
    lines = capsys.readouterr().out.splitlines()
    # issue 21: the status, the control metrics first, then the timing figures, then the run folder
    assert lines[0] == "zzc_good: ok"
    assert [ln.split()[0] for ln in lines[1:4]] == ["y.ISE", "task.a.t", "net.bus"]
    assert lines[1].split()[1] == "0.5"
    assert lines[2].endswith("worst response 2 ms, 1 deadline misses in 10 jobs")
    assert lines[3].endswith("25 % lost of 8 messages, worst delay 1.5 ms")
    assert lines[-1] == "run folder: /tmp/run-x"
    assert "cpu.a" not in "\n".join(lines)  # the rest stays in metrics.csv


def test_run_of_an_invalid_scenario_runs_nothing_and_exits_2(tmp_path, monkeypatch, capsys, good):
    rec = _fake_module(monkeypatch, "runner", "run", _result())
    path = write(tmp_path, "bad.yaml", good.replace("program: zzc_prog", "program: zzc_porg", 1))
    assert main(["run", str(path)]) == 2
    assert rec.calls == []
    err = capsys.readouterr().err
    assert "nodes.a.tasks[0].program: unknown program 'zzc_porg'; did you mean 'zzc_prog'?" in err
    assert "nothing was run" in err and "Traceback" not in err


def test_run_of_a_missing_file_exits_2(tmp_path, capsys):
    assert main(["run", str(tmp_path / "none.yaml")]) == 2
    assert "file not found" in capsys.readouterr().err


def test_simulation_error_is_printed_without_traceback(tmp_path, monkeypatch, capsys, good):
    _fake_module(monkeypatch, "runner", "run", error=SimulationError("integrator failed at t = 0.5 s"))
    path = write(tmp_path, "good.yaml", good)
    assert main(["run", str(path)]) == 1
    err = capsys.readouterr().err
    assert err == "netsim: error: integrator failed at t = 0.5 s\n"


def test_a_run_that_did_not_finish_exits_1(tmp_path, monkeypatch, capsys, good):
    _fake_module(monkeypatch, "runner", "run", _result("diverged at t = 0.3 s", error="state blew up"))
    path = write(tmp_path, "good.yaml", good)
    assert main(["run", str(path)]) == 1
    captured = capsys.readouterr()
    assert captured.out.startswith("zzc_good: diverged at t = 0.3 s")
    assert "state blew up" in captured.err


def test_malformed_set_is_a_usage_error(tmp_path, capsys, good):
    path = write(tmp_path, "good.yaml", good)
    assert main(["run", str(path), "--set", "plant.x0"]) == 2
    assert "write key.path=value" in capsys.readouterr().err


def test_batch_expands_folders_and_skips_sweep_files(tmp_path, monkeypatch, capsys, good):
    import pandas as pd

    rec = _fake_module(monkeypatch, "sweep.batch", "run_batch", (pd.DataFrame({"status": ["ok", "ok", "error"]}), 1))
    folder = tmp_path / "sc"
    folder.mkdir()
    write(folder, "b.yaml", good)
    write(folder, "a.yml", good)
    write(folder, "s.yaml", "sweep: x\nbase: b.yaml\n")
    write(folder, "notes.txt", "not a scenario")
    extra = write(tmp_path, "c.yaml", good)
    assert main(["batch", str(folder), str(extra), "--workers", "2", "--out", "o", "--no-progress"]) == 1
    (args, kwargs), = rec.calls
    assert [p.name for p in args[0]] == ["a.yml", "b.yaml", "c.yaml"]
    assert kwargs == {"out": "o", "workers": 2, "progress": False}
    assert capsys.readouterr().out.startswith("2 of 3 scenarios ok, 1 failed")


def test_batch_of_a_missing_path_exits_2(tmp_path, capsys):
    assert main(["batch", str(tmp_path / "nope")]) == 2
    assert "file not found" in capsys.readouterr().err


def _sweep_result(n_failed=0, interrupted=False, n_diverged=0):
    import pandas as pd

    statuses = ["ok"] * 3 + ["error"] * n_failed + ["diverged at t = 1 s"] * n_diverged
    return types.SimpleNamespace(n_failed=n_failed + n_diverged, interrupted=interrupted,
                                 summary=pd.DataFrame({"status": statuses}),
                                 describe=lambda: "sweep s: summary and optimum")


def _fake_run_sweep(monkeypatch, result) -> _Calls:
    """Replace the ``run_sweep`` the command imports (``from netsim.sweep import run_sweep``) with a recorder.

    Only that attribute is replaced: the rest of the package stays importable (the command also imports
    ``netsim.sweep.executor`` for ``--scheduler``; a plain module standing in for ``netsim.sweep`` broke that
    import when this test ran alone).
    """
    import netsim.sweep

    rec = _Calls()

    def fn(*args, **kwargs):
        rec.calls.append((args, kwargs))
        return result

    monkeypatch.setattr(netsim.sweep, "run_sweep", fn)
    return rec


def test_sweep_passes_its_options_and_prints_the_description(tmp_path, monkeypatch, capsys):
    rec = _fake_run_sweep(monkeypatch, _sweep_result())
    path = write(tmp_path, "sw.yaml", "sweep: s\n")
    assert main(["sweep", str(path), "--workers", "3", "--scheduler", "tcp://h:8786", "--overwrite"]) == 0
    (args, kwargs), = rec.calls
    assert args == (str(path),)
    assert kwargs == {"out": None, "workers": 3, "scheduler": "tcp://h:8786", "local_dask": False,
                      "dashboard": None, "overwrite": True, "progress": True}
    assert capsys.readouterr().out == "sweep s: summary and optimum\n"


def test_sweep_exit_codes_for_failures_and_interruption(tmp_path, monkeypatch, capsys):
    path = write(tmp_path, "sw.yaml", "sweep: s\n")
    _fake_run_sweep(monkeypatch, _sweep_result(n_failed=2))
    assert main(["sweep", str(path)]) == 1
    assert "3 of 5 sweep runs ok, 2 failed" in capsys.readouterr().err
    _fake_run_sweep(monkeypatch, _sweep_result(n_diverged=1))
    assert main(["sweep", str(path)]) == 1  # a diverged point is not ok, as for `netsim run`
    assert "3 of 4 sweep runs ok, 1 diverged" in capsys.readouterr().err
    _fake_run_sweep(monkeypatch, _sweep_result(interrupted=True))
    assert main(["sweep", str(path)]) == 130
    assert "run the same command again to resume" in capsys.readouterr().err


def test_sweep_rejects_scheduler_with_local_dask(tmp_path, capsys):
    path = write(tmp_path, "sw.yaml", "sweep: s\n")
    assert main(["sweep", str(path), "--scheduler", "tcp://h:1", "--dask-local"]) == 2
    assert "not both" in capsys.readouterr().err


def test_report_passes_its_options(monkeypatch, capsys):
    rec = _fake_module(monkeypatch, "report", "report", {"gpi": types.SimpleNamespace(shape=(21, 3))})
    assert main(["report", "hdd", "--out", "r", "--no-plots"]) == 0
    assert rec.calls == [(("hdd",), {"out": "r", "plots": False})]
    assert capsys.readouterr().out == "gpi: 21 rows\n"


def test_list_prints_one_line_per_entry(capsys):
    assert main(["list", "programs"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert any(line.split() == ["zzc_prog", "cli", "test", "program"] for line in lines)
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert "plants:" in out and "networks:" in out and "policies:" in out
    assert "  zzc_net" in out


def test_list_of_an_unknown_kind_suggests_one(capsys):
    assert main(["list", "plantz"]) == 2
    assert capsys.readouterr().err == "netsim: error: unknown kind 'plantz'; did you mean 'plants'?\n"


def test_version(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"netsim {netsim.__version__}"


def test_no_command_prints_help_and_exits_2(capsys):
    assert main([]) == 2
    assert "examples:" in capsys.readouterr().out


@pytest.mark.parametrize("command", ["run", "batch", "sweep", "report", "validate", "list"])
def test_every_command_help_has_examples(command, capsys):
    assert main([command, "--help"]) == 0
    assert "examples:" in capsys.readouterr().out


def test_help_is_fast_and_sets_single_threaded_blas():
    code = (
        "import os, sys\n"
        "from netsim.cli import main\n"
        "main(['--help'])\n"
        "heavy = [m for m in ('numpy', 'scipy', 'pandas', 'control', 'pydantic', 'matplotlib') if m in sys.modules]\n"
        "print('HEAVY', heavy, os.environ['OPENBLAS_NUM_THREADS'], os.environ['OMP_NUM_THREADS'])\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    env["PYTHONPATH"] = str(ROOT)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=ROOT, check=True)
    assert out.stdout.splitlines()[-1] == "HEAVY [] 1 1"


def test_python_dash_m_netsim_runs_the_cli(tmp_path):
    path = write(tmp_path, "bad.yaml", "")  # an empty file: no plugin imports needed, so the test is quick
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-m", "netsim", "validate", str(path)], capture_output=True, text=True,
                         env=env, cwd=ROOT)
    assert out.returncode == 1
    assert out.stdout.splitlines()[0] == f"{path}:1: the file is empty; a scenario needs at least 'name' and 'duration'"


def test_plot_window_draws_the_gantt_chart_over_that_window(tmp_path, capsys):
    out = tmp_path / "run"
    code = main(["run", str(ROOT / "scenarios" / "dc_servo_can.yaml"), "--out", str(out), "--no-progress",
                 "--set", "duration=0.3 s", "--plot-window", "0.1 s:150 ms"])
    assert code == 0
    assert {p.name for p in out.glob("*.png")} == {"responses.png", "schedule.png", "network.png"}
    assert capsys.readouterr().out.splitlines()[-1] == f"run folder: {out}"
    assert main(["run", str(ROOT / "scenarios" / "dc_servo_can.yaml"), "--plot-window", "2 s:1 s"]) == 2
    assert "--plot-window '2 s:1 s': the end must come after the start" in capsys.readouterr().err


def test_plot_window_parses_a_length_or_a_range():
    from netsim.cli.commands import _plot_window

    assert _plot_window("50 ms") == (0.0, 0.05)
    assert _plot_window("1 s:1.2 s") == (1.0, 1.2)
    assert _plot_window(None) is None
