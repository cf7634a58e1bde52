"""The built wheel works in a fresh virtual environment outside the checkout (issue 27 section 1, "Done when").

Slow (about 6.5 min here: 2.7 min to build the wheel and install it with its dependencies from the package index,
half a minute for the gallery's DC servo notebook, 3 min for the HDD report's runs on 2 workers): run with
``pytest -m slow tests/packaging/test_wheel_install.py``; .ci/run does. The wheel is built from a copy of the
package's sources (a stale ``build/`` of the checkout cannot leak into it), installed with the versions of
``constraints.txt`` (those the committed reports were made with) and without any extra, and every command runs
from an empty folder, so nothing of the checkout is on the path.
"""

from __future__ import annotations

import csv
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
#: What the wheel is built from (setup.py maps models/ and scenarios/ into the package).
SOURCES = ("pyproject.toml", "setup.py", "MANIFEST.in", "README.md", "LICENSE", "CITATION.cff", "constraints.txt",
           "netsim", "models", "scenarios")


def _run(args: list[str], cwd: Path, env: dict[str, str], timeout: float) -> subprocess.CompletedProcess[str]:
    return subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


def _table(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_wheel_in_a_fresh_venv_runs_shipped_scenarios_and_regenerates_the_hdd_report(tmp_path):
    started = time.monotonic()
    src = tmp_path / "src"
    src.mkdir()
    for name in SOURCES:
        item = ROOT / name
        if item.is_dir():
            shutil.copytree(item, src / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        else:
            shutil.copy2(item, src / name)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
    env.update(MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", PIP_DISABLE_PIP_VERSION_CHECK="1")

    built = _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(tmp_path / "dist"), str(src)],
                 tmp_path, env, 600)
    assert built.returncode == 0, built.stderr[-3000:]
    (wheel,) = (tmp_path / "dist").glob("netsim-*.whl")

    venv = tmp_path / "venv"
    made = _run([sys.executable, "-m", "venv", str(venv)], tmp_path, env, 300)
    assert made.returncode == 0, made.stderr[-3000:]
    python, netsim = venv / "bin" / "python", venv / "bin" / "netsim"
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    installed = _run([str(python), "-m", "pip", "install", "-q", "-c", str(ROOT / "constraints.txt"), str(wheel)],
                     tmp_path, env, 1200)
    assert installed.returncode == 0, installed.stderr[-3000:]
    install_s = time.monotonic() - started

    work = tmp_path / "work"  # an empty folder: no checkout, no scenarios/, no models/
    work.mkdir()
    where = _run([str(python), "-c", "import netsim, netsim.models.hdd, netsim.shipped as s; "
                  "print(netsim.__file__); print(s.folder())"], work, env, 120)
    assert where.returncode == 0, where.stderr[-3000:]
    for line in where.stdout.split():
        assert Path(line).is_relative_to(venv) and not Path(line).is_relative_to(ROOT), line

    no_models = _run([str(python), "-c", "import models"], work, env, 60)
    assert no_models.returncode != 0 and "No module named 'models'" in no_models.stderr

    listed = _run([str(netsim), "scenarios"], work, env, 120)
    assert listed.returncode == 0, listed.stderr[-3000:]
    names = [line.split()[0] for line in listed.stdout.splitlines()]
    assert names == sorted(p.stem for p in (ROOT / "scenarios").glob("*.yaml"))

    ran = _run([str(netsim), "run", "dc_servo_can"], work, env, 600)
    assert ran.returncode == 0, ran.stderr[-3000:]
    assert len(list((work / "reports" / "dc_servo_can").glob("*/meta.json"))) == 1

    # a gallery notebook in a fresh kernel of this venv (the runner needs nbclient and ipykernel, not netsim's)
    kernel = _run([str(python), "-m", "pip", "install", "-q", "-c", str(ROOT / "constraints.txt"), "nbclient",
                   "ipykernel"], tmp_path, env, 900)
    assert kernel.returncode == 0, kernel.stderr[-3000:]
    notebook_folder = tmp_path / "notebook"
    notebook_folder.mkdir()
    notebook = _run([str(python), str(ROOT / "tests" / "examples" / "notebook_runner.py"),
                     str(ROOT / "examples" / "01_dc_servo_can.ipynb"), str(notebook_folder)], notebook_folder, env, 900)
    assert notebook.returncode == 0, (notebook.stdout + notebook.stderr)[-3000:]

    dask = _run([str(netsim), "sweep", "hdd_gpi_sweep", "--dask-local"], work, env, 120)  # no [dask] extra here
    assert dask.returncode == 2 and "pip install 'netsim[dask]'" in dask.stderr

    report_started = time.monotonic()
    report = _run([str(netsim), "report", "hdd", "--no-plots"], work, env, 3600)
    report_s = time.monotonic() - report_started
    assert report.returncode == 0, report.stderr[-3000:]
    # the versions of the committed report (constraints.txt) and the same runs: the same tables, to the byte
    made, committed = work / "reports" / "hdd", ROOT / "reports" / "hdd"
    for name in ("table.csv", "readings.csv", "gpi.csv", "gpi4.csv"):
        assert (made / name).read_bytes() == (committed / name).read_bytes(), name
    # every quoted number but the sweeps' wall times (this machine's speed, not the model's)
    assert ([row for row in _table(made / "quoted.csv") if not row["key"].endswith("_wall")]
            == [row for row in _table(committed / "quoted.csv") if not row["key"].endswith("_wall")])
    print(f"wheel install {install_s:.0f} s, netsim report hdd --no-plots {report_s:.0f} s")
