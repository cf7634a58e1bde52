"""The ``unicycle`` metric: band coverage, covariance growth and recovery, tracking errors of one run.

Reads the signals the ``unicycle_ekf`` program and the ``unicycle`` plant record (``x, y, theta``: truth on the
filter's grid; ``xhat[i]``, ``sd[i]``: posterior mean and standard deviations; ``detP``; ``ref[i]``). Names
(``unicycle.`` prefix), per phase ``p`` of the trajectory (``straight``, ``turn``, ``front``, ``all``) and state
``s`` (``x``, ``y``, ``theta``):

* ``cover_<s>_<p>``: share of samples with ``|truth - xhat| <= 1.96 sd`` (the 95 % band);
* ``rmse_<s>_<p>``: RMS estimation error; ``nees_all``: mean of ``e' P^-1 e`` from the diagonal (``sum (e/sd)^2``);
* ``sd_<s>_end_<p>``: the standard deviation at the phase's last sample; ``detP_end_<p>``;
* ``detP_ratio_turn``: ``det P`` at the last sample of the blackout over its value at the sample before it;
  ``detP_monotone_turn``: 1 when it grew at every sample of the blackout;
* ``recovery_<s>_s``: seconds after the blackout's last sample until ``sd`` is back at (or below) its value at
  the sample before the blackout (NaN when it never is: the state is not observable with the front sensor
  alone).

The blackout is read from the scenario (:func:`blackout_window`): the first interval, after the start, in which
none of its ``ir_sensor`` tasks is in one of its ``on`` windows (the study's schedule: 4 s to 6 s, the turn).
Without ``ir_sensor`` tasks (the standalone studies call :func:`run_measures` directly) it is the trajectory's
``turn`` phase; with sensors that never are all off there is no blackout and no ``detP_*_turn``/``recovery_*``.
The names keep ``turn`` (the study's blackout is its turn).
* ``track_rms_<c>`` / ``track_max_<c>`` (``c`` = ``e1, e2, e3``): the cart-frame error of eq (24) between the
  reference and the *true* pose, over the whole run.
"""

from __future__ import annotations

import math
from typing import Any, Literal, Mapping, Union

import numpy as np
from pydantic import Field

from netsim.models.unicycle.design import PHASES
from netsim.registry import register
from netsim.timebase import S, parse_time
from netsim.units import StrictModel

__all__ = ["UnicycleMetricParams", "unicycle_metric", "run_measures", "blackout_window"]

STATES = ("x", "y", "theta")


class UnicycleMetricParams(StrictModel):
    """Phase boundaries of the trajectory (default: the study's 4 s / 2 s / 4 s)."""

    phases: list[str] = Field(default_factory=lambda: [p.name for p in PHASES])
    ends: list[float] = Field(default_factory=lambda: np.cumsum([p.duration for p in PHASES]).tolist(),
                              description="end of each phase in s")


#: What :func:`run_measures` takes as the blackout: ``(start_s, end_s)``, ``"turn"`` (the trajectory's turn
#: phase) or ``None`` (no blackout).
Blackout = Union[tuple[float, float], Literal["turn"], None]


def blackout_window(scenario: Mapping[str, Any] | None) -> Blackout:
    """The sensors' blackout of a (resolved) scenario: ``(start_s, end_s)`` of the first interval after 0 in
    which no ``ir_sensor`` task is in one of its ``on`` windows (``end_s`` the run's duration if none comes
    back); ``None`` when the sensors are never all off; ``"turn"`` when the scenario has no ``ir_sensor`` task.
    """
    nodes = (scenario or {}).get("nodes") or {}
    windows: list[tuple[int, float]] = []
    sensors = 0
    for node in nodes.values():
        for task in (node or {}).get("tasks") or []:
            if task.get("program") != "ir_sensor":
                continue
            sensors += 1
            on = (task.get("params") or {}).get("on")
            if on is None:
                windows.append((0, math.inf))
            else:
                windows += [(parse_time(a), parse_time(b)) for a, b in on]
    if not sensors:
        return "turn"
    duration = parse_time(scenario["duration"]) if scenario and "duration" in scenario else math.inf
    merged: list[list[float]] = []  # the union of the windows, in order
    for a, b in sorted(w for w in windows if w[0] < min(w[1], duration)):
        if merged and a <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    if not merged or merged[0][1] >= duration:  # never on, or never all off after having been on
        return None
    end = merged[1][0] if len(merged) > 1 else duration
    return (merged[0][1] / S, end / S)


