"""Figures of one run: responses and control signals, the schedule (Gantt chart), the network timeline.

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
    "signal_units",
    "signal_label",
    "first_transient",
    "density_window",
    "resolve_window",
    "MAX_BARS",
]

log = logging.getLogger(__name__)

#: Bars a Gantt chart or network timeline shows by default: the whole run up to this many intervals.
MAX_BARS = 3000

#: Pixels per inch the density rule assumes: the lowest resolution the figures are saved at (the README's
#: examples use 72 dpi); at any higher resolution every job is wider still.
PX_PER_INCH = 72
#: Pixels the shortest job and the shortest gap between two jobs of a row span in a chosen Gantt window.
MIN_FEATURE_PX = 2
#: Share of a Gantt chart's width the time axis takes (the rest: row names and the legend).
_PLOT_SHARE = 0.7
#: The transient zoom is drawn when the first transient lasts less than this share of the run.
ZOOM_SHARE = 0.3
#: A signal has settled when it stays within this share of its range around its final value.
SETTLE_BAND = 0.05


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


def signal_units(scenario: Mapping[str, Any] | None) -> dict[str, str]:
    """Each signal's unit, from the ``unit:`` of the scenario's ``io`` channels (never from names).

    An ADC or encoder channel's unit is also that of the plant output it reads (when named, e.g. ``output:
    theta``); a DAC's that of ``<name>.command`` and of the plant input it drives. A reference takes the unit
    of the outputs that follow it (a task's ``channel``, a metric's ``output``; a state-feedback task's measured
    outputs) when they agree. Signals whose unit nobody declared are absent.

    Examples
    --------
    >>> signal_units({"io": {"y": {"type": "adc", "output": "angle", "unit": "rad"}}})
    {'y': 'rad', 'angle': 'rad'}
    """
    units: dict[str, str] = {}
    if not scenario:
        return units
    for name, ch in (scenario.get("io") or {}).items():
        if not isinstance(ch, Mapping) or not ch.get("unit"):
            continue
        unit = str(ch["unit"])
        units[name] = unit
        port = ch.get("input") if ch.get("type") == "dac" else ch.get("output")
        if isinstance(port, str):
            units.setdefault(port, unit)
        if ch.get("type") == "dac":
            units[f"{name}.command"] = unit
    followers: dict[str, set[str]] = {}

    def follow(ref: Any, outs: list[Any]) -> None:
        if isinstance(ref, str) and ref:
            followers.setdefault(ref, set()).update(units[o] for o in outs if isinstance(o, str) and o in units)

    for node in (scenario.get("nodes") or {}).values():
        for kind in ("tasks", "handlers"):
            for entry in (node or {}).get(kind) or []:
                p = (entry or {}).get("params") or {}
                measured = [o for m in p.get("measurements") or [] if isinstance(m, Mapping)
                            for o in [m.get("channel"), *(m.get("outputs") or [])]]
                follow(p.get("reference"), [p.get("channel"), *measured])
    for metric in scenario.get("metrics") or []:
        p = (metric or {}).get("params") or {}
        follow(p.get("reference"), [p.get("output")])
    for ref, found in followers.items():
        if len(found) == 1 and ref not in units:
            units[ref] = next(iter(found))
    return units


def signal_label(name: str) -> str:
    """A signal's name as printed in a legend: ``x_hat[3]`` -> :math:`\\hat{x}_3`, ``alpha`` -> :math:`\\alpha`,
    ``theta_m`` -> :math:`\\theta_m`, ``r`` -> :math:`r`; a name with nothing to typeset stays as written (``y1``,
    ``u.command``).

    Examples
    --------
    >>> signal_label("x_hat[3]"), signal_label("alpha"), signal_label("y1")
    ('$\\\\hat{x}_{3}$', '$\\\\alpha$', 'y1')
    """
    from netsim.figure_style import symbol

    base, _, rest = name.partition("[")
    index = rest.rstrip("]") if rest.endswith("]") else ""
    if (rest and not index) or "." in base or not base:
        return name
    hat = base.endswith("_hat") and len(base) > 4
    stem = base[:-4] if hat else base
    shown = symbol(stem)
    if shown.startswith("$"):
        core = shown.strip("$")
    elif stem.isidentifier() and "_" not in stem and len(stem) == 1:
        core = stem
    elif not hat and not index:
        return shown if "_" in stem else name
    else:
        core = r"\mathrm{" + shown.replace(" ", r"\ ") + "}"
    if hat:
        core = r"\hat{" + core + "}"
    if index:
        core = core + "_{" + index + "}" if "_{" not in core else "{" + core + "}_{" + index + "}"
    return f"${core}$" if (hat or index or shown.startswith("$") or len(stem) == 1) else name


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
    units = signal_units(scenario)
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
    axes[0].set_title(title or "responses")
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


def density_window(rows: list[tuple[np.ndarray, np.ndarray]], end_s: float, width_px: float) -> tuple[float, float]:
    """The Gantt window ``(0, t1)`` at which every interval and every gap between two intervals of a row is at
    least :data:`MIN_FEATURE_PX` pixels wide, on a time axis ``width_px`` pixels wide: the whole run when that
    holds for it.

    ``rows`` holds each row's interval starts and ends in seconds (a zero-length interval, drawn as a tick,
    counts through its gaps only). With nothing to measure, the whole run.
    """
    smallest = math.inf
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
        gaps = s[1:] - np.maximum.accumulate(e)[:-1]
        if (gaps > 0).any():
            smallest = min(smallest, float(gaps[gaps > 0].min()))
    end = float(end_s) if end_s and math.isfinite(end_s) and end_s > 0 else max(last, 1e-9)
    if not math.isfinite(smallest):
        return 0.0, end
    return 0.0, min(end, max(smallest * width_px / MIN_FEATURE_PX, 1e-9))


def _axis_px(fig: Any, ax: Any) -> float:
    """Pixels of ``ax``'s width at :data:`PX_PER_INCH` (a new figure's: :data:`_PLOT_SHARE` of it)."""
    try:
        fig.canvas.draw_idle  # noqa: B018 - a figure with a canvas: its layout is known after a draw
        width_in = ax.get_position().width * fig.get_figwidth()
    except AttributeError:  # a subfigure or an axes without a position
        width_in = _PLOT_SHARE * fig.get_figwidth()
    return max(50.0, min(width_in, _PLOT_SHARE * fig.get_figwidth()) * PX_PER_INCH)


def _window_note(t0: float, t1: float, end_s: float, chosen: bool = False) -> str:
    if t0 == 0.0 and end_s and t1 >= end_s:
        return "whole run"
    span = f"{t0:.6g} s to {t1:.6g} s of {end_s:.6g} s" if end_s else f"{t0:.6g} s to {t1:.6g} s"
    return span + (f", every job {MIN_FEATURE_PX} px wide or more" if chosen else "")


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
    seen: set[str] = set()

    def once(label: str) -> str | None:
        if label in seen:
            return None
        seen.add(label)
        return label

    for i, (node, task) in enumerate(rows):
        sel = sched[(sched["node"] == node) & (sched["task"] == task)]
        for state, grp in sel.groupby("state"):
            bars = [(max(s, t0), min(e, t1) - max(s, t0)) for s, e in zip(grp["start_s"], grp["end_s"]) if e > s]
            if bars:
                h = heights.get(state, 0.2)
                c = colours.get(state, "tab:green")
                # an edge as wide as a thin line: a bar narrower than a pixel still shows
                ax.broken_barh(bars, (i - h / 2, h), facecolors=c, edgecolors=c, linewidth=0.5, label=once(state))
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
    ax.set_title(title or f"schedule ({_window_note(t0, t1, run_end, chosen)})")
    ax.grid(True, axis="x", alpha=0.3)
    if seen:
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
        t0, t1 = density_window(spans, run_end, _axis_px(fig, ax))
        t1 = min(t1, resolve_window(None, sent, run_end)[1])
    else:
        t0, t1 = resolve_window(window, sent, run_end)
    dropped_all = messages["dropped"].astype(str).str.lower() == "true"
    msgs = messages[(sent >= t0) & (sent <= t1)]
    dropped = dropped_all[msgs.index]
    seen: set[str] = set()

    def once(label: str) -> str | None:
        if label in seen:
            return None
        seen.add(label)
        return label

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
    ax.set_title(title or f"network ({_window_note(t0, t1, run_end, chosen)}; {n_drop} dropped)")
    ax.grid(True, axis="x", alpha=0.3)
    if seen:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
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
