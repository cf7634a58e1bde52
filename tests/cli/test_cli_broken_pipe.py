"""A reader that stops early (``netsim list | head``) ends the command quietly: no traceback, no 'Exception
ignored' line, exit 0 (the choice documented in :mod:`netsim.cli`)."""

from __future__ import annotations

import fcntl
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
_F_SETPIPE_SZ = 1031  # Linux fcntl: shrink the pipe so the output cannot all fit in it before the reader leaves


@pytest.mark.parametrize("command", ["list", "docs", "schema"])
def test_a_reader_that_stops_after_one_line_gets_no_traceback(command):
    env = {**os.environ, "NETSIM_ALLOW_PLUGINS": "0"}
    proc = subprocess.Popen([sys.executable, "-m", "netsim", command], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        fcntl.fcntl(proc.stdout.fileno(), _F_SETPIPE_SZ, 4096)
    except OSError:
        pass
    first = proc.stdout.readline()
    proc.stdout.close()  # the reader goes away, as head does after its line
    err = proc.stderr.read().decode()
    code = proc.wait(timeout=120)
    assert first.strip()
    assert "Traceback" not in err and "Exception ignored" not in err and "Broken pipe" not in err, err
    assert code == 0
