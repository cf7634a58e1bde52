"""``python -m netsim`` never imports a module from the folder it is run in (issue 14 A)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import netsim


def test_python_m_netsim_ignores_modules_in_the_working_folder(tmp_path):
    marker = tmp_path / "imported"
    # netsim's plugin list imports 'models': a models.py in the working folder must not be taken for it
    (tmp_path / "models.py").write_text(f"open({str(marker)!r}, 'w').close()\n")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONSAFEPATH"}
    env["PYTHONPATH"] = str(Path(netsim.__file__).resolve().parents[1])  # the netsim under test
    proc = subprocess.run([sys.executable, "-m", "netsim", "list", "plants"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "dc_servo" in proc.stdout  # netsim's own models were loaded
    assert not marker.exists()
