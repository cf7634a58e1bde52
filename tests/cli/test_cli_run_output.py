"""``netsim run`` and its output folder: a bad ``--out`` is refused before anything runs, write errors and
failed runs are reported without a traceback, naming the path (and the partial run folder)."""

from __future__ import annotations

import sys
import types
from pathlib import Path

import logging

import pytest

from netsim.cli import main
from netsim.errors import SimulationError


@pytest.fixture(autouse=True)
def _keep_root_log_level():
    """main() sets the root logger's level from -v/-q; put it back for the tests that follow."""
    level = logging.getLogger().level
    yield
    logging.getLogger().setLevel(level)


def _fake_run(monkeypatch, error: BaseException | None = None) -> list:
    calls: list = []

    def run(*args, **kwargs):
        calls.append((args, kwargs))
        if error is not None:
            raise error
        return types.SimpleNamespace(meta={"status": "ok"}, metrics={}, out_dir="/tmp/x")

    module = types.ModuleType("netsim.runner")
    module.run = run
    monkeypatch.setitem(sys.modules, "netsim.runner", module)
    return calls


def _scenario(tmp_path: Path, good: str) -> Path:
    path = tmp_path / "good.yaml"
    path.write_text(good)
    return path


def test_out_naming_a_file_is_refused_before_the_run(tmp_path, monkeypatch, capsys, good):
    calls = _fake_run(monkeypatch)
    afile = tmp_path / "afile"
    afile.write_text("")
    assert main(["run", str(_scenario(tmp_path, good)), "--out", str(afile)]) == 2
    err = capsys.readouterr().err
    assert calls == []
    assert err == (f"netsim: error: output '{afile}' is a file, not a folder; give a folder path with --out "
                   "(a new or an existing folder), or remove the file\n")


def test_os_error_while_writing_is_one_line_with_the_path_and_exit_1(tmp_path, monkeypatch, capsys, good):
    _fake_run(monkeypatch, PermissionError(13, "Permission denied", "/data/run/signals.csv"))
    assert main(["run", str(_scenario(tmp_path, good))]) == 1
    err = capsys.readouterr().err
    assert err == "netsim: error: cannot write /data/run/signals.csv: Permission denied\n"


def test_a_failed_run_says_where_its_partial_folder_is(tmp_path, monkeypatch, capsys, good):
    error = SimulationError("integrator failed at t = 0.5 s")
    error.run_folder = tmp_path / "partial"
    _fake_run(monkeypatch, error)
    assert main(["run", str(_scenario(tmp_path, good))]) == 1
    err = capsys.readouterr().err
    assert err.splitlines() == ["netsim: error: integrator failed at t = 0.5 s",
                                f"netsim: the partial results are in {tmp_path / 'partial'}"]


def test_shipped_scenario_with_out_naming_a_file_prints_no_traceback(tmp_path, capsys):
    root = Path(__file__).resolve().parents[2]
    afile = tmp_path / "afile"
    afile.touch()
    assert main(["run", str(root / "scenarios" / "dc_servo_can.yaml"), "--out", str(afile)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and f"output '{afile}' is a file" in err


class _Terminal:
    """A stand-in for a terminal on stderr (collects what is written)."""

    def __init__(self) -> None:
        self.parts: list[str] = []

    def write(self, text: str) -> int:
        self.parts.append(text)
        return len(text)

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return True

    def fileno(self) -> int:
        raise OSError("no file descriptor")


def _progress_seen(monkeypatch, tmp_path, good, *extra, before=()) -> tuple[object, str]:
    seen = {}

    def run(*args, progress=None, **kwargs):
        seen["progress"] = progress
        if progress is not None:
            for k in range(11):
                progress(k * 100_000_000, 1_000_000_000)
        return types.SimpleNamespace(meta={"status": "ok"}, metrics={"m": 1.0}, out_dir="/tmp/x")

    module = types.ModuleType("netsim.runner")
    module.run = run
    monkeypatch.setitem(sys.modules, "netsim.runner", module)
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    assert main([*before, "run", str(_scenario(tmp_path, good)), *extra]) == 0
    return seen["progress"], "".join(terminal.parts)


def test_run_on_a_terminal_shows_a_progress_bar_of_simulated_time(tmp_path, monkeypatch, good):
    progress, err = _progress_seen(monkeypatch, tmp_path, good)
    assert callable(progress)
    assert "zzc_good" in err and "1 s / 1 s simulated" in err and "ETA" in err


def test_no_progress_and_quiet_turn_the_bar_off(tmp_path, monkeypatch, good):
    assert _progress_seen(monkeypatch, tmp_path, good, "--no-progress")[0] is None
    assert _progress_seen(monkeypatch, tmp_path, good, before=["-q"])[0] is None


def test_quiet_after_the_command_silences_the_status_and_metrics(tmp_path, monkeypatch, capsys, good):
    _fake_run(monkeypatch)
    path = str(_scenario(tmp_path, good))
    for argv in (["run", path, "-q"], ["-q", "run", path], ["run", "--quiet", path]):
        assert main(argv) == 0, argv
        assert capsys.readouterr().out == "", argv
    assert main(["run", path]) == 0  # not quiet: the status line
    assert capsys.readouterr().out.startswith("zzc_good: ok")


def test_verbose_after_the_command_raises_the_log_level(tmp_path, monkeypatch, good):
    _fake_run(monkeypatch)
    path = str(_scenario(tmp_path, good))
    assert main(["run", path, "-vv"]) == 0
    assert logging.getLogger().level == logging.DEBUG
    assert main(["-v", "validate", path]) == 0
    assert logging.getLogger().level == logging.INFO
    assert main(["validate", path]) == 0
    assert logging.getLogger().level == logging.WARNING
