"""Run figures a paper author would accept (issues 21 and 27): units on every axis, panels by declared signal kind
and unit, one colour per loop with references set apart, a zoom on the first transient, a diverged run clipped
with a marker, a Gantt window chosen by pixel density with releases, deadlines, zero-length jobs and a row of
deadline misses, network instants of zero-delay links and drops on media without a bit rate."""

from __future__ import annotations

from pathlib import Path

import matplotlib.colors as mcolors
import numpy as np
import pandas as pd
import pytest

import netsim
from netsim.plotting import MAX_BARS, network_figure, resolve_window, responses_figure, schedule_figure

ROOT = Path(__file__).resolve().parents[2]


def _lines(ax) -> dict[str, object]:
    return {line.get_label(): line for line in ax.get_lines() if not line.get_label().startswith("_")}


def _same_colour(a, b) -> bool:
    return mcolors.to_rgba(a.get_color()) == mcolors.to_rgba(b.get_color())


def test_panels_follow_the_declared_io_role_not_the_name():
    # a sensor whose name starts with "u" and an actuator that does not: the old name rule swapped them
    scenario = {"io": {"u_meas": {"type": "adc"}, "drive": {"type": "dac"}}, "signals": {"ref": {"type": "step"}},
                "metrics": [{"type": "control_error", "params": {"reference": "ref", "output": "u_meas"}}]}
    t = np.linspace(0.0, 1.0, 11)
    signals = pd.DataFrame({"time_s": t, "ref": 1.0, "u_meas": t, "drive": 1.0 - t, "x_hat": t / 2})
    fig = responses_figure(signals, scenario)
    assert len(fig.axes) == 3
    assert set(_lines(fig.axes[0])) == {"ref", "$u_{meas}$"}
    assert set(_lines(fig.axes[1])) == {"drive"}
    assert set(_lines(fig.axes[2])) == {"$\\hat{x}$"}  # not declared: its own panel
    for ax in fig.axes:
        assert "(" in ax.get_ylabel() and ")" in ax.get_ylabel()  # a unit (or that none was declared) on every axis
    assert fig.axes[-1].get_xlabel() == "time (s)"
    lines = _lines(fig.axes[0])
    # the reference is dashed and in another colour than its output (issue 27: r and y were one colour)
    assert not _same_colour(lines["ref"], lines["$u_{meas}$"]) and lines["ref"].get_linestyle() == "--"
    assert lines["$u_{meas}$"].get_linestyle() == "-"


def test_three_loops_get_three_colours_and_their_shared_reference_is_black():
    result = netsim.run(ROOT / "scenarios" / "three_servos_edf.yaml", overrides={"duration": "0.2 s"})
    fig = result.plot()
    out, act = _lines(fig.axes[0]), _lines(fig.axes[1])
    for i in (1, 2, 3):
        assert _same_colour(out[f"y{i}"], act[f"u{i}"])  # y1 with u1: declared by task pid{i}'s channels
    assert len({mcolors.to_hex(out[f"y{i}"].get_color()) for i in (1, 2, 3)}) == 3
    assert mcolors.to_hex(out["$r$"].get_color()) == "#000000"


def test_a_diverged_run_is_clipped_with_a_marker_not_flattened():
    t = np.linspace(0.0, 2.0, 201)
    y = np.exp(12.0 * t) * 1e-3  # reaches 2.6e7, "diverged at t = 1.8 s"
    scenario = {"io": {"y": {"type": "adc"}}, "signals": {"r": {"type": "step"}}}
    signals = pd.DataFrame({"time_s": t, "r": 1.0, "y": y})
    ax = responses_figure(signals, scenario, status="diverged at t = 1.8 s").axes[0]
    lo, hi = ax.get_ylim()
    early = np.abs(y[t < 0.9]).max()  # the scale over the first half before divergence
    assert hi == pytest.approx(2.0 * early) and lo == pytest.approx(-2.0 * early)
    markers = [ln for ln in ax.get_lines() if ln.get_marker() == "^"]
    assert len(markers) == 1  # where y leaves the axes
    first_out = t[np.argmax(y > hi)]
    assert markers[0].get_xdata()[0] == pytest.approx(first_out)
    assert any(ln.get_label().startswith("diverged at 1.8") for ln in ax.get_lines())
    ok = responses_figure(signals.assign(y=np.minimum(y, 5.0)), scenario).axes[0]
    assert ok.get_ylim()[1] > 5.0  # an ok run is never clipped