def run_measures(t: np.ndarray, truth: np.ndarray, xhat: np.ndarray, sd: np.ndarray, detP: np.ndarray,
                 ref: np.ndarray | None, names: list[str], ends: list[float],
                 blackout: Blackout = "turn") -> dict[str, float]:
    """The measures of the module docstring from arrays over the filter's samples (``N x 3`` for poses);
    ``blackout`` as :func:`blackout_window` gives it."""
    out: dict[str, float] = {}
    e = truth - xhat
    e[:, 2] = np.arctan2(np.sin(e[:, 2]), np.cos(e[:, 2]))
    inside = np.abs(e) <= 1.96 * sd
    bounds = [0.0] + list(ends)
    masks = {}
    for i, name in enumerate(names):
        last = i == len(names) - 1
        masks[name] = (t >= bounds[i] - 1e-9) & ((t <= bounds[i + 1] + 1e-9) if last else (t < bounds[i + 1] - 1e-9))
    masks["all"] = np.ones_like(t, dtype=bool)
    for p, m in masks.items():
        if not m.any():
            continue
        for j, s in enumerate(STATES):
            out[f"cover_{s}_{p}"] = float(inside[m, j].mean())
            out[f"rmse_{s}_{p}"] = float(math.sqrt(np.mean(e[m, j] ** 2)))
            if p != "all":
                out[f"sd_{s}_end_{p}"] = float(sd[m, j][-1])
        if p != "all":
            out[f"detP_end_{p}"] = float(detP[m][-1])
    out["nees_all"] = float(np.mean(np.sum((e / sd) ** 2, axis=1)))
    if blackout == "turn":
        dark = masks.get("turn")
    elif blackout is None:
        dark = None
    else:
        a, b = blackout
        dark = (t >= a - 1e-9) & ((t < b - 1e-9) if b < t[-1] + 1e-9 else np.ones_like(t, dtype=bool))
    if dark is not None and dark.any():
        idx = np.flatnonzero(dark)
        i0, i1 = idx[0] - 1 if idx[0] > 0 else idx[0], idx[-1]
        out["detP_ratio_turn"] = float(detP[i1] / detP[i0])
        out["detP_monotone_turn"] = float(np.all(np.diff(detP[i0:i1 + 1]) > 0))
        after = np.arange(i1 + 1, len(t))
        for j, s in enumerate(STATES):
            back = after[sd[after, j] <= sd[i0, j]]
            out[f"recovery_{s}_s"] = float(t[back[0]] - t[i1]) if back.size else float("nan")
    if ref is not None:
        ec = np.empty_like(ref)
        for k in range(len(t)):
            d = ref[k] - truth[k]
            c, s_ = math.cos(truth[k, 2]), math.sin(truth[k, 2])
            ec[k] = (c * d[0] + s_ * d[1], -s_ * d[0] + c * d[1], math.atan2(math.sin(d[2]), math.cos(d[2])))
        for j, c_ in enumerate(("e1", "e2", "e3")):
            out[f"track_rms_{c_}"] = float(math.sqrt(np.mean(ec[:, j] ** 2)))
            out[f"track_max_{c_}"] = float(np.max(np.abs(ec[:, j])))
    return out


@register("metric", "unicycle", "2WD cart: 95 % band coverage, det P growth and recovery, tracking errors")
def unicycle_metric(result: Any, params: Any, baseline: Any = None) -> dict[str, float]:
    """The measures of the module docstring, named ``unicycle.<measure>``."""
    p = UnicycleMetricParams.model_validate(params or {})
    sig = result.signals
    sig = sig[sig["xhat[0]"].notna() & sig["x"].notna()]
    t = sig["time_s"].to_numpy(dtype=float)
    truth = sig[["x", "y", "theta"]].to_numpy(dtype=float)
    xhat = sig[["xhat[0]", "xhat[1]", "xhat[2]"]].to_numpy(dtype=float)
    sd = sig[["sd[0]", "sd[1]", "sd[2]"]].to_numpy(dtype=float)
    ref = sig[["ref[0]", "ref[1]", "ref[2]"]].to_numpy(dtype=float) if "ref[0]" in sig else None
    m = run_measures(t, truth, xhat, sd, sig["detP"].to_numpy(dtype=float), ref, p.phases, p.ends,
                     blackout_window(getattr(result, "scenario", None)))
    return {f"unicycle.{k}": v for k, v in m.items()}


unicycle_metric.Params = UnicycleMetricParams  # type: ignore[attr-defined]
#: the recorded signals the metric reads (``netsim validate`` checks that ``record:`` keeps them)
unicycle_metric.reads_signals = ("x", "y", "theta", "xhat", "sd", "detP")  # type: ignore[attr-defined]
