"""A write that fails half-way (a full disk) gives one clear line, a non-zero exit and an incomplete folder (issue 14 C).

A full disk is simulated with the file-size limit (``RLIMIT_FSIZE``, ``SIGXFSZ`` ignored): a write past the limit
fails with ``EFBIG`` exactly where a full disk fails with ``ENOSPC``, after part of the run folder is written.
"""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import pytest

import netsim
from netsim.errors import ConfigError
from netsim.report import report

ROOT = Path(__file__).resolve().parents[2]
#: Bytes any one file may have: scenario.yaml of dc_servo_can (about 3.6 kB) fits, its signals.csv does not.
FILE_LIMIT = 20_000


def _small_disk() -> None:
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (FILE_LIMIT, FILE_LIMIT))


@pytest.mark.skipif(not hasattr(resource, "RLIMIT_FSIZE"), reason="needs RLIMIT_FSIZE")
def test_a_write_that_fails_half_way_gives_one_line_and_leaves_an_incomplete_folder(tmp_path):
    out = tmp_path / "run"
    env = dict(os.environ, PYTHONPATH=str(Path(netsim.__file__).resolve().parents[1]))  # the netsim under test
    proc = subprocess.run([sys.executable, "-m", "netsim", "run", str(ROOT / "scenarios" / "dc_servo_can.yaml"),
                           "--out", str(out), "--quiet"], preexec_fn=_small_disk, env=env, cwd=tmp_path,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode != 0
    assert "Traceback" not in proc.stderr, proc.stderr[-2000:]
    errors = [ln for ln in proc.stderr.splitlines() if ln.startswith("netsim: error:")]
    assert len(errors) == 1 and "cannot write" in errors[0], proc.stderr[-2000:]
    # no meta.json: the folder is marked incomplete, and no CSV cut short lies in it under its final name
    assert out.is_dir() and not (out / "meta.json").exists()
    assert all(p.stat().st_size < FILE_LIMIT for p in out.iterdir())  # a cut file would hold FILE_LIMIT bytes
    assert not [p.name for p in out.iterdir() if p.name.endswith(".tmp")]  # the failed temporary file is removed
    with pytest.raises(ConfigError):  # never read as a finished run
        report(out, plots=False)
