"""`netsim run -q` shows only errors on the console, but the run's meta.json still keeps the warnings a metric logs."""

from __future__ import annotations

import io
import json
import logging
import sys

from netsim.cli import main


def test_quiet_run_keeps_a_metric_warning_in_meta_json_and_prints_none(tmp_path, capsys):
    # the variant of tests/test_run_warnings.py: hdd_case3 with h = 100 and a 1 Gbit/s network makes et_control log
    # that the actuator played past the end of its packet (a WARNING); -q sets the console to ERROR
    out = tmp_path / "r"
    code = main(["run", "-q", "scenarios/hdd_case3.yaml", "--out", str(out),
                 "--set", "nodes.controller.tasks[0].params.design_params.h=100",
                 "--set", "networks.net.bitrate=1 Gbit/s", "--set", "networks.net.max_frame_bits=null"])
    assert code == 0
    meta = json.loads((out / "meta.json").read_text())
    assert any("past the end of its packet" in w for w in meta["warnings"])
    assert "past the end of its packet" not in capsys.readouterr().err
    # the run put the loggers' levels back
    assert logging.getLogger("netsim").level == logging.NOTSET


def test_a_second_main_in_one_process_logs_to_the_current_stderr(monkeypatch):
    # the first main() binds netsim's console handler to the stderr of its time; a later call must make it write
    # to the stderr of its own time (a notebook or a test harness swaps sys.stderr between calls)
    first, second = io.StringIO(), io.StringIO()
    monkeypatch.setattr(sys, "stderr", first)
    assert main(["list", "policies"]) == 0
    first.close()
    monkeypatch.setattr(sys, "stderr", second)
    assert main(["list", "policies"]) == 0
    logging.getLogger("netsim.test_marker").warning("marker after the second call")
    assert "WARNING: marker after the second call" in second.getvalue()
