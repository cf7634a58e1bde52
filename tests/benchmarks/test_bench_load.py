"""Scenario loading benchmark (opt-in: pytest -m benchmark -s tests/benchmarks/test_bench_load.py), issue 15 B.

Printed, never asserted as timings:

* load + validate of ``scenarios/hdd_case1.yaml`` (``load_scenario``: read, parse, one schema validation, plugin
  parameters and cross references, build's static checks), split into parsing and the rest, and the cost of
  the second, position-keeping parse that runs only when a problem needs its line;
* the whole ``netsim.run(hdd_case1, write=False)``;
* ``netsim validate scenarios/hdd_case4.yaml`` as a user runs it (a fresh process), and in process: the import of
  python-control (the HDD plant's design uses it), the first check (plugin modules imported, plant built) and a
  second check.

``BEFORE`` holds the same figures measured at commit 970ce6a (ruamel.yaml's round-trip loader, the schema
validated again by the runner), on this kind of machine (2 cores, Python 3.11; best of 4 rounds, each the best of
40 loads and 8 runs, alternating with the new code so both saw the same load): the ratios printed compare with
them. Times are the best of repetitions (the machine is shared).
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from netsim.runner import clear_baseline_cache, run
from netsim.scenario import load_scenario, scenario_hash
from netsim.scenario.safe_yaml import line_table, load_file

ROOT = Path(__file__).resolve().parents[2]
CASE1 = ROOT / "scenarios" / "hdd_case1.yaml"
CASE4 = ROOT / "scenarios" / "hdd_case4.yaml"

#: Figures of commit 970ce6a (before issue 15 B), seconds: measured with this file's method on this machine.
BEFORE = {"load_validate": 17.99e-3, "run": 103.1e-3}


def _best(fn, reps: int) -> float:
    best = float("inf")
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


@pytest.mark.benchmark
def test_bench_load_and_validate_hdd_case1():
    sc = load_scenario(CASE1)  # warm-up: plugin modules, the HDD plant's design cache
    run(CASE1, write=False)
    t_load = _best(lambda: load_scenario(CASE1), 30)
    t_parse = _best(lambda: load_file(CASE1), 30)
    text = CASE1.read_text()
    t_lines = _best(lambda: line_table(text), 30)

    def whole_run():
        clear_baseline_cache()
        run(CASE1, write=False)

    t_run = _best(whole_run, 10)
    print(f"\n[bench] hdd_case1 load+validate {t_load * 1e3:.2f} ms (before {BEFORE['load_validate'] * 1e3:.2f} ms: "
          f"{t_load / BEFORE['load_validate']:.2f}x of it); of which reading and parsing {t_parse * 1e3:.2f} ms; "
          f"positions for an error report {t_lines * 1e3:.2f} ms (only when a problem needs a line)")
    print(f"[bench] netsim.run(hdd_case1, write=False) {t_run * 1e3:.1f} ms (before {BEFORE['run'] * 1e3:.1f} ms: "
          f"{t_run / BEFORE['run']:.2f}x of it); load+validate is {t_load / t_run:.1%} of it")
    # what was timed is the real thing: the file's scenario, equal to the one loaded from its data
    assert scenario_hash(sc) == scenario_hash(load_file(CASE1)[0])


@pytest.mark.benchmark
def test_bench_validate_hdd_case4():
    cmd = [sys.executable, "-m", "netsim", "validate", str(CASE4)]
    walls = []
    for _ in range(3):
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
        walls.append(time.perf_counter() - t0)
        assert proc.returncode == 0 and "valid" in proc.stdout, proc.stdout + proc.stderr
    code = ("import time; t0 = time.perf_counter(); import control; t1 = time.perf_counter(); "
            "from netsim.scenario import check_scenario; t2 = time.perf_counter(); "
            f"p = check_scenario({str(CASE4)!r}); t3 = time.perf_counter(); p = check_scenario({str(CASE4)!r}); "
            "t4 = time.perf_counter(); print(t1 - t0, t3 - t2, t4 - t3, len(p))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    t_control, t_first, t_second, n = out.split()
    print(f"\n[bench] `netsim validate hdd_case4.yaml` {min(walls):.2f} s wall (best of 3 processes); in process: "
          f"import control {float(t_control):.2f} s, first check {float(t_first):.2f} s (plugin modules imported, "
          f"HDD plant designed), second check {float(t_second) * 1e3:.1f} ms")
    assert int(n) == 0  # hdd_case4 is valid and clean: the figures are those of a complete check
