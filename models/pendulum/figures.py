"""Figures of the rotary-pendulum report (``netsim report pendulum``).

Kept apart from :mod:`netsim.models.pendulum.report`, which runs the study and writes the tables and README.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from netsim.lazy_import import lazy_module

pd = lazy_module("pandas")

__all__ = ["closed_loop_figure", "delay_figure"]


def closed_loop_figure(out: Path, runs_signals: dict[str, pd.DataFrame]) -> None:
    """Write ``closed_loop_lqr.png``: the pendulum angle and the input of the closed-loop runs, one line per estimator."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for name, s in runs_signals.items():
        ax[0].plot(s.index, s["alpha"], label=name)
        ax[1].plot(s.index, s["u"], label=name, lw=0.8)
    ax[0].set_ylabel("alpha [rad]")
    ax[1].set_ylabel("u [V]")
    ax[1].set_xlabel("time [s]")
    ax[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "closed_loop_lqr.png", dpi=100)
    plt.close(fig)


def delay_figure(out: Path, dc: pd.DataFrame) -> None:
    """Write ``delay_cost.png``: stationary cost against the total delay, analysis and runs, per estimator."""
    import matplotlib

    from netsim.models.pendulum.report_sweeps import CI_LEVEL

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5))
    for i, (e, g) in enumerate(dc.groupby("estimator", sort=False)):
        c = f"C{i}"
        fin = g[np.isfinite(g.analytic_cost)]
        ax.plot(fin.total_delay_ms, fin.analytic_cost, "-", color=c, label=f"{e}: analysis")
        ok = g[g.sim_cost.notna()]
        ax.errorbar(ok.total_delay_ms, ok.sim_cost, yerr=[ok.sim_cost - ok.sim_ci_low, ok.sim_ci_high - ok.sim_cost],
                    fmt="o", color=c, ms=4, capsize=3, label=f"{e}: runs ({100 * CI_LEVEL:g} %)")
    ax.set_yscale("log")
    ax.set_xlabel("total sample-to-actuation delay [ms]")
    ax.set_ylabel("stationary cost per sample")
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(out / "delay_cost.png", dpi=100)
    plt.close(fig)
