"""Is the loop stable? A finished run judged on the loop's own signals (issue 26): growth, bounds, metric verdicts.

Divergence (:mod:`netsim.divergence`) catches a run whose values become non-finite or run away past 1000 times
the loop's scale. A loop can be unstable well before that: a levitated ball whose gap error grows from 0.5 mm to
330 mm in a second, a pendulum that fell and swings, bounded, about the hanging position. Three checks, set by
the scenario's ``verdict:`` block (:mod:`netsim.scenario.schema_verdict`), look for a loop that left its
operating region:

growth
    For every metric that names an ``output`` signal (and a ``reference``; 0 without one), the error
    ``e = reference - output``; and every signal of ``verdict.signals`` about 0. The run is cut into windows of
    ``verdict.window`` (default: duration / 20) and the envelope ``E_k = max |e|`` of each window is taken. The
    loop is unstable when ``verdict.windows`` (n, default 4) consecutive windows each have an envelope at least
    ``verdict.growth_ratio`` (g, default 1.15) times the one before, without slowing down (the later half of
    those growth steps at least :data:`STEADY` times the earlier half, in logarithms, as exponential growth keeps
    its pace), the last of them is past the loop's scale ``max(max |reference|, |output(0)|, E_0)``, and no later
    window falls back below the geometric middle ``sqrt(E_start E_end)`` of that growth. The same test is made on windows 2 and 4 times as long (ratio g^2,
    g^4): a growing oscillation slower than the window still shows. What it lets pass, and why:

    * a converging loop and a step response: the error envelope shrinks;
    * a rise from rest (a ramp, a response to a load disturbance): its growth slows down;
    * a square-wave reference: an edge is one jump of the envelope, after which it falls back;
    * a bounded limit cycle and noise: the envelope stays at its level (no sustained growth), and one that grows
      from rest to a small level stays below the loop's scale;
    * a loop whose scale is 0 (a regulator at rest at 0, no noise) is not judged.

bound
    ``verdict.bound: {signal: b}``: the first sample with ``|signal| > b``.

metric verdicts
    A registered metric function may carry ``verdict(result, params) -> (t_s, text) | None``, its own judgement
    of the run (the ``pendulum`` metric: the pendulum fell, ``|alpha|`` past pi/2). Off with ``verdict.metrics:
    false``.

The earliest finding makes the status ``unstable at t = ... s`` (a result, not a success: exit 1, as ``diverged``;
:mod:`netsim.status`), with its text as the run's ``error``; with ``verdict.action: warn`` the status stays ``ok``
and the text is a warning. ``verdict: false`` switches all three off.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from netsim.scenario.schema_verdict import WINDOWS_PER_RUN, VerdictSettings
from netsim.timebase import S

if TYPE_CHECKING:
    from netsim.scenario.schema import Scenario

__all__ = ["Finding", "settings_of", "window_envelope", "find_growth", "judge_signals", "judge_metrics",
           "apply_finding", "LONGER_WINDOWS"]

log = logging.getLogger(__name__)

#: The growth test is also made on windows this many times ``verdict.window`` (a slow growing oscillation).
LONGER_WINDOWS = (1, 2, 4)
#: Envelopes below this share of the loop's scale count as this share (no division by an exact 0).
FLOOR = 1e-6
#: Exponential growth keeps its pace: over the growing windows, the mean log growth of the later half must be at
#: least this share of the earlier half's. A ramp from rest, whose window ratios are 2, 3/2, 4/3, 5/4 ..., slows
#: down faster than that (its halves give at most 0.66 for ratios above 1.15).
STEADY = 0.7


@dataclass(frozen=True)
class Finding:
    """A sign that the loop left its operating region: when (s) and what."""

    t_s: float
    text: str


@dataclass(frozen=True)
class Growth:
    """A sustained growth of an envelope: windows ``start`` (where it began) to ``end`` (where it is confirmed), of
    ``width`` base windows each."""

    start: int
    end: int
    width: int
    e_start: float
    e_end: float


def settings_of(scenario: Scenario) -> VerdictSettings:
    """The scenario's ``verdict:`` block, or the defaults when it has none."""
    got = getattr(scenario, "verdict", None)
    return got if isinstance(got, VerdictSettings) else VerdictSettings()


