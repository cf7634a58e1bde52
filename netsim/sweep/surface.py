"""Response surfaces of two-factor sweeps (the GPI surface of Cuenca et al., Fig. 5) and their arg-min.

From a sweep's ``summary.csv`` (one row per run), :func:`load_surface` builds ``z`` over the grid of the two
factors ``x`` and ``y`` (mean over replicates, failed runs left out); :func:`find_optimum` returns the cell
with the lowest ``z`` (ties: the first cell in sweep order); :func:`surface_from_summary` writes
``surface.csv`` (the stored surface, long form), ``optimum.json`` and ``surface.png`` (a heat map with the
optimum starred, log axes for log-spaced factors); :func:`metric_heatmaps` draws one heat map per metric.

Examples
--------
>>> surf = load_surface("reports/hdd_gpi/summary.csv", x="sigma_s", y="sigma_c", z="GPI")  # doctest: +SKIP
>>> find_optimum(surf)["x_value"]                                                      # doctest: +SKIP
1e-05
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from netsim.errors import ConfigError

__all__ = [
    "Surface",
    "load_surface",
    "find_optimum",
    "plot_surface",
    "surface_figure",
    "metric_heatmaps",
    "cell_edges",
    "surface_from_summary",
    "describe_optimum",
]

log = logging.getLogger(__name__)


@dataclass
class Surface:
    """``z`` on the grid ``xs`` x ``ys``.

    Attributes
    ----------
    cells
        Long form, one row per (x, y) cell in sweep order: ``x, y, z`` (mean over ok runs), ``runs`` (ok
        runs in the cell), ``index`` (first run index of the cell), plus the mean of every other numeric
        summary column (``metric`` columns, for the optimum's record).
    xs, ys
        Sorted distinct factor values.
    Z
        ``len(ys) x len(xs)`` array (NaN where no run succeeded).
    """

    x: str
    y: str
    z: str
    cells: pd.DataFrame
    xs: np.ndarray
    ys: np.ndarray
    Z: np.ndarray
    logx: bool = False
    logy: bool = False


def load_surface(
    summary: str | Path | pd.DataFrame, *, x: str, y: str, z: str = "GPI", logx: bool = False, logy: bool = False
) -> Surface:
    """Build the surface ``z(x, y)`` from a sweep summary (path or DataFrame).

    Raises
    ------
    ConfigError
        When a column is missing or a factor is not numeric.
    """
    from netsim.results.folder import read_summary

    df = summary if isinstance(summary, pd.DataFrame) else read_summary(summary)
    for col in (x, y, z):
        if col not in df.columns:
            raise ConfigError(f"surface: no column '{col}' in the summary (columns: {', '.join(map(str, df.columns))})")
    df = df.sort_values("index") if "index" in df.columns else df.reset_index(names="index")
    try:
        xv = df[x].astype(float)
        yv = df[y].astype(float)
    except (TypeError, ValueError):
        raise ConfigError(f"surface: factors '{x}' and '{y}' must be numeric") from None
    ok = df["status"].astype(str) == "ok" if "status" in df.columns else pd.Series(True, index=df.index)
    zv = pd.to_numeric(df[z], errors="coerce").where(ok)
    frame = pd.DataFrame({"x": xv.to_numpy(), "y": yv.to_numpy(), "z": zv.to_numpy(), "ok": ok.to_numpy(),
                          "index": df["index"].to_numpy()})
    skip = {x, y, z, "index", "replicate", "seed", "status", "error", "folder"}
    extra = [c for c in df.columns if c not in skip and pd.api.types.is_numeric_dtype(df[c])]
    for c in extra:
        frame[f"metric:{c}"] = df[c].where(ok).to_numpy()
    grouped = frame.groupby(["x", "y"], sort=False)
    cells = grouped.agg(
        z=("z", "mean"), runs=("ok", "sum"), index=("index", "min"),
        **{c: (c, "mean") for c in frame.columns if c.startswith("metric:")},
    ).reset_index()
    cells = cells.sort_values("index", kind="stable").reset_index(drop=True)
    cells["runs"] = cells["runs"].astype(int)
    xs = np.unique(cells["x"].to_numpy(float))
    ys = np.unique(cells["y"].to_numpy(float))
    Z = np.full((ys.size, xs.size), np.nan)
    ix = np.searchsorted(xs, cells["x"].to_numpy(float))
    iy = np.searchsorted(ys, cells["y"].to_numpy(float))
    Z[iy, ix] = cells["z"].to_numpy(float)
    return Surface(x, y, z, cells, xs, ys, Z, logx, logy)


def find_optimum(surface: Surface) -> dict[str, Any]:
    """The cell with the lowest ``z`` (first in sweep order among equals).

    Returns
    -------
    dict
        ``x, y, z`` (names), ``x_value, y_value, z_value``, ``index`` (first run of the cell), ``runs``,
        ``metrics`` (mean of the other numeric columns in that cell), ``cells`` and ``missing`` (cells
        without a successful run).

    Raises
    ------
    ConfigError
        When no cell has a value.
    """
    z = surface.cells["z"].to_numpy(float)
    if not np.isfinite(z).any():
        raise ConfigError(f"surface: no successful run has a finite '{surface.z}'; nothing to minimise")
    k = int(np.nanargmin(np.where(np.isfinite(z), z, np.nan)))
    row = surface.cells.iloc[k]
    metrics = {c.removeprefix("metric:"): _num(row[c]) for c in surface.cells.columns if c.startswith("metric:")}
    return {
        "x": surface.x,
        "y": surface.y,
        "z": surface.z,
        "x_value": float(row["x"]),
        "y_value": float(row["y"]),
        "z_value": float(row["z"]),
        "index": int(row["index"]),
        "runs": int(row["runs"]),
        "cells": int(len(surface.cells)),
        "missing": int((~np.isfinite(z)).sum()),
        "metrics": metrics,
    }


def _num(v: Any) -> float | None:
    f = float(v)
    return f if math.isfinite(f) else None


def describe_optimum(opt: dict[str, Any]) -> str:
    """``optimum: GPI = 0.1763 at sigma_s = 1e-05, sigma_c = 0.0132 (run 220)``."""
    return (
        f"optimum: {opt['z']} = {opt['z_value']:.6g} at {opt['x']} = {opt['x_value']:.6g}, "
        f"{opt['y']} = {opt['y_value']:.6g} (run {opt['index']})"
    )


def cell_edges(centres: np.ndarray, log: bool) -> np.ndarray:
    """Edges of the heat-map cells around sorted grid values: midpoints between neighbours, half a step
    beyond the ends; on a log axis the midpoints are geometric (midpoints of log10), so each cell of a
    log-spaced grid is equally wide on the log axis (``pcolormesh(shading="nearest")`` put the edges at linear
    midpoints: on log axes the first column shrank to a sliver and the last row was cut, issue 21).
    """
    v = np.asarray(centres, dtype=float)
    if log:
        return 10.0 ** cell_edges(np.log10(v), False)
    if v.size == 1:
        half = abs(v[0]) * 0.5 or 0.5
        return np.array([v[0] - half, v[0] + half])
    mid = (v[:-1] + v[1:]) / 2.0
    return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])


def _heat_panel(fig: Any, ax: Any, xs: np.ndarray, ys: np.ndarray, Z: np.ndarray, *, x: str, y: str, z: str,
                logx: bool, logy: bool) -> None:
    """One heat map of ``Z`` (rows ``ys``, columns ``xs``) on ``ax`` with its colour bar; axes named by the
    factors' symbols, log scale for log-spaced factors (matplotlib's one tick style: powers of ten)."""
    from netsim.figure_style import symbol

    mesh = ax.pcolormesh(cell_edges(xs, logx), cell_edges(ys, logy), np.ma.masked_invalid(Z), shading="flat",
                         cmap="viridis")
    fig.colorbar(mesh, ax=ax, label=symbol(z))
    if logx:
        ax.set_xscale("log")
    if logy:
        ax.set_yscale("log")
    ax.set_xlabel(symbol(x))
    ax.set_ylabel(symbol(y))


def surface_figure(surface: Surface, optimum: dict[str, Any] | None = None) -> Any:
    """A :class:`matplotlib.figure.Figure`: the heat map of ``z`` over the two factors, the optimum starred.

    The cells span :func:`cell_edges` (log-spaced edges on a log axis), so a corner optimum's star sits inside
    its cell, half a cell from the frame; the star is drawn unclipped as well. The optimum is written in the
    title, never over a cell.
    """
    from matplotlib.figure import Figure

    from netsim.figure_style import COLUMN_WIDTH_IN, symbol

    fig = Figure(figsize=(COLUMN_WIDTH_IN, 2.8), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    _heat_panel(fig, ax, surface.xs, surface.ys, surface.Z, x=surface.x, y=surface.y, z=surface.z,
                logx=surface.logx, logy=surface.logy)
    if optimum is not None:
        ox, oy, oz = optimum["x_value"], optimum["y_value"], optimum["z_value"]
        ax.plot([ox], [oy], marker="*", color="red", markersize=9, markeredgecolor="white", markeredgewidth=0.6,
                linestyle="none", clip_on=False)
        ax.set_title(f"min {symbol(surface.z)} = {oz:.3g} at {symbol(surface.x)} = {ox:.3g}, "
                     f"{symbol(surface.y)} = {oy:.3g}")
    return fig


def metric_heatmaps(summary: pd.DataFrame, *, x: str, y: str, metrics: list[str], logx: bool = False,
                    logy: bool = False) -> Any:
    """One heat map per metric over the factors ``x`` and ``y`` (mean over replicates and other factors).

    Columns of ``metrics`` missing from ``summary`` or without any value are left out; None when none is
    left. Two panels per row, each half a paper column wide.
    """
    from matplotlib.figure import Figure

    from netsim.figure_style import COLUMN_WIDTH_IN

    surfaces = []
    for name in metrics:
        if name in summary.columns and pd.to_numeric(summary[name], errors="coerce").notna().any():
            surfaces.append(load_surface(summary, x=x, y=y, z=name, logx=logx, logy=logy))
    if not surfaces:
        return None
    cols = 1 if len(surfaces) == 1 else 2
    rows = math.ceil(len(surfaces) / cols)
    fig = Figure(figsize=(COLUMN_WIDTH_IN * (1 if cols == 1 else 2), 2.4 * rows), layout="constrained")
    for k, surf in enumerate(surfaces):
        ax = fig.add_subplot(rows, cols, k + 1)
        _heat_panel(fig, ax, surf.xs, surf.ys, surf.Z, x=x, y=y, z=surf.z, logx=logx, logy=logy)
    return fig


def plot_surface(surface: Surface, optimum: dict[str, Any] | None, path: str | Path) -> Path:
    """Save :func:`surface_figure` at ``path`` in the paper style and the current plot format
    (:mod:`netsim.figure_style`); returns the written path."""
    from netsim.figure_style import paper_style, save_figure

    with paper_style():
        return save_figure(surface_figure(surface, optimum), path)


def surface_from_summary(
    summary_path: str | Path,
    *,
    x: str,
    y: str,
    z: str = "GPI",
    logx: bool = False,
    logy: bool = False,
    out: str | Path | None = None,
    plot: bool = True,
) -> tuple[dict[str, Any], dict[str, Path]]:
    """Surface, optimum and figure of a sweep summary; writes ``surface.csv``, ``optimum.json``, ``surface.png``.

    Returns
    -------
    (optimum, files)
        The optimum (see :func:`find_optimum`) and the written files by name.
    """
    summary_path = Path(summary_path)
    folder = Path(out) if out is not None else summary_path.parent
    surf = load_surface(summary_path, x=x, y=y, z=z, logx=logx, logy=logy)
    opt = find_optimum(surf)
    opt["logx"], opt["logy"] = logx, logy
    files: dict[str, Path] = {}
    cells = surf.cells[["index", "x", "y", "z", "runs"]].rename(columns={"x": x, "y": y, "z": z})
    files["surface"] = folder / "surface.csv"
    from netsim.sweep.summary import format_value

    lines = [",".join(cells.columns)]
    for row in cells.itertuples(index=False):
        lines.append(",".join(format_value(v.item() if hasattr(v, "item") else v) for v in row))
    files["surface"].write_text("\n".join(lines) + "\n", encoding="utf-8")
    files["optimum"] = folder / "optimum.json"
    files["optimum"].write_text(json.dumps(opt, indent=1, sort_keys=True, allow_nan=False), encoding="utf-8")
    if plot:
        files["figure"] = plot_surface(surf, opt, folder / "surface.png")
    log.info("%s", describe_optimum(opt))
    return opt, files
