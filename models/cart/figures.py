"""The cart report's figures (Henningsson & Cervin, Figs. 1-4), built from the report's tables.

Each figure is one paper column wide (:data:`netsim.figure_style.COLUMN_WIDTH_IN`); the report draws and
saves them inside :func:`netsim.figure_style.paper_style`. Controllers are named as in the paper.
"""

from __future__ import annotations

from typing import Any

import pandas as pd

from netsim.models.cart.controllers import CONTROLLERS

__all__ = ["CONTROLLER_NAMES", "cart_figures"]

#: The controllers' names in figures (Henningsson & Cervin's names, not the code's identifiers).
CONTROLLER_NAMES = {"pure_pi": "pure PI", "observer_pi": "observer PI", "basic_event": "basic event",
                    "position_prediction": "position prediction", "full_event": "full event"}
_EV = "$E_v$ (JMAP reconstruction)"
_SIGMA_U = "$\\sigma_u$ = std($u$)/mean($u$)"


def cart_figures(f2: pd.DataFrame, fq: pd.DataFrame, trace: dict[str, Any], a: pd.DataFrame,
                 b: pd.DataFrame) -> dict[str, Any]:
    """The report's figures by file name (:class:`matplotlib.figure.Figure`, one paper column wide; draw
    them inside :func:`netsim.figure_style.paper_style`): Fig. 2 from ``f2``, Figs. 3-4 from ``fq`` (when
    it has rows), Fig. 1 from ``trace`` (name -> run with ``p``, ``v``, ``u``); ``a`` and ``b`` are the run
    means of ``f2`` by controller and wc and of ``fq`` by controller and q."""
    from matplotlib.figure import Figure

    from netsim.figure_style import COLUMN_WIDTH_IN

    figs: dict[str, Any] = {}
    fig = Figure(figsize=(COLUMN_WIDTH_IN, 3.0), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    for c in CONTROLLERS:
        d = a[a.controller == c].sort_values("wc")
        line, = ax.plot(d.Ev_jmap, d.sigma_u_pooled, "o-", ms=3, label=CONTROLLER_NAMES.get(c, c))
        for _, r in d.iterrows():
            ax.annotate(str(int(r.wc)), (r.Ev_jmap, r.sigma_u_pooled), fontsize=5, xytext=(2, 2),
                        textcoords="offset points")
        raw = f2[f2.controller == c]
        ax.plot(raw.Ev_jmap, raw.sigma_u_pooled, ".", ms=2, color=line.get_color(), alpha=0.4)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(_EV)
    ax.set_ylabel(_SIGMA_U + ", run mean")
    ax.set_title("Fig. 2: $q$ = 6, $v_{ref}$ = 0.8 m/s (labels: $\\omega_c$ in rad/s)")
    ax.legend()
    ax.grid(True, which="both")
    figs["fig2_sigma_vs_ev.png"] = fig
    if not fq.empty:
        for col, name, label, title in (
                ("Ev_jmap", "fig3_ev_vs_q.png", _EV, "Fig. 3: $E_v$ vs $q$ ($\\omega_c$ = 40, $v_{ref}$ = 0.4)"),
                ("sigma_u_pooled", "fig4_sigma_vs_q.png", _SIGMA_U,
                 "Fig. 4: $\\sigma_u$ vs $q$ ($\\omega_c$ = 40, $v_{ref}$ = 0.4)")):
            fig = Figure(figsize=(COLUMN_WIDTH_IN, 2.6), layout="constrained")
            ax = fig.add_subplot(1, 1, 1)
            for c in b.controller.unique():
                d = b[b.controller == c].sort_values("q")
                ax.plot(d.q, d[col], "o-", ms=3, label=CONTROLLER_NAMES.get(c, c))
            ax.set_yscale("log")
            ax.set_xlabel("$q$ (dropped encoder bits)")
            ax.set_ylabel(label)
            ax.set_title(title)
            ax.legend()
            ax.grid(True, which="both")
            figs[name] = fig
    if trace:
        fig = Figure(figsize=(COLUMN_WIDTH_IN, 3.2), layout="constrained")
        axs = fig.subplots(2, 1, sharex=True)
        for name, run in trace.items():
            shown = CONTROLLER_NAMES.get(name, name)
            axs[0].plot(run.p, run.v, label=shown, lw=0.8)
            axs[1].plot(run.p, run.u, label=shown, lw=0.6)
        axs[0].axhline(0.8, ls=":", color="k", lw=0.8)
        axs[0].set_ylabel("velocity $v$ (m/s)")
        axs[1].set_ylabel("$u = K_u u_V$ (m/s$^2$)")
        axs[1].set_xlabel("position $p$ (m)")
        axs[0].set_title("Fig. 1: $q$ = 6, $\\omega_c$ = 20, $v_{ref}$ = 0.8 m/s")
        axs[0].legend()
        axs[0].set_ylim(0.6, 1.0)
        figs["fig1_time.png"] = fig
    return figs