def window_ns(settings: VerdictSettings, duration_ns: int) -> int:
    """The base window of the envelope: ``verdict.window`` or the duration / :data:`WINDOWS_PER_RUN`."""
    return int(settings.window) if settings.window else max(1, int(duration_ns) // WINDOWS_PER_RUN)


# ----------------------------------------------------------------------------------------------- envelopes
def window_envelope(chunks: Iterable[tuple[np.ndarray, np.ndarray]], width_ns: int, count: int) -> np.ndarray:
    """``max |value|`` over each window ``[k width, (k + 1) width)``, ``k < count``, of ``(t_ns, values)`` chunks in
    time order; NaN for a window without a finite value. Samples past the last window are left out."""
    env = np.full(count, np.nan)
    for t_ns, vals in chunks:
        idx = np.asarray(t_ns, dtype=np.int64) // int(width_ns)
        mag = np.abs(np.asarray(vals, dtype=float))
        keep = (idx < count) & np.isfinite(mag)
        if not keep.any():
            continue
        idx, mag = idx[keep], mag[keep]
        starts = np.flatnonzero(np.r_[True, idx[1:] != idx[:-1]])
        top = np.maximum.reduceat(mag, starts)
        at = idx[starts]
        env[at] = np.fmax(env[at], top)
    return env


def _coarser(env: np.ndarray, m: int) -> np.ndarray:
    """Envelopes of windows ``m`` times as long (the last incomplete group dropped)."""
    k = len(env) // m
    if m == 1 or k == 0:
        return env[: k * m].copy()
    groups = env[: k * m].reshape(k, m)
    out = np.full(k, np.nan)
    seen = np.isfinite(groups).any(axis=1)
    out[seen] = np.nanmax(groups[seen], axis=1)
    return out


def find_growth(env: np.ndarray, scale: float, windows: int, ratio: float) -> Growth | None:
    """The first sustained growth of ``env`` (one scale of windows; see the module docstring), or None.

    ``windows`` consecutive windows each at least ``ratio`` times the window before, the last past ``scale``, and
    no later window below ``sqrt(E_start E_end)``. Envelopes are floored at :data:`FLOOR` times ``scale``; a window
    without values (NaN) breaks a growth.
    """
    if not scale > 0 or len(env) <= windows:
        return None
    e = np.fmax(env, FLOOR * scale)  # NaN stays NaN only where env is NaN
    e[~np.isfinite(env)] = np.nan
    with np.errstate(invalid="ignore", divide="ignore"):
        grows = e[1:] >= ratio * e[:-1]  # False where either is NaN
    with np.errstate(invalid="ignore", divide="ignore"):
        logs = np.log(e[1:] / e[:-1])
    half = windows // 2
    run = 0
    for j, up in enumerate(grows, start=1):
        run = run + 1 if up else 0
        if run < windows or not e[j] >= scale:
            continue
        start = j - windows
        steps = logs[start:j]
        if steps[-half:].mean() < STEADY * steps[:half].mean():
            continue  # slowing down: a rise from rest (a ramp, a response to a disturbance), not exponential growth
        middle = math.sqrt(float(e[start]) * float(e[j]))
        later = e[j + 1:]
        later = later[np.isfinite(later)]
        if later.size and float(later.min()) < middle:
            continue  # it came back: a transient (a reference edge), not a loop leaving its region
        return Growth(start, j, 1, float(e[start]), float(e[j]))
    return None


# ----------------------------------------------------------------------------------------------- signals
Chunks = Callable[[list[str]], Iterator[tuple[np.ndarray, list[np.ndarray]]]]


def _reader(result: Any) -> Chunks:
    """``read(names)``: the signals table's rows in windows for ``names`` (from the recorded samples when the table
    was not built, else from the table)."""

    def read(names: list[str]) -> Iterator[tuple[np.ndarray, list[np.ndarray]]]:
        got = result._signal_chunks(names) if hasattr(result, "_signal_chunks") else None
        if got is not None:
            yield from got
            return
        sig = result.signals
        t_ns = np.rint(sig["time_s"].to_numpy(dtype=float) * S).astype(np.int64)
        yield t_ns, [sig[n].to_numpy(dtype=float) for n in names]

    return read


def _names(result: Any) -> set[str]:
    source = getattr(result, "_signal_source", None)
    if source is not None:
        return set(source.names)
    sig = result.signals
    return set() if sig is None else set(sig.columns) - {"time_s"}


def _errors(read: Chunks, out: str, ref: str | None) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    for t_ns, cols in read([out, ref] if ref else [out]):
        y = cols[0]
        yield t_ns, (cols[1] - y if ref else y)


def _scale(read: Chunks, out: str, ref: str | None) -> float:
    """``max(max |reference|, |output(0)|)``: the loop's own size (as :mod:`netsim.divergence` takes it)."""
    top_r, first_y = 0.0, None
    for _, cols in read([out, ref] if ref else [out]):
        if ref:
            r = cols[1][np.isfinite(cols[1])]
            if r.size:
                top_r = max(top_r, float(np.abs(r).max()))
        if first_y is None:
            y = cols[0][np.isfinite(cols[0])]
            if y.size:
                first_y = abs(float(y[0]))
    return max(top_r, first_y or 0.0)


def _first_over(chunks: Iterable[tuple[np.ndarray, np.ndarray]], level: float, t_from: int
                ) -> tuple[int, float] | None:
    """The first sample at or after ``t_from`` with ``|value| > level``: ``(t_ns, value)``."""
    for t_ns, vals in chunks:
        over = (np.asarray(t_ns) >= t_from) & (np.abs(vals) > level)
        if over.any():
            k = int(np.argmax(over))
            return int(t_ns[k]), float(vals[k])
    return None


def _growth_finding(read: Chunks, out: str, ref: str | None, settings: VerdictSettings, width_ns: int,
                    t_end_ns: int, what: str) -> Finding | None:
    count = int(t_end_ns // width_ns)
    if count <= settings.windows:
        return None
    env = window_envelope(_errors(read, out, ref), width_ns, count)
    first = env[np.isfinite(env)]
    scale = max(_scale(read, out, ref), float(first[0]) if first.size else 0.0)
    if not scale > 0:
        return None
    best: tuple[int, Growth] | None = None
    for m in LONGER_WINDOWS:
        coarse = _coarser(env, m)
        hit = find_growth(coarse, scale, settings.windows, settings.growth_ratio ** m)
        if hit is not None:
            confirmed = (hit.end + 1) * m * width_ns
            if best is None or confirmed < best[0]:
                best = (confirmed, Growth(hit.start, hit.end, m, hit.e_start, hit.e_end))
    if best is None:
        return None
    g = best[1]
    level = max(scale, g.e_start)
    t_from = (g.start + 1) * g.width * width_ns
    left = _first_over(_errors(read, out, ref), level, t_from)
    t_ns = left[0] if left is not None else best[0]
    win = g.width * width_ns / S
    ratio = settings.growth_ratio ** g.width
    text = (f"{what} grew {g.e_end / g.e_start:.3g}x over {settings.windows} windows of {win:.6g} s (envelope "
            f"{g.e_start:.3g} -> {g.e_end:.3g}, each window at least {ratio:.3g}x the one before), left the loop's "
            f"scale {scale:.3g} at t = {t_ns / S:.9g} s and did not come back (verdict.window, verdict.windows, "
            f"verdict.growth_ratio set this check; verdict.growth: false turns it off)")
    return Finding(t_ns / S, text)


def _pairs(metric_specs: Iterable[Any]) -> list[tuple[str, str | None]]:
    """``(output, reference or None)`` of every metric that names an output signal, once each."""
    out: list[tuple[str, str | None]] = []
    for spec in metric_specs or []:
        params = _params_of(spec)
        y, r = params.get("output"), params.get("reference")
        if isinstance(y, str) and (r is None or isinstance(r, str)) and "time_s" not in (y, r):
            pair = (y, r or None)
            if pair not in out:
                out.append(pair)
    return out


def _params_of(spec: Any) -> dict[str, Any]:
    """A metric spec's parameters with its ``Params`` defaults (et_control's ``reference: r, output: y``) when the
    loader validated them, else as written."""
    try:
        validated = spec.validated_params()
    except Exception:  # noqa: BLE001 - a spec built by hand, not validated: its parameters as written
        validated = None
    if hasattr(validated, "model_dump"):
        return validated.model_dump()
    if isinstance(validated, dict):
        return dict(validated)
    params = spec.params if hasattr(spec, "params") else dict(spec).get("params")
    return dict(params or {})


def judge_signals(result: Any, scenario: Scenario, t_end_ns: int) -> tuple[Finding | None, list[str]]:
    """The growth and bound checks of a finished run: the earliest finding (or None) and warnings about
    ``verdict:`` names that nothing recorded.

    Parameters
    ----------
    result
        The run's :class:`~netsim.results.RunResult` (its signals, read window by window when it can).
    scenario
        The validated scenario (its ``metrics`` and ``verdict``).
    t_end_ns
        Where the run ended.
    """
    settings = settings_of(scenario)
    names = _names(result)
    read = _reader(result)
    found: list[Finding] = []
    warnings: list[str] = []
    width = window_ns(settings, scenario.duration)
    if settings.growth:
        checks: list[tuple[str, str | None, str]] = []
        for out, ref in _pairs(scenario.metrics):
            if out in names and (ref is None or ref in names):
                checks.append((out, ref, f"the error {ref} - {out}" if ref else f"the output {out}"))
        for name in settings.signals:
            if name in names:
                checks.append((name, None, f"the signal {name}"))
            else:
                warnings.append(f"verdict.signals: nothing recorded '{name}'; it was not judged")
        for out, ref, what in checks:
            hit = _growth_finding(read, out, ref, settings, width, t_end_ns, what)
            if hit is not None:
                found.append(hit)
    for name, bound in settings.bound.items():
        if name not in names:
            warnings.append(f"verdict.bound.{name}: nothing recorded '{name}'; it was not judged")
            continue
        over = _first_over(((t, cols[0]) for t, cols in read([name])), float(bound), 0)
        if over is not None:
            t_ns, v = over
            found.append(Finding(t_ns / S, f"|{name}| reached {abs(v):.4g} at t = {t_ns / S:.9g} s, past its "
                                           f"bound {bound:g} (verdict.bound.{name})"))
    return (min(found, key=lambda f: f.t_s) if found else None), warnings


def judge_metrics(result: Any, scenario: Scenario) -> Finding | None:
    """The earliest verdict of the scenario's metrics that carry one (a ``verdict`` attribute on the registered
    metric function), or None; nothing when ``verdict.metrics`` is false."""
    if not settings_of(scenario).metrics:
        return None
    from netsim.registry import lookup

    found: list[Finding] = []
    for spec in scenario.metrics or []:
        try:
            fn = lookup("metric", spec.type)
        except Exception:  # noqa: BLE001 - an unknown metric already failed the metrics step
            continue
        hook = getattr(fn, "verdict", None)
        if hook is None:
            continue
        params = spec.validated_params() if hasattr(spec, "validated_params") else spec.params
        hit = hook(result, params)
        if hit is not None:
            found.append(Finding(float(hit[0]), str(hit[1])))
    return min(found, key=lambda f: f.t_s) if found else None


def apply_finding(meta: dict[str, Any], finding: Finding | None, scenario: Scenario) -> str | None:
    """Record ``finding`` in a run's ``meta``: status ``unstable at t = ... s`` and the text as ``error``
    (``verdict.action: fail``), or a warning (``warn``; the warning's text is returned). A run that is not ``ok``
    keeps its status."""
    if finding is None or str(meta.get("status", "ok")) != "ok":
        return None
    status = f"unstable at t = {finding.t_s:.9g} s"
    if settings_of(scenario).action == "warn":
        text = f"{status}: {finding.text} (verdict.action: warn)"
        meta["warnings"] = list(meta.get("warnings") or []) + [text]
        log.warning("%s: %s", getattr(scenario, "name", "run"), text)
        return text
    meta["status"] = status
    meta["error"] = finding.text
    return None
