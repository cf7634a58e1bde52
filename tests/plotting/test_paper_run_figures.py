"""Run figures fit for a paper (issue 27 section 4): units from the io channels on the axes, states of other
units off the outputs' panel, a zoom on the first transient, a Gantt chart whose default window shows every job
(no aliasing), with releases, deadlines and zero-length jobs, and a network timeline that draws zero-delay
messages and keeps its key in a legend."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import netsim
from netsim.plotting import (MIN_FEATURE_PX, PX_PER_INCH, density_window, first_transient, network_figure,
                             responses_figure, schedule_figure, signal_label, signal_units)

ROOT = Path(__file__).resolve().parents[2]
UNITS = {"io.theta_m.unit": "rad", "io.alpha_m.unit": "rad", "io.u.unit": "V"}


def _panel_of(fig, label: str):
    return [ax for ax in fig.axes if label in [ln.get_label() for ln in ax.get_lines()]]


@pytest.fixture(scope="module")
def pendulum():
    return netsim.run(ROOT / "scenarios" / "pendulum_lqr.yaml", overrides={"duration": "1 s", **UNITS})


@pytest.fixture(scope="module")
def servo():
    return netsim.run(ROOT / "scenarios" / "dc_servo_can.yaml")  # 2 s: 201 sensor jobs of 0.9 ms, 0.5 ms others


def test_declared_units_name_the_axes_and_estimates_leave_the_outputs_panel(pendulum) -> None:
    fig = responses_figure(pendulum.signals, pendulum.scenario, zoom=False)
    (angles,) = _panel_of(fig, signal_label("alpha"))
    assert angles.get_ylabel() == "output (rad)"
    assert _panel_of(fig, signal_label("theta")) == [angles]
    (inputs,) = _panel_of(fig, "$u$")
    assert inputs.get_ylabel() == "input (V)"
    # alpha (rad) no longer shares an axis with x_hat[3] (rad/s), whose swing hid it
    (estimates,) = _panel_of(fig, signal_label("x_hat[3]"))
    assert estimates is not angles and estimates is not inputs
    assert all("plant output units" not in ax.get_ylabel() for ax in fig.axes)


def test_signal_units_follow_the_channels_to_plant_ports_and_references() -> None:
    scenario = {"io": {"y": {"type": "adc", "output": "angle", "unit": "rad"},
                       "u": {"type": "dac", "input": "volts_in", "unit": "V"},
                       "z": {"type": "adc"}},
                "signals": {"r": {"type": "step"}, "r2": {"type": "step"}},
                "nodes": {"n": {"tasks": [{"params": {"channel": "y", "reference": "r", "output_channel": "u"}},
                                          {"params": {"channel": "z", "reference": "r2"}}]}}}
    assert signal_units(scenario) == {"y": "rad", "angle": "rad", "u": "V", "volts_in": "V", "u.command": "V",
                                      "r": "rad"}  # r2 follows z, whose unit is not declared


def test_a_short_first_transient_gets_a_zoom_panel() -> None:
    t = np.linspace(0.0, 10.0, 10001)
    r = np.where(t >= 1.0, 1.0, 0.0)
    y = np.where(t >= 1.0, 1.0 - np.exp(-(t - 1.0) / 0.05), 0.0)  # settles within 5 % at 1 + 3 tau = 1.15 s
    window = first_transient(t, {"y": y}, {"r": r})
    assert window is not None and window[0] == pytest.approx(0.985, abs=2e-3)
    assert 1.15 <= window[1] <= 1.3
    scenario = {"io": {"y": {"type": "adc", "unit": "m"}}, "signals": {"r": {"type": "step"}},
                "metrics": [{"type": "control_error", "params": {"reference": "r", "output": "y"}}]}
    signals = pd.DataFrame({"time_s": t, "r": r, "y": y})
    fig = responses_figure(signals, scenario)
    assert len(fig.axes) == 2 and fig.axes[1].get_xlim() == pytest.approx(window)
    assert "first transient" in fig.axes[1].get_xlabel()
    assert len(responses_figure(signals, scenario, zoom=False).axes) == 1
    # a response as long as the run: the full view shows it, no zoom
    slow = pd.DataFrame({"time_s": t, "r": r, "y": np.where(t >= 1.0, 1.0 - np.exp(-(t - 1.0) / 3.0), 0.0)})
    assert len(responses_figure(slow, scenario).axes) == 1


def test_density_window_gives_the_smallest_feature_its_pixels() -> None:
    # one row of 1 ms jobs every 10 ms, another of 4 ms jobs 2 ms apart: the 1 ms job is the smallest feature
    a = (np.arange(0, 2, 0.01), np.arange(0, 2, 0.01) + 0.001)
    b = (np.arange(0, 2, 0.006), np.arange(0, 2, 0.006) + 0.004)
    assert density_window([a, b], 2.0, 500.0) == (0.0, pytest.approx(0.001 * 500 / MIN_FEATURE_PX))
    assert density_window([a], 0.2, 500.0) == (0.0, 0.2)  # fits: the whole run
    # a network timeline (gaps=None): a retransmission 10 us after a 1 ms frame does not shrink the window, but
    # instants without length are told apart by their gaps
    frames = (np.array([0.0, 0.00101, 0.5]), np.array([0.001, 0.00201, 0.501]))
    assert density_window([frames], 2.0, 500.0, gaps=True)[1] == pytest.approx(1e-5 * 500 / MIN_FEATURE_PX)
    assert density_window([frames], 2.0, 500.0, gaps=None)[1] == pytest.approx(1e-3 * 500 / MIN_FEATURE_PX)
    instants = (np.array([0.0, 0.002, 0.004]),) * 2
    assert density_window([instants], 2.0, 500.0, gaps=None)[1] == pytest.approx(2e-3 * 500 / MIN_FEATURE_PX)


def _raster(fig):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig.set_dpi(PX_PER_INCH)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[:, :, :3].astype(int)


def test_the_default_gantt_window_shows_every_job_of_a_2_s_run(servo) -> None:
    fig = servo.plot_schedule()
    ax = fig.axes[0]
    rows = [t.get_text() for t in ax.get_yticklabels()]
    i = rows.index("sensor.sample")
    t0, t1 = ax.get_xlim()
    img = _raster(fig)
    (x0, y), (x1, _) = ax.transData.transform([(t0, i), (t1, i)])
    line = img[img.shape[0] - int(round(y)), int(np.ceil(x0)) + 1:int(np.floor(x1)) - 1]
    blue = np.abs(line - np.array([31, 119, 180])).sum(axis=1) < 120  # tab:blue, antialiased edges
    drawn = int(np.count_nonzero(np.diff(blue.astype(int)) == 1) + blue[0])
    sched = servo.schedule[servo.schedule["task"] == "sample"]
    start, end = sched["start_s"].astype(float), sched["end_s"].astype(float)
    inside = int(((start < t1) & (end > t0)).sum())
    # every job in the window is a separate bar (the old whole-run chart showed about 60 of 201, irregularly)
    assert inside >= 10 and drawn == inside


def test_zero_length_jobs_are_ticks_on_their_own_row(servo) -> None:
    ax = servo.plot_schedule(window=0.05).axes[0]
    rows = [t.get_text() for t in ax.get_yticklabels()]
    assert "interference.traffic" in rows  # its jobs take no time: no schedule interval, yet a row
    ticks = [ln for ln in ax.get_lines() if ln.get_marker() == "|"]
    jobs = servo.jobs[(servo.jobs["task"] == "traffic") & servo.jobs["start_s"].between(0, 0.05)]
    assert sum(len(ln.get_xdata()) for ln in ticks) == len(jobs) > 40
    assert {float(y) for ln in ticks for y in ln.get_ydata()} == {float(rows.index("interference.traffic"))}


def test_a_zero_delay_link_draws_each_message_instant_and_a_legend() -> None:
    nodes = ["sensor", "controller", "actuator", "interference"]
    res = netsim.run(ROOT / "scenarios" / "dc_servo_can.yaml",
                     overrides={"duration": "0.3 s", "networks.can": {"type": "link", "nodes": nodes}})
    msgs = res.messages
    assert (msgs["delivered_s"] == msgs["sent_s"]).all()  # zero delay: the old timeline drew nothing
    ax = network_figure(msgs, end_s=0.3).axes[0]
    ticks = sum(len(ln.get_xdata()) for ln in ax.get_lines() if ln.get_marker() == "|")
    assert ticks == len(msgs) > 50
    legend = ax.get_legend()
    assert legend is not None and [t.get_text() for t in legend.get_texts()] == ["message taking no time"]
    assert "blue" not in ax.get_title() and "cyan" not in ax.get_title()  # the key left the title


def test_an_explicit_schedule_window_is_kept(servo) -> None:
    ax = schedule_figure(servo.schedule, servo.jobs, window=(0.5, 0.6), end_s=2.0).axes[0]
    assert ax.get_xlim() == pytest.approx((0.5, 0.6))
