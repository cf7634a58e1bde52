"""The kernels' schedule trace is kept in the run folder (``schedule.csv``) and read back (issue 26 section 7).

Before, :meth:`RunResult.read` returned an empty schedule and ``plot_schedule`` of a read folder said "no kernel
trace".
"""

from __future__ import annotations

import pandas as pd

import netsim
from netsim.results import RunResult


def _scenario(schedule: str = "on") -> dict:
    # One task, period 6 ms, 2 ms of execution, alone on its CPU: it runs [0, 2), [6, 8), ... ms
    return {
        "name": "one_task",
        "duration": "20 ms",
        "plant": {"model": "dc_servo", "params": {"gain": 1000, "a": 1}},
        "io": {"y": {"type": "adc", "output": 0}, "u": {"type": "dac", "input": 0}},
        "signals": {"r": {"type": "constant", "value": 1.0}},
        "nodes": {"computer": {"policy": "fp", "tasks": [
            {"name": "pid", "program": "periodic_controller", "period": "6 ms", "priority": 1, "execution": "2 ms",
             "params": {"channel": "y", "output_channel": "u", "reference": "r", "K": 0.96, "Ti": 0.12}}]}},
        "output": {"schedule": schedule},
    }


def test_schedule_csv_holds_the_running_intervals_in_integer_nanoseconds(tmp_path):
    netsim.run(_scenario(), out=tmp_path / "run")
    lines = (tmp_path / "run" / "schedule.csv").read_text().splitlines()
    assert lines == [
        "node,task,state,start_ns,end_ns",
        "computer,pid,running,0,2000000",
        "computer,pid,running,6000000,8000000",
        "computer,pid,running,12000000,14000000",
        "computer,pid,running,18000000,20000000",
    ]


def test_a_read_folder_has_the_runs_schedule_and_plots_it(tmp_path):
    ran = netsim.run("scenarios/three_servos_dm.yaml", out=tmp_path / "run")
    back = RunResult.read(tmp_path / "run")
    assert len(back.schedule) > 100 and back.traces["schedule"] == "on"
    pd.testing.assert_frame_equal(back.schedule, ran.schedule)
    fig = back.plot_schedule()
    ax = fig.axes[0]
    assert "no kernel trace" not in ax.get_title()
    assert len(ax.patches) + len(ax.collections) > 0  # bars were drawn


def test_without_a_trace_no_file_is_written_and_the_chart_says_it_was_not_kept(tmp_path):
    folder = tmp_path / "run"
    netsim.run(_scenario("on"), out=folder)
    assert (folder / "schedule.csv").exists()
    netsim.run(_scenario("off"), out=folder)  # rewriting the folder: the old trace is not this run's
    assert not (folder / "schedule.csv").exists()
    back = RunResult.read(folder)
    assert back.schedule.empty and back.traces["schedule"] == "off"
    assert "output.schedule: off" in back.plot_schedule().axes[0].get_title()


def test_a_pickled_result_writes_the_same_schedule_file(tmp_path):
    import pickle

    ran = netsim.run(_scenario(), out=tmp_path / "a")
    copy = pickle.loads(pickle.dumps(ran))  # the trace records are left behind: written from the table
    copy.to_csv(tmp_path / "b")
    assert (tmp_path / "b" / "schedule.csv").read_bytes() == (tmp_path / "a" / "schedule.csv").read_bytes()
