"""Figures of one run: responses and control signals, the schedule (Gantt chart), the network timeline.

The Gantt chart and network timeline live in :mod:`netsim.timeline_figures`, what a scenario declares about its
signals in :mod:`netsim.signal_kinds`, the figure class in :mod:`netsim.inline_figure`; all are re-exported here.
Each ``*_figure`` function returns a :class:`matplotlib.figure.Figure` (no pyplot state, no display needed;
``fig.savefig(path)`` saves it). A figure made here is an :class:`InlineFigure`, which a fresh Jupyter kernel shows
inline without ``%matplotlib inline`` (a bare ``Figure`` shows there as its text repr unless the inline backend
is active). Each takes the axes (``ax=``) or, with several panels, the figure (``fig=``) to draw into, and returns
the figure drawn on. :meth:`netsim.results.RunResult.plot`,
``plot_schedule`` and ``plot_network`` call them; :func:`save_figures` (``netsim run --plot``,
``result.plot(save=DIR)``) writes ``responses.png``, ``schedule.png`` and ``network.png``.

What the figures follow:

- A panel per signal kind and unit (:func:`signal_roles`, :func:`signal_units`): the scenario's ``io`` channels
  (ADC and encoder: sensor, DAC: actuator) and ``signals`` (reference); each axis says the unit the channels
  declare (``unit:``) or that none was declared; a vector without a unit (``x_hat[0]``...) gets its own panel, so
  signals of different units do not share an axis. Names are typeset (:func:`signal_label`: ``x_hat[3]`` as
  :math:`\\hat{x}_3`).
- One colour per loop (:func:`signal_loops`): a task's ``reference``, ``channel`` and ``output_channel`` and a
  metric's ``reference`` and ``output`` share a hue; a reference is dashed and darker than its output.
- A last panel zooms on the first transient when it is short (:func:`first_transient`), shaded in the others.
- Time is "time (s)" everywhere.
- A diverged run is clipped to the loop's scale before it diverged, with a marker where a signal leaves the
  axes and a line at the divergence instant (a 1e10 scale would flatten everything else).
- The Gantt chart and network timeline show, by default, the window in which every job (message) and every gap
  between two of a row spans :data:`MIN_FEATURE_PX` pixels at :data:`PX_PER_INCH` (:func:`density_window`):
  the whole run when it fits, so that no job is lost to aliasing; ``window`` chooses (``netsim run
  --plot-window``). The Gantt chart marks each job's release and deadline, draws zero-length jobs as ticks and
  puts the deadline misses on a row of their own.
- Network timelines show every message: transmissions (tx start to end) where the medium has a bit rate, the
  delay (sent to delivered) where it has none, a tick where a message took no time, and a red cross at the
  send instant of each dropped copy; the key is a legend.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pandas as pd

from netsim.inline_figure import InlineFigure
from netsim.inline_figure import new_figure as _figure
from netsim.signal_kinds import signal_label, signal_loops, signal_roles, signal_units
from netsim.timeline_figures import (MAX_BARS, MIN_FEATURE_PX, PX_PER_INCH, density_window, network_figure,
                                     resolve_window, schedule_figure)

__all__ = [
    "InlineFigure",
    "bar_figure",
    "responses_figure",
    "schedule_figure",
    "network_figure",
    "save_figures",
    "plot_run",
    "signal_roles",
    "signal_loops",
    "signal_units",
    "signal_label",
    "first_transient",
    "density_window",
    "resolve_window",
    "MAX_BARS",
    "MIN_FEATURE_PX",
    "PX_PER_INCH",
]

log = logging.getLogger(__name__)

#: The transient zoom is drawn when the first transient lasts less than this share of the run.
ZOOM_SHARE = 0.3
#: A signal has settled when it stays within this share of its range around its final value.
SETTLE_BAND = 0.05


def _colours(names: list[str], loops: list[list[str]], roles: Mapping[str, str]) -> dict[str, str]:
    palette = [f"C{i}" for i in range(10)]
    out: dict[str, str] = {}
    k = 0
    for group in loops:
        members = [n for n in names if n in group or n.split("[", 1)[0] in group
                   or n.removesuffix(".command") in group]
        if members:
            for n in members:
                out[n] = palette[k % len(palette)]
            k += 1
    for n in names:
        if n not in out:
            if roles.get(n.split("[", 1)[0]) == "reference":
                out[n] = "black"  # followed by several loops, or by none that is declared
            else:
                out[n] = palette[k % len(palette)]
                k += 1
    return out


def _reference_colour(colour: str) -> Any:
    """A reference's colour: its loop's hue, darkened, so that r and y differ in colour as well as in style."""
    import matplotlib.colors as mcolors

    if colour == "black":
        return "black"
    r, g, b = mcolors.to_rgb(colour)
    return (0.45 * r, 0.45 * g, 0.45 * b)


def _diverged_at(status: str) -> float | None:
    if not status.startswith("diverged at t = "):
        return None
    try:
        return float(status.removeprefix("diverged at t = ").split()[0])
    except (ValueError, IndexError):  # a status text netsim did not write: no divergence line to draw
        return None


def _clip_to_scale(ax: Any, t: np.ndarray, series: dict[str, np.ndarray], colours: dict[str, str],
                   t_div: float) -> bool:
    """Clip the axes to the signals' scale over the first half of the run before ``t_div``; mark the points
    where a signal leaves the axes. True when clipped."""
    early = t < 0.5 * t_div if t_div > 0 else np.ones_like(t, dtype=bool)
    ref = [np.abs(v[early & np.isfinite(v)]) for v in series.values()]
    scale = max((float(r.max()) for r in ref if r.size), default=0.0)
    peak = max((float(np.abs(v[np.isfinite(v)]).max()) for v in series.values() if np.isfinite(v).any()),
               default=0.0)
    has_nonfinite = any(not np.isfinite(v[~np.isnan(v)]).all() for v in series.values())
    if scale <= 0.0 or (peak <= 10.0 * scale and not has_nonfinite):
        return False
    lim = 2.0 * scale
    ax.set_ylim(-lim, lim)
    for name, v in series.items():
        out = np.flatnonzero(~np.isnan(v) & (np.abs(v) > lim))
        if out.size:
            i = int(out[0])
            up = v[i] > 0
            ax.plot([t[i]], [0.97 * lim if up else -0.97 * lim], "^" if up else "v", color=colours[name],
                    markersize=9, markeredgecolor="black", linestyle="none")
    ax.annotate(f"clipped to the scale before divergence (|values| reach {peak:.3g})", (0.01, 0.97),
                xycoords="axes fraction", fontsize=8, va="top",
                bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "none"})
    return True


def _panels(names: list[str], roles: Mapping[str, str], units: Mapping[str, str],
            scenario: Mapping[str, Any] | None) -> list[tuple[str, list[str]]]:
    """``(y label, signals)`` per panel: one panel per kind and unit, so that signals of different units never
    share an axis; a vector signal (``x_hat[0]``...) whose unit nobody declared gets a panel of its own."""
    measured = {str((ch or {}).get("output")) for ch in ((scenario or {}).get("io") or {}).values()
                if isinstance(ch, Mapping) and ch.get("type") in ("adc", "encoder")
                and isinstance((ch or {}).get("output"), str)}
    driven = {str((ch or {}).get("input")) for ch in ((scenario or {}).get("io") or {}).values()
              if isinstance(ch, Mapping) and ch.get("type") == "dac" and isinstance((ch or {}).get("input"), str)}

    def kind(n: str) -> str:
        role = roles.get(n, roles.get(n.split("[", 1)[0], ""))
        if role in ("sensor", "reference") or n in measured:
            return "sensor"
        if role == "actuator" or n in driven:
            return "actuator"
        return "other"

    heading = {"sensor": "output", "actuator": "input", "other": "value"}
    order: list[tuple[str, str]] = []
    members: dict[tuple[str, str], list[str]] = {}
    for n in names:
        k, unit = kind(n), units.get(n, units.get(n.split("[", 1)[0], ""))
        if roles and k == "sensor" and not unit and roles.get(n.split("[", 1)[0]) == "reference":
            unit = ""  # a reference without a unit: beside the outputs without one
        key = (k, unit) if unit or "[" not in n else (k, "[vector]" + n.split("[", 1)[0])
        if key not in members:
            order.append(key)
            members[key] = []
        members[key].append(n)
    rank = {"sensor": 0, "actuator": 1, "other": 2}
    order.sort(key=lambda key: rank[key[0]])
    panels = []
    for k, unit in order:
        if unit.startswith("[vector]"):
            label = f"{signal_label(unit.removeprefix('[vector]'))} (units of its components)"
        elif unit:
            label = f"{heading[k]} ({unit})"
        else:
            label = f"{heading[k]} (unit not declared)"
        panels.append((label, members[(k, unit)]))
    return panels


def _numbered_ports(scenario: Mapping[str, Any] | None) -> tuple[list[str], list[str]] | None:
    """The plant's ``(output names, input names)`` when an io channel with a ``unit:`` names its plant port by
    number (``output: 0``, as the cart's encoder does), so that the unit reaches the recorded output; None
    otherwise, or when the plant cannot be built here (the plant is built again, as ``to_timeresponse`` does)."""
    channels = (scenario or {}).get("io") or {}
    numbered = any(isinstance(ch, Mapping) and ch.get("unit") and isinstance(ch.get("output", ch.get("input")), int)
                   for ch in channels.values())
    if not numbered:
        return None
    from netsim.results.interop import _plant_names

    names = _plant_names(scenario)
    return (names[1], names[2]) if names is not None else None


def first_transient(t: np.ndarray, outputs: Mapping[str, np.ndarray],
                    references: Mapping[str, np.ndarray]) -> tuple[float, float] | None:
    """``(t0, t1)`` around the run's first transient, or None when there is none worth a zoom.

    The transient starts at 0 when an output starts away from its final value, else at the first change of
    a reference; it ends when every output has stayed within :data:`SETTLE_BAND` of its range around the value
    it holds before the next reference change (or at the end). None when it lasts more than
    :data:`ZOOM_SHARE` of the run (the full view shows it) or the outputs never settle.
    """
    if t.size < 3 or not outputs:
        return None
    changes = sorted({float(t[i]) for v in references.values() if v.size == t.size
                      for i in np.flatnonzero(np.abs(np.diff(v)) > 0) + 1})
    span = float(t[-1] - t[0])
    if span <= 0:
        return None

    def settle(start: float, stop: float) -> float | None:
        sel = (t >= start) & (t < stop) if stop > start else t >= start
        if sel.sum() < 3:
            return None
        ends = []
        for v in outputs.values():
            seg, tt = v[sel], t[sel]
            finite = seg[np.isfinite(seg)]
            if finite.size < 3:
                return None
            whole = v[np.isfinite(v)]
            band = SETTLE_BAND * float(whole.max() - whole.min())
            if band <= 0:
                continue
            final = float(np.median(finite[-max(3, finite.size // 10):]))
            away = np.flatnonzero(~(np.abs(seg - final) <= band))
            ends.append(float(tt[min(away[-1] + 1, tt.size - 1)]) if away.size else start)
        return max(ends) if ends else None

    t0 = float(t[0])
    stop = changes[0] if changes else float(t[-1])
    end = settle(t0, stop)
    if end is None or end <= t0 + 1e-12 * span:  # nothing moves before the first change: zoom on that change
        if not changes:
            return None
        t0 = changes[0]
        later = [c for c in changes if c > t0]
        end = settle(t0, later[0] if later else float(t[-1]))
        if end is None or end <= t0:
            return None
    length = end - t0
    if length > ZOOM_SHARE * span:
        return None
    return max(float(t[0]), t0 - 0.1 * length), min(float(t[-1]), end + 0.5 * length)


def responses_figure(signals: pd.DataFrame, scenario: Mapping[str, Any] | None = None, *, status: str = "ok",
                     title: str = "", fig: Any = None, zoom: Any = None) -> Any:
    """Recorded signals over time (held between samples), a panel per kind and unit, one colour per loop, and a
    zoom on the first transient.

    Parameters
    ----------
    signals : pandas.DataFrame
        The run's signals table (``time_s`` first).
    scenario : Mapping, optional
        The resolved scenario (``RunResult.scenario``): the source of each signal's kind, loop and unit (the io
        channels' ``unit:``, :func:`signal_units`). Without it every signal is drawn in one panel.
    status : str, default "ok"
        The run's status; a ``diverged at t = ...`` run is clipped to its scale before divergence.
    title : str, optional
        Figure title (default: ``responses``).
    fig : matplotlib.figure.Figure or SubFigure, optional
        An empty figure to draw the panels into (default: a new :class:`InlineFigure`).
    zoom : bool or tuple of float, optional
        A last panel showing the first panel's signals over ``(t0, t1)``; None (default): over the first
        transient when it is short (:func:`first_transient`); False: no zoom.

    Returns
    -------
    matplotlib.figure.Figure
        ``fig``, or the new figure.
    """
    from netsim.figure_style import TIME_LABEL

    names = [c for c in signals.columns if c != "time_s"]
    roles = signal_roles(scenario)
    units = signal_units(scenario, _numbered_ports(scenario))
    loops = signal_loops(scenario)
    colours = _colours(names, loops, roles)
    if roles or units:
        panels = _panels(names, roles, units, scenario)
    else:
        panels = [("value (units of each signal)", names)]
    if not panels:
        panels = [("nothing recorded", [])]
    t = signals["time_s"].to_numpy(dtype=float)
    t_div = _diverged_at(status)

    def is_ref(n: str) -> bool:
        return roles.get(n.split("[", 1)[0]) == "reference"

    window = None
    if zoom is not False and t_div is None and panels[0][1]:
        if isinstance(zoom, (tuple, list)):
            window = (float(zoom[0]), float(zoom[1]))
        else:
            first = panels[0][1]
            window = first_transient(
                t, {n: signals[n].to_numpy(dtype=float) for n in first if not is_ref(n)},
                {n: signals[n].to_numpy(dtype=float) for n in first if is_ref(n)})
    n_axes = len(panels) + (window is not None)
    if fig is None:
        fig = _figure(9, 2.2 * n_axes + 0.6)
    grid = fig.subplots(n_axes, 1, squeeze=False)[:, 0]
    axes = list(grid[:len(panels)])
    for ax in axes[1:]:
        ax.sharex(axes[0])
    for ax in axes[:-1]:
        ax.tick_params(labelbottom=False)

    def draw(ax: Any, group: list[str]) -> dict[str, np.ndarray]:
        series = {n: signals[n].to_numpy(dtype=float) for n in group}
        for n, v in series.items():
            ref = is_ref(n)
            ax.plot(t, v, drawstyle="steps-post", label=signal_label(n), linewidth=1.2 if ref else 1.0,
                    color=_reference_colour(colours[n]) if ref else colours[n], linestyle="--" if ref else "-")
        ax.grid(True, alpha=0.3)
        return series

    for ax, (label, group) in zip(axes, panels):
        series = draw(ax, group)
        if t_div is not None and series:
            _clip_to_scale(ax, t, series, colours, t_div)
            ax.axvline(t_div, color="red", linestyle=":", linewidth=1.2, label=f"diverged at {t_div:.6g} s")
        ax.set_ylabel(label)
        if group:
            ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8, frameon=False)
    # a scenario's name is an identifier (three_servos_edf): shown in words, as the figures show every name
    axes[0].set_title(title.replace("_", " ") if re.fullmatch(r"[A-Za-z0-9_-]+", title) else (title or "responses"))
    axes[-1].set_xlabel(TIME_LABEL)
    if window is not None:
        zax = grid[-1]
        draw(zax, panels[0][1])
        zax.set_xlim(*window)
        inside = (t >= window[0]) & (t <= window[1])
        vals = np.concatenate([signals[n].to_numpy(dtype=float)[inside] for n in panels[0][1]])
        vals = vals[np.isfinite(vals)]
        if vals.size:
            lo, hi = float(vals.min()), float(vals.max())
            pad = 0.08 * (hi - lo) if hi > lo else 0.5 * max(abs(hi), 1.0)
            zax.set_ylim(lo - pad, hi + pad)
        zax.set_ylabel(panels[0][0])
        zax.set_xlabel(f"{TIME_LABEL}: first transient, {window[0]:.3g} s to {window[1]:.3g} s")
        for ax in axes:
            ax.axvspan(*window, color="0.85", alpha=0.5, zorder=0, lw=0)
    return fig


def save_figures(result: Any, out_dir: str | Path, *, window: Any = None) -> list[Path]:
    """Write ``responses.png``, ``schedule.png`` (when a kernel traced) and ``network.png`` (when a message
    was sent) into ``out_dir``; returns the files written."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    name = str(result.meta.get("scenario", ""))
    end_s = float(result.meta.get("t_end_s") or 0.0)
    written = []
    fig = responses_figure(result.signals, result.scenario, status=result.status, title=name)
    fig.savefig(out / "responses.png")
    written.append(out / "responses.png")
    if result.schedule is not None and not result.schedule.empty:
        schedule_figure(result.schedule, result.jobs, window=window, end_s=end_s).savefig(out / "schedule.png")
        written.append(out / "schedule.png")
    if result.messages is not None and not result.messages.empty:
        network_figure(result.messages, window=window, end_s=end_s).savefig(out / "network.png")
        written.append(out / "network.png")
    return written


def plot_run(result: Any, out_dir: str | Path, window: Any = None) -> list[Path]:
    """The run's figures as PNG files in ``out_dir`` (:func:`save_figures`)."""
    return save_figures(result, out_dir, window=window)


#: Positive values spanning more than this ratio are drawn on a log axis (a 10 us and a 100 ms bar both show).
LOG_SPAN = 100.0


def bar_figure(frame: pd.DataFrame, label_cols: list[str], value_cols: list[str], *, title: str = "",
               xlabel: str = "") -> Any:
    """Horizontal bars, one group per row of ``frame`` (labelled by ``label_cols``), one bar per value column.

    The value axis is logarithmic when the positive values span more than :data:`LOG_SPAN` (response times
    from microseconds to tenths of a second); ``xlabel`` names it with its unit. None when nothing has a value.
    """
    data = frame.dropna(subset=value_cols, how="all")
    if data.empty:
        return None
    labels = [" / ".join(str(r[c]) for c in label_cols) for _, r in data.iterrows()]
    y = np.arange(len(data))
    height = 0.8 / len(value_cols)
    fig = _figure(9, 1.4 + 0.35 * len(data) * max(1, len(value_cols) / 2))
    ax = fig.subplots()
    values = data[value_cols].to_numpy(dtype=float)
    for i, col in enumerate(value_cols):
        ax.barh(y + i * height, values[:, i], height=height, label=col)
    positive = values[np.isfinite(values) & (values > 0)]
    if positive.size and positive.max() / positive.min() > LOG_SPAN:
        ax.set_xscale("log")  # the decade ticks say so: no "(log axis)" in the label (one style, issue 27)
    ax.set_yticks(y + height * (len(value_cols) - 1) / 2, labels, fontsize=8)
    ax.invert_yaxis()
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax.set_title(title)
    ax.set_xlabel(xlabel)
    ax.grid(axis="x", alpha=0.3)
    return fig
