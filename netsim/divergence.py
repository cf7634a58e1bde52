"""Runs that went unstable without tripping the plant's hard bound: non-finite signals and run-away errors.

The plant stops a run when its state norm passes ``divergence_bound`` (1e12 by default, an absolute number that
suits no scenario in particular). Two checks after the run judge it on its own scale:

* a recorded signal that takes a NaN or infinite value: the run diverged at the first such sample, named;
* a ``control_error`` metric's error ``reference - output`` that grows past ``diverged_above`` times the loop's
  own scale, the larger of the reference's largest magnitude and the output's first value (default
  :data:`DEFAULT_RATIO` = 1000; ``diverged_above: null`` turns it off; a loop whose scale is 0, a regulator at
  rest at 0, is not judged).

Either makes the run's status ``diverged at t = ... s`` (the run itself went on to its end: the tables show the
whole of it). A loop that leaves its operating region without running away that far (a growing error envelope, a
fallen pendulum) is judged by :mod:`netsim.results.verdict`: ``unstable at t = ... s``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, Iterable

import numpy as np

from netsim.timebase import S

__all__ = ["DEFAULT_RATIO", "first_non_finite", "first_runaway_error", "find_divergence"]

#: Default of ``control_error``'s ``diverged_above``: an error 1000 times the loop's own scale is a run-away.
DEFAULT_RATIO = 1000.0


def first_non_finite(times: Mapping[str, Sequence[int]], values: Mapping[str, Sequence[float]]
                     ) -> tuple[int, str] | None:
    """The first recorded sample that is NaN or infinite, as ``(t_ns, signal name)``, or None."""
    best: tuple[int, str] | None = None
    for name, vals in values.items():
        arr = np.asarray(vals, dtype=float)
        bad = ~np.isfinite(arr)
        if bad.any():
            t = int(times[name][int(np.argmax(bad))])
            if best is None or t < best[0]:
                best = (t, name)
    return best


def first_runaway_error(t_s: np.ndarray, r: np.ndarray, y: np.ndarray, ratio: float) -> tuple[float, float, float] | None:
    """The first time ``|r - y|`` exceeds ``ratio`` times ``max(max |r|, |y[0]|)``: ``(t_s, |e|, scale)`` or None.

    NaN samples (a signal not yet sampled) are ignored.
    """
    finite_r = r[np.isfinite(r)]
    finite_y = y[np.isfinite(y)]
    scale = max(float(np.abs(finite_r).max()) if finite_r.size else 0.0, abs(float(finite_y[0])) if finite_y.size else 0.0)
    if not scale > 0:
        return None
    err = np.abs(r - y)
    over = np.isfinite(err) & (err > ratio * scale)
    if not over.any():
        return None
    k = int(np.argmax(over))
    return float(t_s[k]), float(err[k]), scale


def find_divergence(result: Any, recorder: Any, metric_specs: Iterable[Any]) -> tuple[float, str] | None:
    """``(t_s, message)`` of the first sign of divergence in a finished run, or None.

    Parameters
    ----------
    result
        The run's :class:`~netsim.results.RunResult` (its signals table).
    recorder
        The run's recorder (raw samples: the signals table holds values between samples, which hides a NaN).
    metric_specs
        The scenario's ``metrics:`` entries; each ``control_error`` entry is checked with its ``diverged_above``.
    """
    found: list[tuple[float, str]] = []
    if recorder is not None:
        bad = first_non_finite(recorder.times, recorder.values)
        if bad is not None:
            found.append((bad[0] / S, f"signal '{bad[1]}' became {_value_at(recorder, bad)} at t = {bad[0] / S:.9g} s"))
    sig = result.signals
    for spec in metric_specs or []:
        spec = spec.model_dump() if hasattr(spec, "model_dump") else dict(spec)
        if spec.get("type") != "control_error":
            continue
        params = dict(spec.get("params") or {})
        ratio = params.get("diverged_above", DEFAULT_RATIO)
        out, ref = params.get("output"), params.get("reference")
        if ratio is None or out not in sig.columns or (ref and ref not in sig.columns):
            continue
        y = sig[out].to_numpy(dtype=float)
        r = sig[ref].to_numpy(dtype=float) if ref else np.zeros_like(y)
        hit = first_runaway_error(sig["time_s"].to_numpy(dtype=float), r, y, float(ratio))
        if hit is not None:
            t, e, scale = hit
            found.append((t, f"the error {ref or '0'} - {out} reached {e:.3g} at t = {t:.9g} s, over "
                             f"{float(ratio):g} times the loop's scale {scale:.3g} (control_error diverged_above)"))
    if not found:
        return None
    return min(found, key=lambda item: item[0])


def _value_at(recorder: Any, hit: tuple[int, str]) -> str:
    t, name = hit
    for tt, v in zip(recorder.times[name], recorder.values[name]):
        if tt == t and not math.isfinite(v):
            return repr(v)
    return "non-finite"
