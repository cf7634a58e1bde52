"""Performance metrics of a cart run (paper section VII-A).

Over the *stationary* part of the run -- the last 0.7 m of the 1 m, after 0.3 m of startup:

``sigma_u = std(u) / mean(u)``
    Control signal activity (``u = Ku uV``, the applied command). The paper normalises by the mean over all
    experiments with the same ``vref``; :func:`cart_metrics` also returns ``mean_u`` and ``std_u`` so a report
    can pool the means.
``Ev = RMS(v / vref - 1)``
    Velocity tracking error of the *true* velocity (``Ev``), of the controller's own estimate (``Ev_est``)
    and of the offline JMAP reconstruction from the full-resolution encoder (``Ev_jmap`` with the paper's
    one-sample timing relaxation, ``Ev_jmap0`` without it -- our samples have no timing jitter).
``events_per_tfilter``
    Encoder events (edges at the controller's resolution) per ``Tfilter`` in the stationary part.
``Ev_half1``, ``Ev_half2``
    ``Ev`` (true velocity) over the first and the second half of the stationary part (0.3-0.65 m and
    0.65-1 m): the paper's Fig. 1 shows the tracking degrading in the later half.
``v_rms_stop``
    The stop phase: RMS of the true velocity (m/s) over ``STOP_WINDOW`` = [1.5 s, 2.0 s] after the cart first
    reaches the end of the run (the reference steps to zero there, within one encoder step). The window
    starts late enough for the slowest loop (wc = 5, Ti = 0.6 s) to have come to rest; a loop at rest gives
    0, a sustained oscillation a sizable fraction of ``vref``. NaN when the run ends before the window does.

Undefined cases give NaN with a flag instead of a division by zero: ``vref = 0`` (``defined = 0``) and a
cart that does not reach the end of the run within the duration (``reached = 0``).
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np

__all__ = ["STARTUP", "DISTANCE", "STOP_WINDOW", "cart_metrics", "stationary_mask", "stop_rms"]

log = logging.getLogger(__name__)

#: Startup distance excluded from the stationary metrics (m).
STARTUP = 0.3
#: Length of the run (m).
DISTANCE = 1.0
#: Window of the stop phase, in seconds after the cart reaches ``DISTANCE`` (``v_rms_stop``).
STOP_WINDOW = (1.5, 2.0)

_KEYS = (
    "sigma_u", "mean_u", "std_u", "Ev", "Ev_est", "Ev_jmap", "Ev_jmap0", "Ev_startup", "events_per_tfilter",
    "Ev_half1", "Ev_half2", "v_rms_stop", "reached", "t_reach", "defined", "n_stationary",
)


def stationary_mask(p: np.ndarray, startup: float = STARTUP, distance: float = DISTANCE) -> np.ndarray:
    """Samples taken while ``startup <= p <= distance`` before the cart first passes ``distance``."""
    p = np.asarray(p, dtype=float)
    past = np.nonzero(p > distance)[0]
    end = int(past[0]) if past.size else len(p)
    mask = np.zeros(len(p), dtype=bool)
    mask[:end] = p[:end] >= startup
    return mask


def stop_rms(t: np.ndarray, v: np.ndarray, t_reach: float, window: tuple[float, float] = STOP_WINDOW) -> float:
    """RMS of ``v`` over ``t_reach + window[0] <= t < t_reach + window[1]`` (NaN if ``t`` ends before the window).

    Parameters
    ----------
    t, v
        Sample times (s) and true velocity (m/s).
    t_reach
        When the cart reached the end of the run (s).
    window
        Start and end of the window after ``t_reach`` (s).
    """
    t = np.asarray(t, dtype=float)
    if not math.isfinite(t_reach) or t.size == 0 or t[-1] < t_reach + window[1] - 1e-9:
        return math.nan
    sel = (t >= t_reach + window[0] - 1e-9) & (t < t_reach + window[1] - 1e-9)
    vv = np.asarray(v, dtype=float)[sel]
    vv = vv[np.isfinite(vv)]
    return float(np.sqrt(np.mean(vv**2))) if vv.size else math.nan


def _rms_rel(v: np.ndarray, vref: float) -> float:
    return float(np.sqrt(np.mean((v / vref - 1.0) ** 2))) if v.size else math.nan


def cart_metrics(
    t: np.ndarray,
    p: np.ndarray,
    v: np.ndarray,
    u: np.ndarray,
    vref: float,
    *,
    v_hat: np.ndarray | None = None,
    edge_times: np.ndarray | None = None,
    tfilter: float | None = None,
    counts_full: np.ndarray | None = None,
    delta_full: float = 5e-5,
    jmap: bool = True,
    startup: float = STARTUP,
    distance: float = DISTANCE,
) -> dict[str, float]:
    """Metrics of one run sampled at the control instants.

    Parameters
    ----------
    t, p, v, u
        Sample times (s), true position (m) and velocity (m/s), applied command ``Ku uV`` (m/s^2).
    vref
        The step reference (m/s).
    v_hat
        The controller's velocity estimate, for ``Ev_est``.
    edge_times
        Times of the encoder events the controller saw (s), for ``events_per_tfilter``.
    tfilter
        The controller's filter time constant (s).
    counts_full
        Full-resolution encoder counts at the sample instants, for the JMAP ``Ev_jmap``.
    delta_full
        Step of ``counts_full`` (m).
    jmap
        Compute ``Ev_jmap`` (a QP over the whole run, ~0.1 s).
    """
    out = {k: math.nan for k in _KEYS}
    t = np.asarray(t, dtype=float)
    p = np.asarray(p, dtype=float)
    reached = bool(np.any(p >= distance))
    out["reached"] = float(reached)
    out["defined"] = 1.0
    if reached:
        out["t_reach"] = float(t[int(np.argmax(p >= distance))])
    if vref == 0.0:
        out["defined"] = 0.0
        log.warning("cart metrics: vref = 0, so sigma_u (normalised by the mean command) and Ev are undefined")
        return out
    if not reached:
        log.warning(
            "cart metrics: the cart reached only %.3f m of %.3f m within %.3f s (friction too high for the "
            "command limit, or an unstable loop); stationary metrics are undefined", float(np.max(p)), distance,
            float(t[-1]) if t.size else 0.0,
        )
        return out
    mask = stationary_mask(p, startup, distance)
    out["n_stationary"] = float(mask.sum())
    uw = np.asarray(u, dtype=float)[mask]
    out["mean_u"] = float(np.mean(uw))
    out["std_u"] = float(np.std(uw))
    out["sigma_u"] = out["std_u"] / out["mean_u"] if out["mean_u"] != 0.0 else math.nan
    vv = np.asarray(v, dtype=float)
    out["Ev"] = _rms_rel(vv[mask], vref)
    pp = p
    mid = 0.5 * (startup + distance)
    out["Ev_half1"] = _rms_rel(vv[mask & (pp < mid)], vref)
    out["Ev_half2"] = _rms_rel(vv[mask & (pp >= mid)], vref)
    out["v_rms_stop"] = stop_rms(t, vv, out["t_reach"])
    start = (p < startup) & (np.cumsum(p >= startup) == 0)
    out["Ev_startup"] = _rms_rel(vv[start], vref)
    if v_hat is not None:
        out["Ev_est"] = _rms_rel(np.asarray(v_hat, dtype=float)[mask], vref)
    if edge_times is not None and tfilter is not None and mask.any():
        t0, t1 = float(t[mask][0]), float(t[mask][-1])
        et = np.asarray(edge_times, dtype=float)
        n_ev = int(np.count_nonzero((et > t0) & (et <= t1)))
        out["events_per_tfilter"] = n_ev * tfilter / (t1 - t0) if t1 > t0 else math.nan
    if jmap and counts_full is not None and len(t) >= 3:
        from netsim.models.cart.jmap import reconstruct

        h = float(np.median(np.diff(t)))
        end = min(len(t), int(np.nonzero(mask)[0][-1]) + 50)  # the run, not the tail after the 1 m
        for key, slack in (("Ev_jmap", 1), ("Ev_jmap0", 0)):
            rec = reconstruct(np.asarray(counts_full)[:end], h, delta_full, slack=slack, v0=0.0)
            out[key] = _rms_rel(rec.v[mask[:end]], vref)
    return out


# ------------------------------------------------------------------------------------------ scenario metric
from pydantic import Field  # noqa: E402

from netsim.errors import ConfigError  # noqa: E402
from netsim.registry import register  # noqa: E402
from netsim.units import StrictModel  # noqa: E402


class CartMetricParams(StrictModel):
    """Parameters of the ``cart`` metric (signal names as recorded by the cart programs and plant grid)."""

    position: str = "p"
    velocity: str = "v"
    command: str = "cart.accel"
    estimate: str = "cart.v_hat"
    count: str = "cart.count"
    vref: float | None = Field(None, description="reference (m/s); default: the largest recorded cart.vref")
    grid: float = Field(1e-3, gt=0, description="sample period of the evaluation (s): the plant record_grid")
    startup: float = STARTUP
    distance: float = DISTANCE
    delta_full: float = Field(5e-5, gt=0, description="full encoder resolution for the JMAP reconstruction (m)")
    jmap: bool = True


def _col(result: Any, name: str) -> np.ndarray:
    if name not in result.signals.columns:
        raise ConfigError(f"metric 'cart' needs signal '{name}', which was not recorded; add it to 'record:' "
                          f"(recorded: {', '.join(result.signals.columns[1:])})")
    return result.signals[name].to_numpy(dtype=float)


@register("metric", "cart", "sigma_u, Ev (true, estimate, JMAP), events per Tfilter over the last 0.7 m of the run")
def cart_metric(result: Any, params: Any, baseline: Any = None) -> dict[str, float]:
    """The cart metrics of a netsim run (names prefixed ``cart.``); see :func:`cart_metrics`."""
    p = params if isinstance(params, CartMetricParams) else CartMetricParams.model_validate(dict(params or {}))
    t_all = result.signals["time_s"].to_numpy(dtype=float)
    on_grid = np.abs(t_all / p.grid - np.round(t_all / p.grid)) < 1e-6
    pos, vel = _col(result, p.position), _col(result, p.velocity)
    u, vh = _col(result, p.command), _col(result, p.estimate)
    cnt = _col(result, p.count)
    sel = on_grid & np.isfinite(pos) & np.isfinite(u)
    vref = p.vref
    if vref is None:
        vr = _col(result, "cart.vref")
        vr = vr[np.isfinite(vr)]
        vref = float(vr[np.argmax(np.abs(vr))]) if vr.size else 0.0
    tf = _col(result, "cart.tfilter")
    tf = tf[np.isfinite(tf)]
    changed = np.concatenate(([False], np.diff(np.nan_to_num(cnt, nan=cnt[np.isfinite(cnt)][0] if np.isfinite(cnt).any() else 0.0)) != 0))
    edges = t_all[changed]
    counts_full = np.floor(pos[sel] / p.delta_full + 0.5)
    out = cart_metrics(t_all[sel], pos[sel], vel[sel], u[sel], vref, v_hat=vh[sel], edge_times=edges,
                       tfilter=float(tf[0]) if tf.size else None, counts_full=counts_full,
                       delta_full=p.delta_full, jmap=p.jmap, startup=p.startup, distance=p.distance)
    return {f"cart.{k}": v for k, v in out.items()}


cart_metric.Params = CartMetricParams  # type: ignore[attr-defined]
