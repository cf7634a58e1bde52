"""A plain-numpy closed-loop simulation of the cart experiment (no simpy, no kernel).

It reproduces the paper's experiment (section VII): the cart starts at rest at ``p = 0`` with all
estimates zero; at ``t = 0`` the reference steps to ``vref``; after 1 m the reference steps back to zero
and the run ends ``tail`` seconds later. The encoder ISR is modelled exactly at its 10 us grid: the plant is
evaluated in closed form at every ISR tick of a control period (vectorized), so the stored count,
direction and stamp of the last edge are exactly those a 100 kHz polling ISR would store. The controller
runs at the control period (1 ms) and its output acts after ``delay`` (0 by default).

This is the reference the netsim scenario is compared against (benchmark ratio, cross-check test) and
the quick engine of the studies (:mod:`netsim.models.cart.study`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from netsim.models.cart.controllers import KU, CartController
from netsim.models.cart.dynamics import propagate
from netsim.models.cart.encoding import DELTA_P, Quantizer
from netsim.models.cart.friction import Friction
from netsim.errors import ConfigError
from netsim.timebase import format_time

__all__ = ["CartRun", "simulate"]


@dataclass
class CartRun:
    """Trace of one run, sampled at the control instants (arrays of equal length)."""

    t: np.ndarray  # s
    p: np.ndarray  # true position, m
    v: np.ndarray  # true velocity, m/s
    uv: np.ndarray  # motor command applied from this instant (after delay), full-voltage units
    v_hat: np.ndarray
    u_bias_hat: np.ndarray
    vref: np.ndarray
    count: np.ndarray  # controller's encoder count (q bits dropped)
    count_full: np.ndarray  # full-resolution count (offline evaluation)
    edge_times: np.ndarray  # stamps of every edge at the controller's resolution, s
    ku: float
    delta: float
    reached: bool  # the cart got to `distance` within the duration
    t_reach: float  # time it did (nan if not)
    info: dict[str, float] = field(default_factory=dict)

    @property
    def u(self) -> np.ndarray:
        """Applied acceleration command ``Ku uV`` (m/s^2)."""
        return self.ku * self.uv


def simulate(
    controller: CartController,
    friction: Friction,
    *,
    vref: float = 0.8,
    q: int = 6,
    distance: float = 1.0,
    duration: float = 5.0,
    tail: float = 0.0,
    tick_ns: int = 10_000,
    delay_ns: int = 0,
    ku: float = KU,
    td: float | None = None,
    delta_p: float = DELTA_P,
    rounding: str = "round",
) -> CartRun:
    """Run one step-response experiment of ``controller`` on the cart.

    Parameters
    ----------
    controller
        A fresh controller (it is reset); its period is the control period.
    friction
        The track's friction realization.
    vref
        Velocity reference during the run (m/s); must be nonzero to ever reach ``distance``.
    q
        Low bits dropped by the controller's encoder (quantization ``delta_p 2^q``).
    distance
        Length of the run (m); the reference returns to zero when the full-resolution position passes it.
    duration
        Longest simulated time (s): a cart that never gets to ``distance`` ends here with ``reached=False``.
    tail
        Simulated time after reaching ``distance`` (s).
    tick_ns
        Encoder ISR period (10 us).
    delay_ns
        Delay from sampling to actuation (controller execution), less than a period.
    ku, td
        Motor gain (m/s^2) and optional velocity time constant (s) of the plant.
    delta_p, rounding
        Full encoder resolution (m) and the count convention (``"round"``: paper eq. 1; ``"floor"``: the
        netsim :class:`~netsim.io.Encoder`).
    """
    period = controller.period_ns
    if period % tick_ns:
        raise ConfigError(f"control period {format_time(period)} must be a multiple of the ISR tick "
                          f"{format_time(tick_ns)}")
    if not 0 <= delay_ns < period:
        raise ConfigError(f"actuation delay must be in [0, period), got {format_time(delay_ns)}")
    if not duration > 0:
        raise ConfigError(f"duration must be positive, got {duration}")
    quant = Quantizer.from_bits(q, delta_p, rounding)
    full = Quantizer(delta_p)
    controller.reset()
    n_ticks = period // tick_ns
    tick_tau = np.arange(1, n_ticks + 1) * (tick_ns * 1e-9)
    h = period * 1e-9
    d = delay_ns * 1e-9
    n_max = int(math.floor(duration / h)) + 1

    p, v, uv_prev = 0.0, 0.0, 0.0
    count, direction, stamp = quant.count(0.0), 1, -1
    rec = {k: np.empty(n_max) for k in ("t", "p", "v", "uv", "vh", "bh", "vr")}
    rec_c = np.empty(n_max, dtype=np.int64)
    rec_cf = np.empty(n_max, dtype=np.int64)
    edges: list[float] = []
    reached, t_reach, t_end = False, math.nan, duration
    n = 0
    for k in range(n_max):
        t_ns = k * period
        t = t_ns * 1e-9
        if not reached and p >= distance:
            reached, t_reach = True, t
            t_end = min(duration, t + tail)
        if t > t_end + 1e-12:
            break
        n = k + 1
        r = vref if not reached else 0.0
        uv = controller.update(t_ns, count, direction, stamp, r)
        rec["t"][k], rec["p"][k], rec["v"][k] = t, p, v
        rec["uv"][k], rec["vh"][k], rec["bh"][k], rec["vr"][k] = uv, controller.v_hat, controller.u_bias_hat, r
        rec_c[k], rec_cf[k] = count, full.count(p)
        # plant over (t, t + h]: previous command until the delay, then the new one
        f = friction.level(p)
        fs = friction.params.stiction * f
        if d > 0.0:
            first = tick_tau <= d
            pa, va = propagate(p, v, ku * uv_prev, f, fs, np.append(tick_tau[first], d), td)
            pb, vb = propagate(float(pa[-1]), float(va[-1]), ku * uv, f, fs, tick_tau[~first] - d, td)
            pt = np.concatenate([pa[:-1], pb])
            vt = np.concatenate([va[:-1], vb])
        else:
            pt, vt = propagate(p, v, ku * uv, f, fs, tick_tau, td)
        counts = np.floor(pt / quant.delta + (0.5 if rounding == "round" else 0.0)).astype(np.int64)
        prev = np.concatenate(([count], counts[:-1]))
        changed = np.nonzero(counts != prev)[0]
        if changed.size:
            j = int(changed[-1])
            direction = 1 if counts[j] > prev[j] else -1
            stamp = t_ns + (j + 1) * tick_ns
            edges.extend((t_ns + (changed + 1) * tick_ns) * 1e-9)
            count = int(counts[-1])
        p, v = float(pt[-1]), float(vt[-1])
        uv_prev = uv
        if not math.isfinite(p):
            break
    return CartRun(
        t=rec["t"][:n].copy(),
        p=rec["p"][:n].copy(),
        v=rec["v"][:n].copy(),
        uv=rec["uv"][:n].copy(),
        v_hat=rec["vh"][:n].copy(),
        u_bias_hat=rec["bh"][:n].copy(),
        vref=rec["vr"][:n].copy(),
        count=rec_c[:n].copy(),
        count_full=rec_cf[:n].copy(),
        edge_times=np.asarray(edges),
        ku=ku,
        delta=quant.delta,
        reached=reached,
        t_reach=t_reach,
    )
