"""Figures of the rotary-pendulum report (``netsim report pendulum``), in the paper style.

Kept apart from :mod:`netsim.models.pendulum.report`, which runs the study and writes the tables and README.
:func:`closed_loop_lqr_figure` and :func:`delay_cost_figure` build the figures (one paper column wide, estimators
named in words, time in seconds); :func:`closed_loop_figure` and :func:`delay_figure` save them into the report
folder in the current plot format (:func:`netsim.figure_style.save_figure`); :func:`regenerate` redraws both
from the report's own data (the three closed-loop runs again, ``delay_cost.csv``) without the sweeps.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from netsim.lazy_import import lazy_module

if TYPE_CHECKING:
    import pandas as pd
else:
    pd = lazy_module("pandas")

__all__ = ["ESTIMATOR_NAMES", "closed_loop_lqr_figure", "delay_cost_figure", "closed_loop_figure", "delay_figure"]

#: The estimators' names in figures (the report's identifiers are ``fd_raw``, ``kalman``...).
ESTIMATOR_NAMES = {"fd_raw": "finite differences", "fd_lowpass": "low-pass finite differences",
                   "luenberger": "Luenberger observer", "luenberger_printed": "Luenberger (printed update)",
                   "kalman": "Kalman filter"}


def _name(estimator: str) -> str:
    return ESTIMATOR_NAMES.get(estimator, estimator.replace("_", " "))


def closed_loop_lqr_figure(runs_signals: dict[str, pd.DataFrame]) -> Any:
    """Pendulum angle and motor voltage of the closed-loop LQR runs from the 0.2 rad tilt, one line per
    estimator (``runs_signals``: estimator -> signals with ``alpha`` and ``u`` indexed by time in seconds).
    The noisiest input is drawn first and lighter, so that it does not cover the others."""
    from matplotlib.figure import Figure

    from netsim.figure_style import COLUMN_WIDTH_IN, TIME_LABEL

    fig = Figure(figsize=(COLUMN_WIDTH_IN, 3.2), layout="constrained")
    ax = fig.subplots(2, 1, sharex=True)
    colours = {name: f"C{i}" for i, name in enumerate(runs_signals)}
    spread = {name: float(np.nanstd(s["u"].to_numpy(float)[len(s) // 2:])) for name, s in runs_signals.items()}
    for name in sorted(runs_signals, key=lambda n: -spread[n]):
        s = runs_signals[name]
        t = s.index.to_numpy(float)
        noisy = spread[name] == max(spread.values()) and len(runs_signals) > 1
        ax[0].plot(t, s["alpha"].to_numpy(float), color=colours[name], label=_name(name))
        ax[1].plot(t, s["u"].to_numpy(float), color=colours[name], lw=0.4 if noisy else 0.8,
                   alpha=0.55 if noisy else 1.0, drawstyle="steps-post")
    handles, labels = ax[0].get_legend_handles_labels()
    order = [labels.index(_name(n)) for n in runs_signals]
    ax[0].legend([handles[i] for i in order], [labels[i] for i in order], loc="upper right")
    ax[0].set_ylabel(r"pendulum angle $\alpha$ (rad)")
    ax[1].set_ylabel("motor voltage $u$ (V)")
    ax[1].set_xlabel(TIME_LABEL)
    for a in ax:
        a.grid(True)
    return fig


def delay_cost_figure(dc: pd.DataFrame) -> Any:
    """Stationary LQG cost per sample against the total sample-to-actuation delay, per estimator: the analysis
    (line) and the runs with their confidence interval (points), on a log axis."""
    from matplotlib.figure import Figure

    from netsim.figure_style import COLUMN_WIDTH_IN
    from netsim.models.pendulum.report_sweeps import CI_LEVEL

    fig = Figure(figsize=(COLUMN_WIDTH_IN, 3.0), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    for i, (e, g) in enumerate(dc.groupby("estimator", sort=False)):
        c = f"C{i}"
        fin = g[np.isfinite(g.analytic_cost)]
        ax.plot(fin.total_delay_ms, fin.analytic_cost, "-", color=c, label=_name(str(e)))
        ok = g[g.sim_cost.notna()]
        ax.errorbar(ok.total_delay_ms, ok.sim_cost, yerr=[ok.sim_cost - ok.sim_ci_low, ok.sim_ci_high - ok.sim_cost],
                    fmt="o", color=c, ms=3, capsize=2, elinewidth=0.7)
    ax.plot([], [], "-", color="0.3", label="analysis")
    ax.errorbar([], [], yerr=[], fmt="o", color="0.3", ms=3, label=f"runs ({100 * CI_LEVEL:g} % interval)")
    ax.set_yscale("log")
    ax.set_xlabel("total sample-to-actuation delay (ms)")
    ax.set_ylabel("stationary cost per sample")
    ax.grid(True, which="both")
    fig.legend(loc="outside lower center", ncols=2)
    return fig


def closed_loop_figure(out: Path, runs_signals: dict[str, pd.DataFrame]) -> Path:
    """Write ``closed_loop_lqr.<format>`` (:func:`closed_loop_lqr_figure`) into ``out``; returns the path."""
    from netsim.figure_style import paper_style, save_figure

    with paper_style():
        return save_figure(closed_loop_lqr_figure(runs_signals), Path(out) / "closed_loop_lqr.png")


def delay_figure(out: Path, dc: pd.DataFrame) -> Path:
    """Write ``delay_cost.<format>`` (:func:`delay_cost_figure`) into ``out``; returns the path."""
    from netsim.figure_style import paper_style, save_figure

    with paper_style():
        return save_figure(delay_cost_figure(dc), Path(out) / "delay_cost.png")

