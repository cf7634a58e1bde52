"""The divergence check of a finished run (:func:`netsim.divergence.find_divergence`) on the signals table read
window by window (issue 19: a long run's table is never whole in memory), with the same answer."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from netsim.timebase import S

__all__ = ["find_divergence_chunked", "first_runaway_error_chunked"]


class _NoSignals:
    """A result without signals: :func:`~netsim.divergence.find_divergence` given no metric then checks the
    recorder only."""

    signals = None


def first_runaway_error_chunked(windows: Any, ratio: float) -> tuple[float, float, float] | None:
    """:func:`netsim.divergence.first_runaway_error` of the windows ``windows()`` gives (``(t_ns, [y, r])`` per
    window, ``r`` None for a reference of 0), read twice: first the scale, then the first row past it."""
    top_r, first_y = 0.0, None
    for _, (y, r) in windows():
        if r is not None:
            finite_r = r[np.isfinite(r)]
            if finite_r.size:
                top_r = max(top_r, float(np.abs(finite_r).max()))
        if first_y is None:
            finite_y = y[np.isfinite(y)]
            if finite_y.size:
                first_y = abs(float(finite_y[0]))
    scale = max(top_r, first_y if first_y is not None else 0.0)
    if not scale > 0:
        return None
    for t_ns, (y, r) in windows():
        err = np.abs((r if r is not None else np.zeros_like(y)) - y)
        over = np.isfinite(err) & (err > ratio * scale)
        if over.any():
            k = int(np.argmax(over))
            return float(t_ns[k] / S), float(err[k]), scale
    return None


def find_divergence_chunked(result: Any, recorder: Any, metric_specs: Iterable[Any]) -> tuple[float, str] | None:
    """:func:`netsim.divergence.find_divergence` of ``result``, reading its signals window by window when it can
    (``result._signal_chunks``); the whole table otherwise."""
    from netsim.divergence import DEFAULT_RATIO, find_divergence

    specs = [s.model_dump() if hasattr(s, "model_dump") else dict(s) for s in metric_specs or []]
    checks = [s for s in specs if s.get("type") == "control_error"]
    source = getattr(result, "_signal_source", None)
    names = set(source.names) if source is not None else set()
    for spec in checks:
        params = dict(spec.get("params") or {})
        if "time_s" in (params.get("output"), params.get("reference")):
            return find_divergence(result, recorder, specs)
    if source is None or result._signal_chunks([]) is None:
        return find_divergence(result, recorder, specs)
    found = []
    hit = find_divergence(_NoSignals(), recorder, [])  # a NaN or infinite recorded sample
    if hit is not None:
        found.append(hit)
    for spec in checks:
        params = dict(spec.get("params") or {})
        ratio = params.get("diverged_above", DEFAULT_RATIO)
        out, ref = params.get("output"), params.get("reference")
        if ratio is None or not isinstance(out, str) or out not in names or (ref and ref not in names):
            continue
        wanted = [out, ref] if ref else [out]

        def windows(wanted: list[str] = wanted) -> Any:
            for t_ns, cols in result._signal_chunks(wanted):
                yield t_ns, (cols[0], cols[1] if len(cols) > 1 else None)

        runaway = first_runaway_error_chunked(windows, float(ratio))
        if runaway is not None:
            t, e, scale = runaway
            text = (f"the error {ref or '0'} - {out} reached {e:.3g} at t = {t:.9g} s, over {float(ratio):g} "
                    f"times the loop's scale {scale:.3g} (control_error diverged_above)")  # as netsim.divergence says
            found.append((t, text))
    if not found:
        return None
    return min(found, key=lambda item: item[0])
