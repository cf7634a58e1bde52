"""Figures of one run: responses and control signals, the schedule (Gantt chart), the network timeline.

Used by ``netsim run --plot`` and :meth:`netsim.results.RunResult.plot`. Figures are drawn on
:class:`matplotlib.figure.Figure` objects with the Agg canvas (no pyplot state, no display needed).

Files written by :func:`plot_run`:

``responses.png``
    every recorded signal over time, held between samples; control signals (names starting with ``u``)
    in a second panel.
``schedule.png``
    per node and task: running intervals as solid bars, ready (preempted/waiting) intervals as light bars,
    deadline misses marked; over the first ``window_s`` seconds.
``network.png``
    per network and sender: transmissions (tx start to end) as bars, dropped frames in red; over the same
    window.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

__all__ = ["plot_run", "plot_responses", "plot_schedule", "plot_network", "DEFAULT_WINDOW_S"]

log = logging.getLogger(__name__)

#: Time window of the schedule and network figures (a whole run of 1 kHz tasks is unreadable).
DEFAULT_WINDOW_S = 0.1


def _figure(width: float, height: float) -> Any:
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), dpi=100, layout="constrained")


def _is_control(name: str) -> bool:
    return name.split(".")[-1].startswith("u")


def plot_responses(signals: pd.DataFrame, path: Path, title: str = "") -> Path | None:
    """Signals over time (step plots); control signals in a second panel. None when nothing was recorded."""
    names = [c for c in signals.columns if c != "time_s"]
    if not names:
        return None
    ctrl = [n for n in names if _is_control(n)]
    resp = [n for n in names if not _is_control(n)]
    panels = [p for p in (resp, ctrl) if p]
    fig = _figure(9, 3.0 * len(panels))
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    t = signals["time_s"].to_numpy()
    for ax, group in zip(axes, panels):
        for n in group:
            ax.plot(t, signals[n].to_numpy(dtype=float), drawstyle="steps-post", label=n, linewidth=1)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    axes[0].set_title(title or "responses")
    axes[-1].set_xlabel("time [s]")
    fig.savefig(path)
    return path


def plot_schedule(schedule: pd.DataFrame, jobs: pd.DataFrame, path: Path, window_s: float = DEFAULT_WINDOW_S,
                  title: str = "") -> Path | None:
    """Gantt chart of the kernels' schedule traces over ``[0, window_s]``. None when there is no trace."""
    if schedule is None or schedule.empty:
        return None
    sched = schedule[schedule["start_s"] < window_s]
    rows = sorted({(n, t) for n, t in zip(schedule["node"], schedule["task"])})
    fig = _figure(10, 0.5 * len(rows) + 1.5)
    ax = fig.subplots()
    colors = {"running": "tab:blue", "ready": "tab:orange", "blocked": "tab:gray"}
    heights = {"running": 0.6, "ready": 0.25, "blocked": 0.15}
    for i, (node, task) in enumerate(rows):
        sel = sched[(sched["node"] == node) & (sched["task"] == task)]
        for state, grp in sel.groupby("state"):
            spans = [(s, min(e, window_s) - s) for s, e in zip(grp["start_s"], grp["end_s"]) if e > s]
            if spans:
                h = heights.get(state, 0.2)
                ax.broken_barh(spans, (i - h / 2, h), facecolors=colors.get(state, "tab:green"),
                               label=state if i == 0 else None)
        if jobs is not None and not jobs.empty:
            late = jobs[(jobs["node"] == node) & (jobs["task"] == task)
                        & (jobs["deadline_met"].astype(str).str.lower() == "false") & (jobs["deadline_s"] <= window_s)]
            ax.plot(late["deadline_s"], np.full(len(late), i + 0.4), "v", color="red", markersize=4)
    ax.set_yticks(range(len(rows)), [f"{n}.{t}" for n, t in rows])
    ax.set_xlim(0, window_s)
    ax.set_xlabel("time [s]")
    ax.set_title(title or "schedule (running: blue, ready: orange, deadline miss: red)")
    ax.grid(True, axis="x", alpha=0.3)
    fig.savefig(path)
    return path


def plot_network(messages: pd.DataFrame, path: Path, window_s: float = DEFAULT_WINDOW_S,
                 title: str = "") -> Path | None:
    """Transmissions per network and sender over ``[0, window_s]``. None when there were no messages."""
    if messages is None or messages.empty:
        return None
    msgs = messages[messages["tx_start_s"].notna() & (messages["tx_start_s"] < window_s)]
    rows = sorted({(n, s) for n, s in zip(messages["network"], messages["sender"])})
    fig = _figure(10, 0.5 * len(rows) + 1.5)
    ax = fig.subplots()
    for i, (net, sender) in enumerate(rows):
        sel = msgs[(msgs["network"] == net) & (msgs["sender"] == sender)]
        dropped = sel["dropped"].astype(str).str.lower() == "true"
        end = sel["tx_end_s"].where(sel["tx_end_s"].notna(), sel["delivered_s"])
        for mask, color in ((~dropped, "tab:blue"), (dropped, "tab:red")):
            spans = [(s, e - s) for s, e in zip(sel["tx_start_s"][mask], end[mask]) if pd.notna(e) and e > s]
            if spans:
                ax.broken_barh(spans, (i - 0.3, 0.6), facecolors=color)
    ax.set_yticks(range(len(rows)), [f"{n}: {s}" for n, s in rows])
    ax.set_xlim(0, window_s)
    ax.set_xlabel("time [s]")
    ax.set_title(title or "network transmissions (dropped: red)")
    ax.grid(True, axis="x", alpha=0.3)
    fig.savefig(path)
    return path


def plot_run(result: Any, out_dir: str | Path, window_s: float = DEFAULT_WINDOW_S) -> list[Path]:
    """Write the run's figures into ``out_dir``; returns the files written."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    name = str(result.meta.get("scenario", ""))
    written = [
        plot_responses(result.signals, out / "responses.png", title=name),
        plot_schedule(result.schedule, result.jobs, out / "schedule.png", window_s),
        plot_network(result.messages, out / "network.png", window_s),
    ]
    return [p for p in written if p is not None]
