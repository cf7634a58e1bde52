"""No figure of the report code or the sweep code shows a raw identifier (issue 27 section 4).

Every figure the sweep surface, ``netsim report`` on a run or sweep folder, the HDD report and the cart report
draw is built here from small hand-made tables, and the text of each axis label, title, suptitle and legend
entry is searched for snake_case names such as ``Ev_jmap``, ``response_mean_s`` or ``sigma_s``: text outside
``$...$`` (mathtext, where ``\\sigma_s`` is a symbol) that joins word characters with an underscore.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pandas as pd
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

_IDENTIFIER = re.compile(r"[A-Za-z0-9]+_[A-Za-z0-9_]+")
_MATH = re.compile(r"\$[^$]*\$")


def figure_texts(fig: Any) -> list[str]:
    """Axis labels, titles (all three places), the suptitle and legend texts of every axes of ``fig``."""
    texts = [fig._suptitle.get_text()] if getattr(fig, "_suptitle", None) is not None else []
    legends = list(fig.legends)
    for ax in fig.axes:
        texts += [ax.get_xlabel(), ax.get_ylabel()] + [ax.get_title(loc) for loc in ("left", "center", "right")]
        if hasattr(ax, "get_zlabel"):
            texts.append(ax.get_zlabel())
        if ax.get_legend() is not None:
            legends.append(ax.get_legend())
    for legend in legends:
        texts += [t.get_text() for t in legend.get_texts()] + [legend.get_title().get_text()]
    return [t for t in texts if t]


def raw_identifiers(fig: Any) -> list[str]:
    """The snake_case words of :func:`figure_texts` outside mathtext."""
    return [w for t in figure_texts(fig) for w in _IDENTIFIER.findall(_MATH.sub(" ", t))]


def test_the_check_finds_a_raw_identifier_in_a_legend() -> None:
    from matplotlib.figure import Figure

    fig = Figure()
    ax = fig.add_subplot()
    ax.plot([0, 1], label="Ev_jmap")
    ax.set_xlabel(r"$\sigma_s$")
    ax.legend()
    assert raw_identifiers(fig) == ["Ev_jmap"]


# ------------------------------------------------------------------------------------------ sweep figures
def _summary() -> pd.DataFrame:
    rows = []
    for i, (s, c) in enumerate((s, c) for s in (1e-9, 1e-5, 1e-1) for c in (1e-4, 0.0132, 1.7424)):
        gpi = (np.log10(s) + 5) ** 2 + (np.log10(c) + 2) ** 2
        rows.append({"index": i, "replicate": 0, "sigma_s": s, "sigma_c": c, "et.GPI": gpi, "et.Uc": 0.5,
                     "et.Ua": 0.25, "et.NE": 0.1, "status": "ok", "seed": i, "error": "", "folder": f"points/{i}"})
    return pd.DataFrame(rows)


def test_sweep_surface_is_one_heat_map_with_symbols_and_an_unclipped_star() -> None:
    from netsim.sweep.surface import find_optimum, load_surface, surface_figure

    surf = load_surface(_summary(), x="sigma_s", y="sigma_c", z="et.GPI", logx=True, logy=True)
    fig = surface_figure(surf, find_optimum(surf))
    assert not raw_identifiers(fig)
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert len(panels) == 1 and panels[0].name == "rectilinear"  # no 3-D panel
    ax = panels[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == (r"$\sigma_{s}$", r"$\sigma_{c}$")
    star = [line for line in ax.lines if line.get_marker() == "*"]
    assert len(star) == 1 and not star[0].get_clip_on()
    x0, x1 = ax.get_xlim()
    # the optimum (1e-5, 0.0132) is a middle cell; the frame reaches half a log step beyond the outer points
    assert x0 < 1e-9 and x1 > 1e-1


def test_sweep_utilization_is_a_heat_map_per_index_over_the_factors(tmp_path: Path) -> None:
    from netsim.figure_style import paper_style
    from netsim.report import _sweep_heatmaps

    _summary().to_csv(tmp_path / "summary.csv", index=False)
    spec = {"sweep": "s", "base": "b.yaml", "factors": {
        "sigma_s": {"paths": ["a.x"], "logspace": {"start": -9, "stop": -1, "num": 3}},
        "sigma_c": {"paths": ["a.y"], "values": [1e-4, 0.0132, 1.7424]}}}
    (tmp_path / "sweep.json").write_text(json.dumps({"spec": spec, "factors": {"sigma_s": ["a.x"], "sigma_c": ["a.y"]}}))
    captured: list[Any] = []
    from matplotlib.figure import Figure

    original = Figure.savefig

    def keep(self, *a, **k):
        captured.append(self)
        return original(self, *a, **k)

    with pytest.MonkeyPatch.context() as mp, paper_style():
        mp.setattr(Figure, "savefig", keep)
        path = _sweep_heatmaps(tmp_path, tmp_path)
    assert path == tmp_path / "utilization.png" and path.is_file()
    fig = captured[0]
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert len(panels) == 4  # Uc, Ua, NE, GPI
    assert {ax.get_xlabel() for ax in panels} == {r"$\sigma_{s}$"}
    # sigma_s is a logspace; sigma_c is listed, and its values span four decades: both on log axes
    assert {ax.get_yscale() for ax in panels} == {"log"} and {ax.get_xscale() for ax in panels} == {"log"}
    # about 7 x 5 in at 300 dpi in the paper style: far from the old 2079 px tall bar list, whatever the points
    assert fig.get_size_inches()[1] <= 5.0
    assert not raw_identifiers(fig)


def test_report_bar_figures_name_their_values(tmp_path: Path) -> None:
    from matplotlib.figure import Figure

    from netsim.report import _figures

    tables = {
        "utilization": pd.DataFrame({"case": ["a"], "Uc_ratio": [0.5], "Ua_ratio": [0.4], "NE_ratio": [0.1],
                                     "GPI": [0.3]}),
        "tasks": pd.DataFrame({"case": ["a"], "node": ["n"], "task": ["t"], "response_mean_s": [1e-3],
                               "response_max_s": [2e-3]}),
        "networks": pd.DataFrame({"case": ["a"], "network": ["can"], "delay_mean_s": [1e-4], "delay_max_s": [3e-4]}),
    }
    captured: list[Any] = []
    original = Figure.savefig

    def keep(self, *a, **k):
        captured.append(self)
        return original(self, *a, **k)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Figure, "savefig", keep)
        made = _figures(tables, tmp_path, tmp_path, "run")
    assert len(made) == 3 and len(captured) == 3
    for fig in captured:
        assert not raw_identifiers(fig), figure_texts(fig)


# ------------------------------------------------------------------------------------------ case studies
def test_hdd_report_figures_have_no_raw_identifiers() -> None:
    from netsim.models.hdd_figures import case_figure, gpi_figure
    from netsim.models.hdd_report import PAPER_OPT

    t = np.arange(0, 100) * 20e-6
    signals = pd.DataFrame({"time_s": t, "r": 1.0, "y": np.tanh(t * 1e3), "y_hat": np.tanh(t * 1e3), "u": 0.1,
                            "N": 1.0})
    messages = pd.DataFrame({"tag": ["y", "u", "y"], "sent_s": [0.0, 2e-5, 4e-5]})
    fig = case_figure(SimpleNamespace(signals=signals, messages=messages), 4)
    assert not raw_identifiers(fig), figure_texts(fig)
    assert fig.axes[-1].get_xlabel() == "time (s)"
    gpi = _summary()[["sigma_s", "sigma_c", "et.GPI"]]
    gpi.loc[gpi.index[-1], "et.GPI"] = -1.0  # the minimum in the far corner, where the old star was clipped
    fig = gpi_figure(gpi, PAPER_OPT)
    assert not raw_identifiers(fig), figure_texts(fig)
    ax = fig.axes[0]
    stars = [line for line in ax.lines if line.get_marker() == "*"]
    assert len(stars) == 1 and not stars[0].get_clip_on()
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x1 > 1e-1 and y1 > 1.7424  # the corner cell's centre lies inside the frame


def test_cart_report_figures_have_no_raw_identifiers() -> None:
    from netsim.models.cart.figures import cart_figures
    from netsim.models.cart.report import CONTROLLERS, _agg

    rows = []
    for c in CONTROLLERS:
        for wc in (10, 20):
            for q in (4, 6):
                rows.append({"controller": c, "wc": wc, "q": q, "vref": 0.8, "seed": 1, "sigma_u_pooled": 0.1 * wc,
                             "sigma_u": 0.1, "Ev_jmap": 0.01 * q, "Ev": 0.02, "Ev_jmap0": 0.02, "Ev_est": 0.02,
                             "Ev_half1": 0.02, "Ev_half2": 0.02, "v_rms_stop": 0.0, "events_per_tfilter": 1.0,
                             "reached": 1.0})
    df = pd.DataFrame(rows)
    run = SimpleNamespace(p=np.linspace(0, 1, 10), v=np.full(10, 0.8), u=np.ones(10))
    figs = cart_figures(df, df, {"pure_pi": run, "full_event": run}, _agg(df, ["controller", "wc"]),
                        _agg(df, ["controller", "q"]))
    assert set(figs) == {"fig1_time.png", "fig2_sigma_vs_ev.png", "fig3_ev_vs_q.png", "fig4_sigma_vs_q.png"}
    for name, fig in figs.items():
        assert not raw_identifiers(fig), (name, figure_texts(fig))
        assert not any("numpy" in t for t in figure_texts(fig)), name


def test_hdd_gpi_figure_marks_a_run_that_was_not_ok() -> None:
    from netsim.models.hdd_figures import gpi_figure
    from netsim.models.hdd_report import PAPER_OPT

    gpi = _summary()[["sigma_s", "sigma_c", "et.GPI", "status"]].copy()
    gpi.loc[gpi.index[2], "status"] = "unstable at t = 0.008 s"
    fig = gpi_figure(gpi, PAPER_OPT)
    marked = [line for line in fig.axes[0].lines if line.get_label() == "run not ok (unstable)"]
    assert len(marked) == 1 and list(marked[0].get_xdata()) == [gpi["sigma_s"].iloc[2]]


# ------------------------------------------------------------------------------------------ paper checks
_UNIT = re.compile(r"\(([^()]+)\)")


def unitless_axes(fig: Any, allowed: set[str] = frozenset()) -> list[str]:
    """Axis labels (x and y, of every axes that has data) without a unit in parentheses, except ``allowed``."""
    bad = []
    for ax in fig.axes:
        if ax.get_label() == "<colorbar>" or not (ax.lines or ax.collections or ax.patches):
            continue
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            if label and label not in allowed and not _UNIT.search(label):
                bad.append(label)
    return bad


def lines_without_legend(fig: Any) -> list[str]:
    """Axes drawing two or more labelled artists with no legend of their own and no figure legend."""
    if fig.legends:
        return []
    bad = []
    for ax in fig.axes:
        labelled = [a for a in ax.get_lines() + ax.collections if not str(a.get_label()).startswith("_")]
        if len(labelled) >= 2 and ax.get_legend() is None:
            bad.append(ax.get_ylabel() or ax.get_title())
    return bad


def assert_paper_figure(fig: Any, allowed_unitless: set[str] = frozenset()) -> None:
    assert not raw_identifiers(fig), figure_texts(fig)
    assert not unitless_axes(fig, allowed_unitless), unitless_axes(fig, allowed_unitless)
    assert not lines_without_legend(fig), lines_without_legend(fig)
    times = [ax.get_xlabel() for ax in fig.axes if "time" in ax.get_xlabel()]
    assert all(t.startswith("time (s)") for t in times), times  # one time style: "time (s)"


def test_the_paper_checks_find_a_unitless_axis_and_a_missing_legend() -> None:
    from matplotlib.figure import Figure

    fig = Figure()
    ax = fig.add_subplot()
    ax.plot([0, 1], label="a")
    ax.plot([1, 0], label="b")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("angle")
    assert unitless_axes(fig) == ["angle"] and lines_without_legend(fig) == ["angle"]
    ax.set_ylabel("angle (rad)")
    ax.legend()
    assert_paper_figure(fig)


@pytest.fixture(scope="module")
def pendulum_run():
    import netsim

    return netsim.run(Path(__file__).resolve().parents[1] / "scenarios" / "pendulum_lqr.yaml", overrides={
        "duration": "1 s", "io.theta_m.unit": "rad", "io.alpha_m.unit": "rad", "io.u.unit": "V"})


def test_run_figures_are_paper_figures(pendulum_run) -> None:
    import netsim

    assert_paper_figure(pendulum_run.plot())
    servo = netsim.run(Path(__file__).resolve().parents[1] / "scenarios" / "dc_servo_can.yaml",
                       overrides={"duration": "0.2 s"})
    assert_paper_figure(servo.plot(), {"output (unit not declared)", "input (unit not declared)"})
    assert_paper_figure(servo.plot_schedule(), {"node.task"})
    assert_paper_figure(servo.plot_network(), {"network: sender"})


def test_pendulum_report_figures_are_paper_figures() -> None:
    from netsim.models.pendulum.figures import closed_loop_lqr_figure, delay_cost_figure

    t = np.arange(0, 1, 0.005)
    runs = {e: pd.DataFrame({"alpha": 0.2 * np.exp(-5 * t), "u": np.sin(t) * k}, index=t)
            for k, e in enumerate(("fd_raw", "luenberger", "kalman"), start=1)}
    fig = closed_loop_lqr_figure(runs)
    assert_paper_figure(fig)
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == [
        "finite differences", "Luenberger observer", "Kalman filter"]
    dc = pd.read_csv(Path(__file__).resolve().parents[1] / "reports" / "pendulum" / "delay_cost.csv")
    assert_paper_figure(delay_cost_figure(dc), {"stationary cost per sample"})


def test_unicycle_report_figures_are_paper_figures() -> None:
    from netsim.models.unicycle.figures import bands_figure, det_p_figure, measurements_figure, qr_rms_figure

    t = np.arange(0, 10.01, 0.01)
    sig = pd.DataFrame({"x": t, "y": -t, "theta": 0.1 * t, "z_front": 1.0, "z_side": 0.5, "detP": np.exp(-t)},
                       index=t)
    for j in range(3):
        sig[f"xhat[{j}]"], sig[f"sd[{j}]"] = sig[["x", "y", "theta"][j]] + 0.01, 0.02
    for j in range(2):
        sig[f"zhat[{j}]"], sig[f"zsd[{j}]"] = 0.7, 0.01
    qr = {name: [{"e": np.zeros((t.size, 3)) + k} for k in range(3)] for name in ("(Q, R)", "(5Q, R)")}
    for fig in (bands_figure(sig), measurements_figure(sig), qr_rms_figure(qr, t)):
        assert_paper_figure(fig)
    assert_paper_figure(det_p_figure(sig), {"$\\det P$"})
