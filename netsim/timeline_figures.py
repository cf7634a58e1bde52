"""Time-line figures of one run: the Gantt chart of the kernels' schedules and the network timeline.

Both show, by default, the window in which every job (message) and every gap between two of a row spans
:data:`MIN_FEATURE_PX` pixels at :data:`PX_PER_INCH` (:func:`density_window`): the whole run when it fits, so
that no job is lost to aliasing (a 2 s run of 0.5 ms jobs drawn whole showed about a quarter of them). The Gantt
chart marks releases and deadlines, draws zero-length jobs as ticks and puts deadline misses on a row of their
own; the network timeline draws a tick where a message took no time and keeps its key in a legend.
:mod:`netsim.plotting` re-exports everything here.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd

from netsim.inline_figure import figure_and_axes as _axes

__all__ = ["MAX_BARS", "PX_PER_INCH", "MIN_FEATURE_PX", "resolve_window", "density_window", "schedule_figure",
           "network_figure"]

#: Bars a Gantt chart or network timeline shows by default: the whole run up to this many intervals.
MAX_BARS = 3000

#: Pixels per inch the density rule assumes: the lowest resolution the figures are saved at (the README's
#: examples use 72 dpi); at any higher resolution every job is wider still.
PX_PER_INCH = 72
#: Pixels the shortest job and the shortest gap between two jobs of a row span in a chosen Gantt window.
MIN_FEATURE_PX = 2
#: Share of a Gantt chart's width the time axis takes (the rest: row names and the legend).
_PLOT_SHARE = 0.7


class _LabelOnce:
    """A legend labeller: each label the first time it is asked for, None after (one legend entry per kind);
    ``seen`` holds the labels given out."""

    def __init__(self) -> None:
        self.seen: set[str] = set()

    def __call__(self, label: str) -> str | None:
        if label in self.seen:
            return None
        self.seen.add(label)
        return label


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


def density_window(rows: list[tuple[np.ndarray, np.ndarray]], end_s: float, width_px: float, *,
                   gaps: bool | None = True) -> tuple[float, float]:
    """The Gantt window ``(0, t1)`` at which every interval and every gap between two intervals of a row is at
    least :data:`MIN_FEATURE_PX` pixels wide, on a time axis ``width_px`` pixels wide: the whole run when that
    holds for it.

    ``rows`` holds each row's interval starts and ends in seconds (a zero-length interval, drawn as a tick,
    counts through its gaps only). ``gaps=False`` measures the intervals only; ``None``: the gaps only when no
    interval has a length (a network timeline: a retransmission a few microseconds after a frame need not be
    told apart from it, but instants of a zero-delay link must). With nothing to measure, the whole run.
    """
    smallest = math.inf
    widest = 0.0
    smallest_gap = math.inf
    last = 0.0
    for starts, ends in rows:
        order = np.argsort(starts, kind="stable")
        s, e = np.asarray(starts, float)[order], np.asarray(ends, float)[order]
        ok = np.isfinite(s) & np.isfinite(e)
        s, e = s[ok], e[ok]
        if not s.size:
            continue
        last = max(last, float(e.max()))
        width = e - s
        if (width > 0).any():
            smallest = min(smallest, float(width[width > 0].min()))
            widest = max(widest, float(width.max()))
        between = s[1:] - np.maximum.accumulate(e)[:-1]
        if (between > 0).any():
            smallest_gap = min(smallest_gap, float(between[between > 0].min()))
    if gaps or (gaps is None and widest == 0.0):
        smallest = min(smallest, smallest_gap)
    end = float(end_s) if end_s and math.isfinite(end_s) and end_s > 0 else max(last, 1e-9)
    if not math.isfinite(smallest):
        return 0.0, end
    return 0.0, min(end, max(smallest * width_px / MIN_FEATURE_PX, 1e-9))


def _axis_px(fig: Any, ax: Any) -> float:
    """Pixels of ``ax``'s width at :data:`PX_PER_INCH`: its share of the figure's width, at most
    :data:`_PLOT_SHARE` (before the layout runs, the axes' position is matplotlib's default, wider than the room
    the row names and the legend leave)."""
    share = min(float(ax.get_position().width), _PLOT_SHARE)
    return max(50.0, share * float(fig.get_figwidth()) * PX_PER_INCH)


def _window_note(t0: float, t1: float, end_s: float, chosen: str = "") -> str:
    if t0 == 0.0 and end_s and t1 >= end_s:
        return "whole run"
    span = f"{t0:.3g} s to {t1:.3g} s of {end_s:.3g} s" if end_s else f"{t0:.3g} s to {t1:.3g} s"
    return span + (f", every {chosen} {MIN_FEATURE_PX} px wide or more" if chosen else "")


def _missed(jobs: pd.DataFrame) -> pd.Series:
    if "outcome" in jobs:
        return jobs["outcome"].isin(["missed", "killed"])
    return jobs["deadline_met"].astype(str).str.lower() == "false"


def schedule_figure(schedule: pd.DataFrame, jobs: pd.DataFrame | None = None, *, window: Any = None,
                    end_s: float = 0.0, title: str = "", ax: Any = None) -> Any:
    """Gantt chart: per node and task, running intervals (solid), ready intervals (light), zero-length jobs
    (ticks), each job's release (up triangle under the row) and deadline (down triangle over it), and the
    deadline misses on a row of their own, on ``ax`` (default: a new figure's axes).

    ``window`` is ``(t0, t1)`` or a length (see :func:`resolve_window`); by default the window in which every
    job and every gap between two jobs spans :data:`MIN_FEATURE_PX` pixels (:func:`density_window`), the whole run when it
    fits, so that no job is lost to aliasing. Returns the figure drawn on.
    """
    from netsim.figure_style import TIME_LABEL

    jobs = jobs if jobs is not None and not jobs.empty else None
    keys = set()
    if schedule is not None and not schedule.empty:
        keys |= set(zip(schedule["node"], schedule["task"]))
    if jobs is not None:
        keys |= set(zip(jobs["node"], jobs["task"]))  # a task whose jobs take no time has no schedule rows
    rows = sorted(keys)
    has_miss = jobs is not None and bool(_missed(jobs).any())
    fig, ax = _axes(ax, 10, 0.5 * max(1, len(rows) + has_miss) + 1.8)
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel("node.task")
    if not rows:
        ax.set_title(title or "schedule: no kernel trace")
        return fig
    if schedule is None or schedule.empty:
        schedule = pd.DataFrame({"node": [], "task": [], "state": [], "start_s": [], "end_s": []})
    start = pd.to_numeric(schedule["start_s"]).to_numpy(dtype=float)
    stop = pd.to_numeric(schedule["end_s"]).to_numpy(dtype=float)
    sched = schedule.assign(start_s=start, end_s=stop)
    jstart = pd.to_numeric(jobs["start_s"]).to_numpy(dtype=float) if jobs is not None else np.zeros(0)
    jfinish = pd.to_numeric(jobs["finish_s"]).to_numpy(dtype=float) if jobs is not None else np.zeros(0)
    zero = (jfinish == jstart) if jobs is not None else np.zeros(0, dtype=bool)
    run_end = end_s or float(np.nanmax(np.concatenate([stop, jfinish, [0.0]])))
    chosen = window is None
    if chosen:
        spans = []
        for node, task in rows:
            sel = (sched["node"] == node) & (sched["task"] == task) & (sched["state"] == "running")
            s, e = sched["start_s"][sel].to_numpy(), sched["end_s"][sel].to_numpy()
            if jobs is not None:
                mine = ((jobs["node"] == node) & (jobs["task"] == task)).to_numpy() & zero
                s, e = np.concatenate([s, jstart[mine]]), np.concatenate([e, jstart[mine]])
            spans.append((s, e))
        t0, t1 = density_window(spans, run_end, _axis_px(fig, ax))
        t1 = min(t1, resolve_window(None, start, run_end)[1]) if start.size else t1
    else:
        t0, t1 = resolve_window(window, start, run_end)
    colours = {"running": "tab:blue", "ready": "tab:orange", "blocked": "tab:gray"}
    heights = {"running": 0.5, "ready": 0.2, "blocked": 0.12}
    inside = (sched["start_s"] < t1) & (sched["end_s"] > t0)
    sched = sched[inside]
    once = _LabelOnce()

    for i, (node, task) in enumerate(rows):
        sel = sched[(sched["node"] == node) & (sched["task"] == task)]
        for state, grp in sel.groupby("state"):
            bars = [(max(s, t0), min(e, t1) - max(s, t0)) for s, e in zip(grp["start_s"], grp["end_s"]) if e > s]
            if bars:
                h = heights.get(state, 0.2)
                c = colours.get(state, "tab:green")
                # an edge as wide as a thin line: a bar narrower than a pixel still shows
                ax.broken_barh(bars, (i - h / 2, h), facecolors=c, edgecolors=c, linewidth=0.5, label=once(state))
        if "core" in sel.columns:  # a multicore node: the core that ran each running interval (c0, c1, ...)
            run = sel[(sel["state"] == "running") & sel["core"].notna()]
            if len(run) <= 300:
                for s, e, core in zip(run["start_s"], run["end_s"], run["core"]):
                    a, b = max(s, t0), min(e, t1)
                    if b > a:
                        ax.text((a + b) / 2, i, f"c{int(core)}", ha="center", va="center", fontsize=6,
                                color="white", clip_on=True)
        if jobs is None:
            continue
        mine = ((jobs["node"] == node) & (jobs["task"] == task)).to_numpy()
        ticks = jstart[mine & zero & (jstart >= t0) & (jstart <= t1)]
        if ticks.size:
            ax.plot(ticks, np.full(ticks.size, float(i)), "|", color="tab:blue", markersize=9, markeredgewidth=1.2,
                    linestyle="none", label=once("zero-length job"))
        rel = pd.to_numeric(jobs["release_s"][mine]).to_numpy(dtype=float)
        rel = rel[(rel >= t0) & (rel <= t1)]
        if rel.size:
            ax.plot(rel, np.full(rel.size, i + 0.36), "^", color="0.2", markersize=3, linestyle="none",
                    label=once("release"))
        dl = pd.to_numeric(jobs["deadline_s"][mine]).to_numpy(dtype=float)
        dl = dl[np.isfinite(dl) & (dl >= t0) & (dl <= t1)]
        if dl.size:
            ax.plot(dl, np.full(dl.size, i - 0.36), "v", color="tab:purple", markersize=3, linestyle="none",
                    label=once("deadline"))
    labels = [f"{n}.{t}" for n, t in rows]
    if has_miss and jobs is not None:
        late = jobs[_missed(jobs)]
        at = pd.to_numeric(late["deadline_s"]).to_numpy(dtype=float)
        shown = (at >= t0) & (at <= t1)
        who = sorted({f"{n}.{t}" for n, t in zip(late["node"][shown], late["task"][shown])})
        at = at[shown]
        row = float(len(rows))
        if at.size:
            ax.plot(at, np.full(at.size, row), "x", color="red", markersize=6, markeredgewidth=1.2, linestyle="none",
                    label=once("deadline miss"))
        ax.axhline(row - 0.5, color="0.6", linewidth=0.6)
        labels.append(f"deadline misses ({at.size}{': ' + ', '.join(who) if 0 < len(who) <= 2 else ''})")
    ax.set_yticks(range(len(labels)), labels)
    ax.set_ylim(len(labels) - 0.5, -0.5)
    ax.set_xlim(t0, t1)
    ax.set_title(title or f"schedule ({_window_note(t0, t1, run_end, 'job' if chosen else '')})")
    ax.grid(True, axis="x", alpha=0.3)
    if once.seen:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    return fig


def network_figure(messages: pd.DataFrame, *, window: Any = None, end_s: float = 0.0, title: str = "",
                   ax: Any = None) -> Any:
    """Per network and sender: transmissions (tx start to end); for media without a bit rate, the delay (sent
    to delivered) as a thin bar, and a tick at the instant of each message that took no time (a zero-delay
    link); each dropped copy a red cross at its send instant. The key is a legend. Over ``window`` (default:
    messages :data:`MIN_FEATURE_PX` pixels apart or more, :func:`density_window`), on ``ax`` (default: a new figure's axes).
    Returns the figure drawn on."""
    from netsim.figure_style import TIME_LABEL

    rows = sorted({(n, s) for n, s in zip(messages["network"], messages["sender"])}) if messages is not None \
        and not messages.empty else []
    fig, ax = _axes(ax, 10, 0.5 * max(1, len(rows)) + 1.8)
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel("network: sender")
    if not rows:
        ax.set_title(title or "network: no messages")
        return fig
    sent = messages["sent_s"].to_numpy(dtype=float)
    tx0 = pd.to_numeric(messages["tx_start_s"]).to_numpy(dtype=float)
    tx1 = pd.to_numeric(messages["tx_end_s"]).to_numpy(dtype=float)
    timed_all = np.isfinite(tx0) & np.isfinite(tx1) & (tx1 > tx0)
    first = np.where(timed_all, tx0, sent)
    last = np.where(timed_all, tx1, sent)
    run_end = end_s or float(np.nanmax(sent))
    chosen = window is None
    if chosen:
        spans = [(first[m], last[m]) for m in ((messages["network"] == n) & (messages["sender"] == s)
                                                for n, s in rows)]
        t0, t1 = density_window(spans, run_end, _axis_px(fig, ax), gaps=None)
        t1 = min(t1, resolve_window(None, sent, run_end)[1])
    else:
        t0, t1 = resolve_window(window, sent, run_end)
    dropped_all = messages["dropped"].astype(str).str.lower() == "true"
    msgs = messages[(sent >= t0) & (sent <= t1)]
    dropped = dropped_all[msgs.index]
    once = _LabelOnce()

    n_drop = 0
    for i, (net, sender) in enumerate(rows):
        mine = (msgs["network"] == net) & (msgs["sender"] == sender)
        sel, lost = msgs[mine], dropped[mine]
        s_tx, e_tx = pd.to_numeric(sel["tx_start_s"]), pd.to_numeric(sel["tx_end_s"])
        timed = s_tx.notna() & e_tx.notna() & (e_tx > s_tx)
        spans_tx = [(s, e - s) for s, e in zip(s_tx[timed & ~lost], e_tx[timed & ~lost])]
        if spans_tx:
            ax.broken_barh(spans_tx, (i - 0.3, 0.6), facecolors="tab:blue", edgecolors="tab:blue", linewidth=0.5,
                           label=once("transmission"))
        lost_tx = [(s, e - s) for s, e in zip(s_tx[timed & lost], e_tx[timed & lost])]
        if lost_tx:
            ax.broken_barh(lost_tx, (i - 0.3, 0.6), facecolors="tab:red", edgecolors="tab:red", linewidth=0.5,
                           label=once("lost transmission"))
        delivered = pd.to_numeric(sel["delivered_s"])
        untimed = ~timed & ~lost & delivered.notna()
        delay = delivered - sel["sent_s"]
        spans_delay = [(s, d) for s, d in zip(sel["sent_s"][untimed & (delay > 0)], delay[untimed & (delay > 0)])]
        if spans_delay:
            ax.broken_barh(spans_delay, (i - 0.12, 0.24), facecolors="tab:cyan", edgecolors="tab:cyan",
                           linewidth=0.5, label=once("delay (no bit rate)"))
        instants = sel["sent_s"][untimed & (delay <= 0)].to_numpy(dtype=float)
        if instants.size:
            ax.plot(instants, np.full(instants.size, float(i)), "|", color="tab:cyan", markersize=9,
                    markeredgewidth=1.2, linestyle="none", label=once("message taking no time"))
        if lost.any():
            ax.plot(sel["sent_s"][lost], np.full(int(lost.sum()), float(i)), "x", color="red", markersize=7,
                    linestyle="none", label=once("dropped copy"))
            n_drop += int(lost.sum())
    ax.set_yticks(range(len(rows)), [f"{n}: {s}" for n, s in rows])
    ax.set_ylim(len(rows) - 0.5, -0.5)
    ax.set_xlim(t0, t1)
    ax.set_title(title or f"network ({_window_note(t0, t1, run_end, 'message' if chosen else '')}; {n_drop} dropped)")
    ax.grid(True, axis="x", alpha=0.3)
    if once.seen:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    return fig
