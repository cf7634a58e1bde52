"""Figures of the HDD reproduction report (``netsim report hdd``): the case figures (like the paper's
Figs. 6-13) and the GPI surface (Fig. 5).

Kept apart from :mod:`netsim.models.hdd_report`, which runs the cases and writes the tables and README.
"""

from __future__ import annotations

from pathlib import Path
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from netsim.lazy_import import lazy_module
from netsim.models.hdd import T_HDD as T

if TYPE_CHECKING:
    import pandas as pd
else:
    pd = lazy_module("pandas")

__all__ = ["case_figure", "case_figures", "gpi_figure", "save_gpi_figure"]


def case_figure(res: Any, n: int) -> Any:
    """The figure of Case ``n``: output, control, network use and multiplicity over time (a
    :class:`matplotlib.figure.Figure`, one paper column wide; draw it inside
    :func:`netsim.figure_style.paper_style`)."""
    from matplotlib.figure import Figure

    from netsim.figure_style import COLUMN_WIDTH_IN, TIME_LABEL

    s = res.signals
    t = s["time_s"].to_numpy()
    fig = Figure(figsize=(COLUMN_WIDTH_IN, 4.2), layout="constrained")
    ax = fig.subplots(4, 1, sharex=True, gridspec_kw={"height_ratios": [2, 1.2, 0.8, 1]})
    ax[0].plot(t, s["r"], "--", color="0.4", label="reference $r$")
    ax[0].plot(t, s["y"], color="C0", label="output $y$")
    if "y_hat" in s:
        ax[0].plot(t, s["y_hat"], ":", color="C3", label="estimate $\\hat{y}$")
    ax[0].legend(loc="lower right", ncols=3, handlelength=1.5, columnspacing=0.8)
    ax[0].set_ylabel("$y$")
    ax[1].plot(t, s["u"], drawstyle="steps-post", color="C0")
    ax[1].set_ylabel("$u$")
    msgs = res.messages
    for tag, lvl, lab, col in (("y", 1.0, "sensor to controller", "C0"), ("u", 0.5, "controller to actuator", "k")):
        ts = msgs.loc[msgs["tag"] == tag, "sent_s"].to_numpy()
        ax[2].vlines(np.floor(ts / T) * T, 0, lvl, lw=0.4, label=lab, color=col)
    ax[2].set_ylabel("sent")
    ax[2].set_yticks([])
    ax[2].set_ylim(0, 1.6)
    ax[2].legend(loc="upper right", ncols=2, handlelength=1.0, columnspacing=0.8)
    if "N" in s:
        ax[3].plot(t, s["N"], drawstyle="steps-post", color="C0")
    ax[3].set_ylabel("$N$")
    ax[3].set_xlabel(TIME_LABEL)
    fig.suptitle(f"HDD Case {n}")
    return fig


def case_figures(results: dict[str, Any], out_dir: Path) -> list[str]:
    """Write ``case1.png`` .. ``case6.png`` (in the current plot format) into ``out_dir``; return their names."""
    from netsim.figure_style import paper_style, save_figure

    names = []
    with paper_style():
        for n in range(1, 7):
            names.append(save_figure(case_figure(results[f"case{n}"], n), out_dir / f"case{n}.png").name)
    return names


def gpi_figure(gpi: pd.DataFrame, paper_opt: Mapping[str, float] | None = None) -> Any:
    """The GPI surface (eq 29) over the tied thresholds: a heat map on log axes (one cell per grid point,
    :func:`netsim.sweep.surface.cell_edges`), our minimum starred and the paper's optimum crossed; the
    markers are never clipped (a corner cell's centre is half a cell inside the frame). ``paper_opt``: the
    paper's optimum ``{"sigma_s": ..., "sigma_c": ...}`` to cross, if given."""
    from matplotlib.figure import Figure

    from netsim.figure_style import COLUMN_WIDTH_IN
    from netsim.sweep.surface import cell_edges

    piv = gpi.pivot_table(index="sigma_c", columns="sigma_s", values="et.GPI")
    xs, ys = piv.columns.to_numpy(float), piv.index.to_numpy(float)
    fig = Figure(figsize=(COLUMN_WIDTH_IN, 2.9), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    mesh = ax.pcolormesh(cell_edges(xs, True), cell_edges(ys, True), np.ma.masked_invalid(piv.to_numpy(float)),
                         shading="flat", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label="GPI (eq 29)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    best = gpi.iloc[gpi["et.GPI"].argmin()]  # the row of the smallest GPI (NaN skipped)
    ax.plot([best["sigma_s"]], [best["sigma_c"]], "*", color="white", mec="k", mew=0.5, ms=9, clip_on=False,
            label="our minimum")
    if paper_opt is not None:
        ax.plot([paper_opt["sigma_s"]], [paper_opt["sigma_c"]], "x", color="red", ms=7, mew=1.5, clip_on=False,
                label="paper's optimum")
    if "status" in gpi:  # a run the verdict called unstable or diverged: its GPI is shown, and marked
        bad = gpi[gpi["status"].astype(str) != "ok"]
        if len(bad):
            ax.plot(bad["sigma_s"], bad["sigma_c"], "o", mfc="none", mec="white", ms=5, mew=0.8, clip_on=False,
                    label="run not ok (unstable)")
    ax.set_xlabel("$\\delta_s = \\sigma_s$")
    ax.set_ylabel("$\\delta_c = \\sigma_c$")
    fig.legend(loc="outside lower center", ncols=3, handletextpad=0.3, columnspacing=0.8)
    return fig


def save_gpi_figure(gpi: pd.DataFrame, out_dir: Path, name: str = "gpi.png",
                    paper_opt: Mapping[str, float] | None = None) -> None:
    """Write :func:`gpi_figure` of ``gpi`` as ``out_dir / name`` in the paper style."""
    from netsim.figure_style import paper_style, save_figure

    with paper_style():
        save_figure(gpi_figure(gpi, paper_opt), out_dir / name)