def test_gantt_window_is_a_parameter_and_misses_sit_on_their_own_row():
    result = netsim.run(ROOT / "scenarios" / "three_servos_dm.yaml", overrides={"duration": "0.3 s"})
    whole = result.plot_schedule(window=0.3)
    assert whole.axes[0].get_xlim() == pytest.approx((0.0, 0.3))
    assert whole.axes[0].get_xlabel() == "time (s)" and whole.axes[0].get_ylabel() == "node.task"
    part = result.plot_schedule(window=(0.05, 0.1)).axes[0]
    assert part.get_xlim() == pytest.approx((0.05, 0.1))
    missed = result.jobs[result.jobs["outcome"].isin(["missed", "killed"])
                         & result.jobs["deadline_s"].between(0.05, 0.1)]
    drawn = [ln for ln in part.get_lines() if ln.get_marker() == "x"]
    assert len(missed) > 0 and sum(len(ln.get_xdata()) for ln in drawn) == len(missed)
    # the misses have a row of their own below the three tasks, named on the axis
    rows = [t.get_text() for t in part.get_yticklabels()]
    assert rows[:3] == ["cpu.pid1", "cpu.pid2", "cpu.pid3"] and rows[3].startswith("deadline misses")
    assert {float(y) for ln in drawn for y in ln.get_ydata()} == {3.0}
    # every release and deadline in the window is marked (up triangles, down triangles)
    jobs = result.jobs
    ups = sum(len(ln.get_xdata()) for ln in part.get_lines() if ln.get_marker() == "^")
    downs = sum(len(ln.get_xdata()) for ln in part.get_lines() if ln.get_marker() == "v")
    assert ups == int(jobs["release_s"].between(0.05, 0.1).sum())
    assert downs == int(jobs["deadline_s"].between(0.05, 0.1).sum())


def test_long_runs_default_to_the_first_max_bars_intervals():
    starts = np.arange(2 * MAX_BARS) * 1e-3
    assert resolve_window(None, starts, 2 * MAX_BARS * 1e-3) == (0.0, pytest.approx((MAX_BARS - 1) * 1e-3))
    assert resolve_window(None, starts[:100], 0.5) == (0.0, 0.5)
    assert resolve_window(0.2, starts, 9.0) == (0.0, 0.2)
    with pytest.raises(ValueError, match="plot window"):
        resolve_window((0.3, 0.1), starts, 9.0)


def test_a_lossy_link_without_a_bit_rate_shows_its_delays_and_every_drop():
    can = ["sensor", "controller", "actuator", "interference"]
    result = netsim.run(ROOT / "scenarios" / "dc_servo_can.yaml", overrides={
        "duration": "0.5 s",
        "networks.can": {"type": "link", "nodes": can, "loss_probability": 0.2,
                         "delay": {"dist": "constant", "value": "1 ms"}}})
    msgs = result.messages
    # no bit rate: zero-length transmissions (tx end = tx start), which the old figure drew as nothing
    assert (msgs["tx_end_s"] == msgs["tx_start_s"]).all()
    fig = network_figure(msgs, end_s=0.5)
    ax = fig.axes[0]
    crosses = sum(len(ln.get_xdata()) for ln in ax.get_lines() if ln.get_marker() == "x")
    assert crosses == int(msgs["dropped"].sum()) > 10  # 20 % of ~100 copies
    bars = sum(len(c.get_paths()) for c in ax.collections)
    assert bars == int((~msgs["dropped"]).sum())  # one delay bar per delivered copy
    assert ax.get_xlabel() == "time (s)" and ax.get_ylabel() == "network: sender"


def test_response_time_bars_go_on_a_log_axis_when_they_span_decades():
    from netsim.plotting import bar_figure

    spread = pd.DataFrame({"task": ["isr", "pid"], "response_mean_s": [2e-6, 0.04], "response_max_s": [5e-6, 0.09]})
    ax = bar_figure(spread, ["task"], ["response_mean_s", "response_max_s"], xlabel="response time (s)").axes[0]
    assert ax.get_xscale() == "log" and ax.get_xlabel() == "response time (s)"
    assert len(ax.patches) == 4  # two tasks x two measures
    close = spread.assign(response_mean_s=[0.01, 0.04], response_max_s=[0.02, 0.09])
    assert bar_figure(close, ["task"], ["response_mean_s"], xlabel="s").axes[0].get_xscale() == "linear"
    assert bar_figure(spread.assign(response_mean_s=np.nan, response_max_s=np.nan), ["task"],
                      ["response_mean_s", "response_max_s"]) is None
