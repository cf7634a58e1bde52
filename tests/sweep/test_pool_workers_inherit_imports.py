"""The workers of a local process pool inherit the modules every point needs from the parent (issue 29).

Before, each forked worker imported pandas (the baseline's signal table) and ``netsim.runner`` for its first point:
about 0.15-0.3 s of CPU per worker, paid again by every worker of every sweep. The sweep runs in a fresh
interpreter, so nothing imported by other tests hides the difference.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[2]

_SCRIPT = '''
import json, sys
from pathlib import Path
from netsim.sweep import run_sweep

def probe(raw, out, seed):
    """What the worker had imported when its point started (1.0: imported)."""
    (Path(out) / "meta.json").write_text(json.dumps({"seed": seed, "scenario_hash": "probe"}))
    return {"pandas": float("pandas" in sys.modules), "runner": float("netsim.runner" in sys.modules)}

if __name__ == "__main__":
    res = run_sweep(sys.argv[1], out=sys.argv[2], workers=2, point_fn=probe, progress=False)
    print(json.dumps({"ok": res.n_ok, "executor": res.executor, "pandas": [float(v) for v in res.summary["pandas"]],
                      "runner": [float(v) for v in res.summary["runner"]]}))
'''


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the pool forks its workers on Linux")
def test_forked_pool_workers_find_pandas_and_the_runner_imported(tmp_path: Path) -> None:
    base = yaml.safe_load((REPO / "scenarios" / "dc_servo_ideal.yaml").read_text(encoding="utf-8"))
    (tmp_path / "base.yaml").write_text(yaml.safe_dump(base, sort_keys=False), encoding="utf-8")
    (tmp_path / "sweep.yaml").write_text(
        "sweep: preload\nbase: base.yaml\nseed: 1\nfactors:\n  K:\n"
        "    paths: [nodes.computer.tasks[0].params.K]\n    values: [0.5, 1.0, 2.0, 4.0]\n", encoding="utf-8")
    script = tmp_path / "probe.py"
    script.write_text(_SCRIPT, encoding="utf-8")
    proc = subprocess.run([sys.executable, str(script), str(tmp_path / "sweep.yaml"), str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=240, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    got = json.loads(proc.stdout.strip().splitlines()[-1])
    assert got["ok"] == 4 and "process pool (2 workers)" in got["executor"]
    # every point of every worker started with both modules already there: inherited at the fork
    assert got["pandas"] == [1.0] * 4
    assert got["runner"] == [1.0] * 4
