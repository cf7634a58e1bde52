"""The command line's use of the garbage collector (issue 29, start-up): fewer young collections while a command
runs, and no full collections over the whole heap at interpreter exit; a caller's own settings are given back."""

from __future__ import annotations

import gc
import subprocess
import sys
from pathlib import Path

import netsim.cli

ROOT = Path(__file__).resolve().parents[2]


def test_the_young_generation_threshold_is_raised_during_a_command_and_restored_after(monkeypatch):
    seen = []
    monkeypatch.setattr(netsim.cli, "_main", lambda argv: seen.append(gc.get_threshold()) or 0)
    before = gc.get_threshold()
    assert netsim.cli.main([]) == 0
    assert gc.get_threshold() == before
    assert seen[0][0] >= 20_000 and seen[0][1:] == before[1:]


def test_the_threshold_is_restored_when_the_command_raises(monkeypatch):
    def boom(argv):
        raise RuntimeError("a bug")

    monkeypatch.setattr(netsim.cli, "_main", boom)
    before = gc.get_threshold()
    try:
        netsim.cli.main([])
    except RuntimeError:
        pass
    assert gc.get_threshold() == before


_PROBE = """
import atexit, gc, sys
# registered before main(): atexit runs handlers last-in first-out, so this one runs after main's
atexit.register(lambda: print("frozen at exit:", gc.get_freeze_count()))
import netsim.cli
code = netsim.cli.main(["validate", "scenarios/dc_servo_ideal.yaml"])
netsim.cli.main(["validate", "scenarios/dc_servo_ideal.yaml"])  # a second call registers nothing more
print("frozen before exit:", gc.get_freeze_count(), "code:", code)
"""


def test_the_heap_is_frozen_at_interpreter_exit_and_not_before():
    out = subprocess.run([sys.executable, "-c", _PROBE], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    lines = dict(line.split(":", 1) for line in out.splitlines() if line.startswith("frozen"))
    assert lines["frozen before exit"].split()[0] == "0"
    assert int(lines["frozen at exit"]) > 10_000  # every object the validation left alive
    atexit_calls = subprocess.run(
        [sys.executable, "-c", "import atexit, netsim.cli\nnetsim.cli.main(['--help'])\nnetsim.cli.main(['--help'])\n"
         "print(atexit._ncallbacks())"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()[-1]
    baseline = subprocess.run([sys.executable, "-c", "import atexit, netsim.cli\nprint(atexit._ncallbacks())"],
                              cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()[-1]
    assert int(atexit_calls) == int(baseline) + 1
