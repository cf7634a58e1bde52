"""What `netsim run` and `netsim validate` import (issue 29: start-up time): a command imports only what it uses.

Each check runs the command in a fresh interpreter and reads ``sys.modules`` at its end, so a module-level
``import pandas`` anywhere on the path (or a table built where none is needed) fails here rather than only slowing
the start-up benchmark (tests/benchmarks/test_bench_run.py). The scenarios are the shipped ones the benchmark
times: dc_servo_ideal (run) and dc_servo_can (validate)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

#: Modules no run or validation of a plain LTI scenario needs: the tables are written without pandas, figures
#: are off, python-control is a design-time tool, and the LTI plant steps with scipy.linalg alone.
HEAVY = ("pandas", "matplotlib", "control", "scipy.signal", "scipy.integrate", "scipy.optimize", "scipy.stats")

_PROBE = """
import json, sys
import netsim.cli
code = netsim.cli.main(sys.argv[1:])
print(json.dumps({"code": code, "modules": sorted(sys.modules)}))
"""


def _imported(*argv: str) -> tuple[int, set[str]]:
    proc = subprocess.run([sys.executable, "-c", _PROBE, *argv], cwd=ROOT, capture_output=True, text=True,
                          check=True)
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    return report["code"], set(report["modules"])


def _heavy(modules: set[str], names: tuple[str, ...] = HEAVY) -> list[str]:
    return sorted(name for name in names if name in modules)


def test_importing_the_command_line_imports_no_numerical_library():
    code = "import sys, netsim.cli; print(sorted(m for m in ('numpy', 'pydantic', 'simpy') + %r if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code % (HEAVY,)], cwd=ROOT, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_netsim_run_of_an_lti_scenario_imports_no_pandas_and_no_design_library(tmp_path):
    code, modules = _imported("run", "scenarios/dc_servo_ideal.yaml", "--out", str(tmp_path / "run"))
    assert code == 0
    assert _heavy(modules) == []
    # nor the design module of state feedback, the network classes, or the readers of run folders
    assert _heavy(modules, ("netsim.programs.state_feedback", "netsim.programs.feedback_design",
                            "netsim.control.part_specs", "netsim.network.pipeline", "netsim.results.folder")) == []
    # the run folder is complete all the same
    written = sorted(p.name for p in (tmp_path / "run").iterdir())
    assert {"signals.csv", "jobs.csv", "metrics.csv", "meta.json"} <= set(written)
    assert json.loads((tmp_path / "run" / "meta.json").read_text())["status"] == "ok"


@pytest.mark.parametrize("scenario", ["scenarios/dc_servo_can.yaml", "scenarios/dc_servo_ideal.yaml"])
def test_netsim_validate_imports_no_pandas_and_no_scipy(scenario):
    code, modules = _imported("validate", scenario)
    assert code == 0
    assert _heavy(modules, HEAVY + ("scipy", "netsim.programs.state_feedback", "netsim.control.part_specs")) == []
