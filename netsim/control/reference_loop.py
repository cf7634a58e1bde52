"""A plain-numpy closed loop of the event-triggered scheme, without kernel or network.

Discrete plant ``x+ = A x + B (u + d)``, ``y = C x + v`` at the fast period; at every instant ``k``: the
sensor trigger sees ``y_k`` (and ``r_k``); a sent sample goes to the :class:`ControlSide` at once, whose
packet (if eq (22) lets it go) reaches the actuator at once; the actuator's :class:`PlayoutBuffer`
gives ``u_k``, held over ``[k, k+1)``. This is the idealized timing of the paper (zero computation and
transmission delay). It is the reference the kernel/network simulation is compared with (benchmark,
tests) and a quick way to explore the algorithms.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from netsim.control.cascade import ControlSide
from netsim.control.packets import PlayoutBuffer

__all__ = ["LoopTrace", "simulate_loop"]


@dataclass
class LoopTrace:
    """Per-instant arrays of one run (length ``n_steps``)."""

    y: np.ndarray        # noise-free plant output
    y_meas: np.ndarray   # measured output (with noise)
    u: np.ndarray        # applied action
    r: np.ndarray
    d: np.ndarray        # disturbance at the plant input
    sent_sc: np.ndarray  # bool: sensor -> controller transmission at k
    sent_ca: np.ndarray  # bool: controller -> actuator transmission at k
    N: np.ndarray        # multiplicity at arrivals (0 where nothing arrived)
    y_hat: np.ndarray    # estimate at arrivals (nan elsewhere)
    d_hat: np.ndarray

    @property
    def n_sc(self) -> int:
        return int(self.sent_sc.sum())

    @property
    def n_ca(self) -> int:
        return int(self.sent_ca.sum())


def simulate_loop(A, B, C, control: ControlSide, sensor_trigger, n_steps: int, *, reference,
                  x0=None, noise_std: float = 0.0, disturbance=None, rng: np.random.Generator | None = None,
                  y_out=None) -> LoopTrace:
    """Run ``n_steps`` fast periods.

    Parameters
    ----------
    A, B, C
        Discrete plant (input ``u + d``).
    reference
        ``r(k) -> float``.
    noise_std
        Standard deviation of the white measurement noise ``v`` (needs ``rng``).
    disturbance
        Array of ``d_k`` (length ``n_steps``) or None.
    """
    A = np.asarray(A, float)
    b = np.asarray(B, float).reshape(-1)
    c = np.asarray(C, float).reshape(-1)
    x = np.zeros(A.shape[0]) if x0 is None else np.asarray(x0, float).copy()
    d = np.zeros(n_steps) if disturbance is None else np.asarray(disturbance, float)
    if noise_std > 0:
        if rng is None:
            raise ValueError("simulate_loop: noise_std > 0 needs an rng")
        noise = rng.standard_normal(n_steps) * noise_std
    else:
        noise = np.zeros(n_steps)
    buf = PlayoutBuffer()
    ys = np.empty(n_steps); ym = np.empty(n_steps); us = np.empty(n_steps); rs = np.empty(n_steps)
    ssc = np.zeros(n_steps, bool); sca = np.zeros(n_steps, bool); Ns = np.zeros(n_steps, int)
    yh = np.full(n_steps, np.nan); dh = np.full(n_steps, np.nan)
    for k in range(n_steps):
        yk = float(c @ x)
        ymk = yk + noise[k]
        rk = reference(k)
        ys[k], ym[k], rs[k] = yk, ymk, rk
        if sensor_trigger.should_send(k, ymk, rk):
            ssc[k] = True
            dec = control.on_measurement(k, ymk)
            Ns[k] = dec.N
            yh[k], dh[k] = dec.y_hat, dec.d_hat
            if dec.send:
                sca[k] = True
                buf.receive(dec.packet)
        u = buf.value(k)
        us[k] = u
        x = A @ x + b * (u + d[k])
    return LoopTrace(ys, ym, us, rs, d, ssc, sca, Ns, yh, dh)
