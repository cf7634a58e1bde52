"""Figures of one run: responses and control signals, the schedule (Gantt chart), the network timeline.

Each ``*_figure`` function returns a :class:`matplotlib.figure.Figure` (no pyplot state, no display needed;
``fig.savefig(path)`` saves it). A figure made here is an :class:`InlineFigure`, which a fresh Jupyter kernel shows
inline without ``%matplotlib inline`` (a bare ``Figure`` shows there as its text repr unless the inline backend
is active). Each takes the axes (``ax=``) or, with several panels, the figure (``fig=``) to draw into, and returns
the figure drawn on. :meth:`netsim.results.RunResult.plot`,
``plot_schedule`` and ``plot_network`` call them; :func:`save_figures` (``netsim run --plot``,
``result.plot(save=DIR)``) writes ``responses.png``, ``schedule.png`` and ``network.png``.

What the figures follow:

- Panels by the signal's declared kind (:func:`signal_roles`): the scenario's ``io`` channels (ADC and encoder:
  sensor, DAC: actuator) and ``signals`` (reference); anything else (states, estimates) in a third panel.
- One colour per loop (:func:`signal_loops`): a task's ``reference``, ``channel`` and ``output_channel`` and a
  metric's ``reference`` and ``output`` share their colour; references are dashed.
- Every axis names its unit: time in seconds; a signal's value in the unit of the plant output or input it
  measures or drives (netsim does not know it: the label says so).
- A diverged run is clipped to the loop's scale before it diverged, with a marker where a signal leaves the
  axes and a line at the divergence instant (a 1e10 scale would flatten everything else).
- The Gantt chart and network timeline show the whole run when it has at most :data:`MAX_BARS` intervals,
  else its beginning up to that many; ``window`` chooses (``netsim run --plot-window``).
- Network timelines show every message: transmissions (tx start to end) where the medium has a bit rate, the
  delay (sent to delivered) where it has none, and a red cross at the send instant of each dropped copy.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pandas as pd
from matplotlib.figure import Figure  # not pyplot: no backend, no global figure list

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
    "resolve_window",
    "MAX_BARS",
]

log = logging.getLogger(__name__)

#: Bars a Gantt chart or network timeline shows by default: the whole run up to this many intervals.
MAX_BARS = 3000

_PANELS = (
    ("sensor", "outputs and references\n[plant output units]"),
    ("actuator", "actuator values\n[plant input units]"),
    ("other", "other recorded signals\n[their own units]"),
)


class InlineFigure(Figure):
    """A matplotlib ``Figure`` that IPython and Jupyter show as a PNG, without pyplot or the inline backend.

    Examples
    --------
    >>> fig = InlineFigure(figsize=(2, 1))
    >>> fig._repr_png_()[:4] == bytes([0x89]) + b"PNG"
    True
    """

    def _repr_png_(self) -> bytes:
        import io

        buf = io.BytesIO()
        self.savefig(buf, format="png", bbox_inches="tight")
        return buf.getvalue()


def _figure(width: float, height: float) -> Any:
    return InlineFigure(figsize=(width, height), dpi=100, layout="constrained")


def _axes(ax: Any, width: float, height: float) -> tuple[Any, Any]:
    """``(figure, axes)``: the given axes and their figure, else one new axes on a new figure of this size."""
    if ax is not None:
        try:
            return ax.get_figure(root=True), ax  # the figure itself, also for axes in a subfigure
        except TypeError:  # matplotlib < 3.10: no root argument
            return ax.figure, ax
    fig = _figure(width, height)
    return fig, fig.subplots()


def signal_roles(scenario: Mapping[str, Any] | None) -> dict[str, str]:
    """Each declared signal's kind from the scenario: ``sensor``, ``actuator`` or ``reference``.

    ``io`` channels of type ``adc`` and ``encoder`` are sensors, ``dac`` actuators (also their
    ``<name>.command``), ``signals`` entries references. Names the scenario does not declare are absent.
    """
    roles: dict[str, str] = {}
    if not scenario:
        return roles
    for name, ch in (scenario.get("io") or {}).items():
        kind = (ch or {}).get("type") if isinstance(ch, Mapping) else None
        if kind == "dac":
            roles[name] = roles[f"{name}.command"] = "actuator"
        elif kind in ("adc", "encoder"):
            roles[name] = "sensor"
    for name in scenario.get("signals") or {}:
        roles.setdefault(name, "reference")
    return roles


def signal_loops(scenario: Mapping[str, Any] | None) -> list[list[str]]:
    """Groups of signals that belong to one loop, from declared parameters (never from their names).

    A task's or handler's ``channel`` (the measured output), ``output_channel`` and ``reference`` form a loop,
    and a metric's ``output`` and ``reference``; loops sharing an output or an actuator merge. A reference that
    several loops follow (three servos on one set-point) belongs to none of them: it is drawn in black.
    """
    loops: list[tuple[set[str], set[str]]] = []  # (outputs and actuators, references)

    def add(own: list[Any], refs: list[Any]) -> None:
        mine = {n for n in own if isinstance(n, str) and n}
        follows = {n for n in refs if isinstance(n, str) and n}
        if not mine:
            return
        for loop in [lp for lp in loops if lp[0] & mine]:
            mine |= loop[0]
            follows |= loop[1]
            loops.remove(loop)
        loops.append((mine, follows))

    if scenario:
        for node in (scenario.get("nodes") or {}).values():
            for kind in ("tasks", "handlers"):
                for entry in (node or {}).get(kind) or []:
                    p = (entry or {}).get("params") or {}
                    add([p.get("channel"), p.get("output_channel")], [p.get("reference")])
        for metric in scenario.get("metrics") or []:
            p = (metric or {}).get("params") or {}
            add([p.get("output")], [p.get("reference")])
    followed = [r for _, refs in loops for r in refs]
    shared = {r for r in followed if followed.count(r) > 1}
    groups = [sorted(own | (refs - shared)) for own, refs in loops]
    return [g for g in groups if len(g) > 1]


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


def responses_figure(signals: pd.DataFrame, scenario: Mapping[str, Any] | None = None, *, status: str = "ok",
                     title: str = "", fig: Any = None) -> Any:
    """Recorded signals over time (held between samples), in panels by declared kind, one colour per loop.

    Parameters
    ----------
    signals : pandas.DataFrame
        The run's signals table (``time_s`` first).
    scenario : Mapping, optional
        The resolved scenario (``RunResult.scenario``): the source of each signal's kind and loop. Without it
        every signal is drawn in one panel.
    status : str, default "ok"
        The run's status; a ``diverged at t = ...`` run is clipped to its scale before divergence.
    title : str, optional
        Figure title (default: ``responses``).
    fig : matplotlib.figure.Figure or SubFigure, optional
        An empty figure to draw the panels into (default: a new :class:`InlineFigure`).

    Returns
    -------
    matplotlib.figure.Figure
        ``fig``, or the new figure.
    """
    names = [c for c in signals.columns if c != "time_s"]
    roles = signal_roles(scenario)
    loops = signal_loops(scenario)
    colours = _colours(names, loops, roles)
    if roles:
        kind = {n: {"sensor": "sensor", "reference": "sensor", "actuator": "actuator"}.get(
            roles.get(n, roles.get(n.split("[", 1)[0], "")), "other") for n in names}
        panels = [(label, [n for n in names if kind[n] == key]) for key, label in _PANELS]
        panels = [p for p in panels if p[1]]
    else:
        panels = [("recorded signals\n[their own units]", names)]
    if not panels:
        panels = [("nothing recorded", [])]
    if fig is None:
        fig = _figure(9, 2.8 * len(panels) + 0.6)
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    t = signals["time_s"].to_numpy(dtype=float)
    t_div = _diverged_at(status)
    for ax, (label, group) in zip(axes, panels):
        series = {n: signals[n].to_numpy(dtype=float) for n in group}
        for n, v in series.items():
            ref = roles.get(n.split("[", 1)[0]) == "reference"
            ax.plot(t, v, drawstyle="steps-post", label=n, linewidth=1.0, color=colours[n],
                    linestyle="--" if ref else "-")
        if t_div is not None and series:
            _clip_to_scale(ax, t, series, colours, t_div)
            ax.axvline(t_div, color="red", linestyle=":", linewidth=1.2, label=f"diverged at {t_div:.6g} s")
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        if group:
            ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8, frameon=False)
    axes[0].set_title(title or "responses")
    axes[-1].set_xlabel("time [s]")
    return fig


def resolve_window(window: Any, starts: pd.Series | np.ndarray, end_s: float) -> tuple[float, float]:
    """The time window ``(t0, t1)`` in seconds of a Gantt chart or timeline.

    ``window`` is ``(t0, t1)``, a length (from 0), or None: the whole run (``[0, end_s]``) when it has at most
    :data:`MAX_BARS` intervals, else from 0 to the start of the ``MAX_BARS``-th interval.
    """
    if window is not None:
        if isinstance(window, (tuple, list)):
            t0, t1 = (float(w) for w in window)
        else:
            t0, t1 = 0.0, float(window)
        if not (math.isfinite(t0) and math.isfinite(t1) and t1 > t0):
            raise ValueError(f"plot window must be a length > 0 or (start, end) with end > start, got {window!r}")
        return t0, t1
    s = np.sort(np.asarray(starts, dtype=float))
    s = s[np.isfinite(s)]
    end = float(end_s) if end_s and math.isfinite(end_s) and end_s > 0 else (float(s[-1]) if s.size else 1.0)
    if s.size > MAX_BARS:
        end = min(end, float(s[MAX_BARS - 1]))
    return 0.0, max(end, 1e-9)


def _window_note(t0: float, t1: float, end_s: float) -> str:
    if t0 == 0.0 and end_s and t1 >= end_s:
        return "whole run"
    return f"{t0:.6g} s to {t1:.6g} s of {end_s:.6g} s" if end_s else f"{t0:.6g} s to {t1:.6g} s"


def schedule_figure(schedule: pd.DataFrame, jobs: pd.DataFrame | None = None, *, window: Any = None,
                    end_s: float = 0.0, title: str = "", ax: Any = None) -> Any:
    """Gantt chart: per node and task, running intervals (solid), ready intervals (light), deadline misses
    (red triangles), over ``window`` (see :func:`resolve_window`), on ``ax`` (default: a new figure's axes).
    Returns the figure drawn on."""
    fig, ax = _axes(ax, 10, 0.5 * max(1, len(set(zip(schedule["node"], schedule["task"])))) + 1.8)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("node.task")
    if schedule is None or schedule.empty:
        ax.set_title(title or "schedule: no kernel trace")
        return fig
    start = pd.to_numeric(schedule["start_s"]).to_numpy(dtype=float)
    stop = pd.to_numeric(schedule["end_s"]).to_numpy(dtype=float)
    t0, t1 = resolve_window(window, start, end_s or float(np.nanmax(stop)))
    rows = sorted({(n, t) for n, t in zip(schedule["node"], schedule["task"])})
    colours = {"running": "tab:blue", "ready": "tab:orange", "blocked": "tab:gray"}
    heights = {"running": 0.6, "ready": 0.25, "blocked": 0.15}
    inside = (start < t1) & (stop > t0)
    sched = schedule[inside].assign(start_s=start[inside], end_s=stop[inside])
    seen: set[str] = set()
    for i, (node, task) in enumerate(rows):
        sel = sched[(sched["node"] == node) & (sched["task"] == task)]
        for state, grp in sel.groupby("state"):
            spans = [(max(s, t0), min(e, t1) - max(s, t0)) for s, e in zip(grp["start_s"], grp["end_s"]) if e > s]
            if spans:
                h = heights.get(state, 0.2)
                ax.broken_barh(spans, (i - h / 2, h), facecolors=colours.get(state, "tab:green"),
                               label=None if state in seen else state)
                seen.add(state)
        if jobs is not None and not jobs.empty:
            missed = jobs["outcome"].isin(["missed", "killed"]) if "outcome" in jobs else \
                jobs["deadline_met"].astype(str).str.lower() == "false"
            late = jobs[(jobs["node"] == node) & (jobs["task"] == task) & missed
                        & (jobs["deadline_s"] >= t0) & (jobs["deadline_s"] <= t1)]
            if len(late):
                ax.plot(late["deadline_s"], np.full(len(late), i + 0.4), "v", color="red", markersize=5,
                        linestyle="none", label=None if "deadline miss" in seen else "deadline miss")
                seen.add("deadline miss")
    ax.set_yticks(range(len(rows)), [f"{n}.{t}" for n, t in rows])
    ax.set_xlim(t0, t1)
    ax.set_title(title or f"schedule ({_window_note(t0, t1, end_s)})")
    ax.grid(True, axis="x", alpha=0.3)
    if seen:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    return fig


def network_figure(messages: pd.DataFrame, *, window: Any = None, end_s: float = 0.0, title: str = "",
                   ax: Any = None) -> Any:
    """Per network and sender: transmissions (tx start to end) or, for media without a bit rate, the delay
    (sent to delivered) as bars; each dropped copy a red cross at its send instant. Over ``window``, on ``ax``
    (default: a new figure's axes). Returns the figure drawn on."""
    rows = sorted({(n, s) for n, s in zip(messages["network"], messages["sender"])}) if messages is not None \
        and not messages.empty else []
    fig, ax = _axes(ax, 10, 0.5 * max(1, len(rows)) + 1.8)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("network: sender")
    if not rows:
        ax.set_title(title or "network: no messages")
        return fig
    sent = messages["sent_s"].to_numpy(dtype=float)
    t0, t1 = resolve_window(window, sent, end_s or float(np.nanmax(sent)))
    dropped_all = messages["dropped"].astype(str).str.lower() == "true"
    msgs = messages[(sent >= t0) & (sent < t1)]
    dropped = dropped_all[msgs.index]
    n_drop = 0
    for i, (net, sender) in enumerate(rows):
        mine = (msgs["network"] == net) & (msgs["sender"] == sender)
        sel, lost = msgs[mine], dropped[mine]
        # a medium without a bit rate records zero-length transmissions: draw its delays instead
        timed = sel["tx_start_s"].notna() & sel["tx_end_s"].notna() & (sel["tx_end_s"] > sel["tx_start_s"])
        spans_tx = [(s, e - s) for s, e in zip(sel["tx_start_s"][timed & ~lost], sel["tx_end_s"][timed & ~lost])]
        if spans_tx:
            ax.broken_barh(spans_tx, (i - 0.3, 0.6), facecolors="tab:blue")
        lost_tx = [(s, e - s) for s, e in zip(sel["tx_start_s"][timed & lost], sel["tx_end_s"][timed & lost])]
        if lost_tx:
            ax.broken_barh(lost_tx, (i - 0.3, 0.6), facecolors="tab:red")
        untimed = ~timed & ~lost & sel["delivered_s"].notna()
        spans_delay = [(s, e - s) for s, e in zip(sel["sent_s"][untimed], sel["delivered_s"][untimed])]
        if spans_delay:
            ax.broken_barh(spans_delay, (i - 0.12, 0.24), facecolors="tab:cyan")
        if lost.any():
            ax.plot(sel["sent_s"][lost], np.full(int(lost.sum()), float(i)), "x", color="red", markersize=7,
                    linestyle="none")
            n_drop += int(lost.sum())
    ax.set_yticks(range(len(rows)), [f"{n}: {s}" for n, s in rows])
    ax.set_xlim(t0, t1)
    ax.set_title(title or f"network ({_window_note(t0, t1, end_s)}): transmissions blue, delays without a bit "
                          f"rate cyan, {n_drop} dropped (red x)")
    ax.grid(True, axis="x", alpha=0.3)
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
        ax.set_xscale("log")
        xlabel = f"{xlabel} (log axis)" if xlabel else "(log axis)"
    ax.set_yticks(y + height * (len(value_cols) - 1) / 2, labels, fontsize=8)
    ax.invert_yaxis()
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax.set_title(title)
    ax.set_xlabel(xlabel)
    ax.grid(axis="x", alpha=0.3)
    return fig
