"""The top-level names of netsim keep their meaning (issue 27 s2): no name in ``netsim.__all__`` is a submodule,
and each one is the same object before and after every public call (run, read, report, sweep), in a fresh
interpreter (the trap showed only there: the first ``netsim.run`` imported ``netsim.sweep.*``, and the name
``netsim.sweep`` turned from the function into the module)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import pytest

import netsim

ROOT = Path(__file__).resolve().parents[1]

#: The check, run in a fresh interpreter: every public name described before and after each public call.
_SCRIPT = textwrap.dedent("""
    import json, sys, types, warnings
    from pathlib import Path
    import yaml
    import netsim

    tmp = Path(sys.argv[1])
    root = Path(sys.argv[2])
    names = list(netsim.__all__)
    first = {n: getattr(netsim, n) for n in names}

    def kinds():
        out = {}
        for n in names:
            v = getattr(netsim, n)
            out[n] = {"same": v is first[n], "module": isinstance(v, types.ModuleType),
                      "callable": callable(v) or n == "__version__"}
        out["sweep"] = isinstance(netsim.sweep, types.ModuleType) and netsim.sweep.__name__ == "netsim.sweep"
        out["report"] = isinstance(netsim.report, types.ModuleType) and netsim.report.__name__ == "netsim.report"
        return out

    assert Path(netsim.__file__).resolve().is_relative_to(root.resolve()), netsim.__file__
    seen = {"import": kinds()}
    scen = root / "scenarios" / "dc_servo_ideal.yaml"
    result = netsim.run(scen, overrides={"duration": "0.05 s"}, out=tmp / "run")
    seen["run"] = kinds()
    back = netsim.RunResult.read(tmp / "run")
    seen["read"] = kinds()
    tables = netsim.make_report(tmp / "run", out=tmp / "report", plots=False)
    seen["report"] = kinds()
    base = yaml.safe_load(scen.read_text())
    base["duration"] = "0.05 s"
    (tmp / "base.yaml").write_text(yaml.safe_dump(base, sort_keys=False))
    (tmp / "sweep.yaml").write_text("sweep: names\\nbase: base.yaml\\nseed: 1\\nfactors:\\n  K:\\n"
                                    "    paths: [nodes.computer.tasks[0].params.K]\\n    values: [0.1, 0.3]\\n")
    swept = netsim.run_sweep(tmp / "sweep.yaml", out=tmp / "sweep", workers=1, progress=False)
    seen["sweep"] = kinds()
    with warnings.catch_warnings(record=True) as caught:  # the old spellings: the modules, callable, deprecated
        warnings.simplefilter("always")
        old_tables = netsim.report(tmp / "run", out=tmp / "report2", plots=False)
        old_swept = netsim.sweep(tmp / "sweep.yaml", out=tmp / "sweep", workers=1, progress=False)
    seen["deprecated"] = {"warned": [str(w.message) for w in caught if w.category is DeprecationWarning],
                          "same_tables": sorted(old_tables) == sorted(tables),
                          "same_runs": old_swept.n_runs == swept.n_runs == 2}
    seen["results"] = {"run": type(result).__name__, "read": type(back).__name__, "sweep_ok": swept.n_ok}
    print(json.dumps(seen))
""")


def test_no_public_name_is_also_a_submodule():
    import pkgutil

    submodules = {m.name for m in pkgutil.iter_modules(netsim.__path__)}
    assert not set(netsim.__all__) & submodules


def test_every_public_name_keeps_its_meaning_across_run_read_report_and_sweep(tmp_path):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run([sys.executable, "-c", _SCRIPT, str(tmp_path), str(ROOT)], capture_output=True,
                          text=True, cwd=tmp_path, timeout=300, env=env)  # this checkout's netsim
    assert proc.returncode == 0, proc.stderr[-3000:]
    seen = json.loads(proc.stdout.strip().splitlines()[-1])
    for step in ("import", "run", "read", "report", "sweep"):
        kinds = seen[step]
        assert kinds.pop("sweep") and kinds.pop("report"), step  # always the modules
        for name, kind in kinds.items():
            assert kind == {"same": True, "module": False, "callable": True}, (step, name, kind)
    assert seen["results"] == {"run": "RunResult", "read": "RunResult", "sweep_ok": 2}
    dep = seen["deprecated"]
    assert dep["same_tables"] and dep["same_runs"]
    assert dep["warned"] == ["calling the module netsim.report is deprecated: call netsim.make_report(...) instead",
                             "calling the module netsim.sweep is deprecated: call netsim.run_sweep(...) instead"]


def test_the_old_function_names_are_still_reachable_from_their_modules():
    from netsim.report import report
    from netsim.sweep import run_sweep

    assert netsim.make_report is report and netsim.run_sweep is run_sweep
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        with pytest.raises(DeprecationWarning, match="netsim.make_report"):
            netsim.report("no such folder")
