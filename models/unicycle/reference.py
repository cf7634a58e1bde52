"""A plain numpy loop of the 2WD cart study: truth, IR sensors, the same EKF and tracking law, no network.

Timing: sample ``k`` at ``k Ts``; the sensors sample there (front every ``front_every`` samples, side every
``side_every``, in their phases' on-windows), the filter fuses them at once, the law computes ``u_k`` and the
truth moves along the exact arc with ``u_k`` held over ``[k Ts, (k+1) Ts)``, then jumps by ``w_k ~ N(0,
Q_true)``. This is the netsim scenario without network and execution delays; the Monte-Carlo studies with
hundreds of runs per setting use it (and the benchmark compares a netsim run against it).
"""

from __future__ import annotations

import math
from typing import Any, Literal, Sequence

import numpy as np

from models.unicycle.design import LQR_Q, LQR_R, PHASES, Phase, TrackingLaw, Trajectory, make_ekf
from models.unicycle.model import (
    FRONT_OFFSET, P0, Q_REPORT, R_REPORT, SIDE_DERIVED, TS, WALL_FRONT, WALL_SIDE, XI0_HAT, arc, measure,
    measure_jacobian, side_offset,
)

__all__ = ["simulate"]


def simulate(
    seed: int,
    *,
    phases: Sequence[Phase] = PHASES,
    Q_filter: Any = Q_REPORT,
    R_filter: Any = R_REPORT,
    Q_true: Any = Q_REPORT,
    R_true: Any = R_REPORT,
    P0_: Any = P0,
    law: Literal["feedforward", "lqr", "lqr_ff"] = "feedforward",
    lqr_Q: Any = LQR_Q,
    lqr_R: Any = LQR_R,
    a_sign: Literal["derived", "printed"] = "derived",
    side_model: Literal["derived", "printed"] = "derived",
    front_every: int = 2,
    side_every: int = 4,
    ts: float = TS,
) -> dict[str, np.ndarray]:
    """One run; returns arrays over samples ``k = 0..N``: ``t``, ``truth`` (N+1 x 3), ``xhat``, ``P`` (N+1 x 3 x 3,
    posteriors), ``zhat``/``zsd`` (predicted readings and their standard deviations), ``u`` (commands), ``ref``.

    Random streams (from ``numpy.random.SeedSequence(seed)``): initial pose, process noise, front noise, side
    noise, each its own.
    """
    traj = Trajectory(phases, XI0_HAT, ts)
    ctl = TrackingLaw(traj, law, lqr_Q, lqr_R, a_sign)
    ekf = make_ekf(Q_filter, R_filter, XI0_HAT, P0_, ts, side_model)
    s0, s1, s2, s3 = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(4))
    sdQ = np.sqrt(np.diag(np.asarray(Q_true, dtype=float)))
    sdR = np.sqrt(np.asarray(R_true, dtype=float).reshape(-1))
    Rf = np.asarray(R_filter, dtype=float).reshape(-1)
    off_f = side_offset(side_model)
    n = traj.n
    xi = XI0_HAT + np.sqrt(np.diag(np.asarray(P0_, dtype=float))) * s0.standard_normal(3)
    out = {k: np.empty((n + 1, 3)) for k in ("truth", "xhat", "ref")}
    out["P"] = np.empty((n + 1, 3, 3))
    out["zhat"] = np.empty((n + 1, 2))
    out["zsd"] = np.empty((n + 1, 2))
    out["u"] = np.empty((n + 1, 2))
    out["z"] = np.full((n + 1, 2), np.nan)
    for k in range(n + 1):
        ph = traj.phase(k * ts)
        if ph.front and k % front_every == 0:
            z = measure(xi, FRONT_OFFSET, WALL_FRONT) + sdR[0] * s2.standard_normal()
            out["z"][k, 0] = z
            ekf.correct([z], "front")
        if ph.side and k % side_every == 0:
            z = measure(xi, SIDE_DERIVED, WALL_SIDE) + sdR[1] * s3.standard_normal()
            out["z"][k, 1] = z
            ekf.correct([z], "side")
        xh, P = ekf.x.copy(), ekf.P.copy()
        out["truth"][k], out["xhat"][k], out["P"][k] = xi, xh, P
        out["ref"][k] = traj.at(k)[0]
        for j, (off, wall) in enumerate(((FRONT_OFFSET, WALL_FRONT), (off_f, WALL_SIDE))):
            H = measure_jacobian(xh, off, wall)
            out["zhat"][k, j] = measure(xh, off, wall)
            out["zsd"][k, j] = math.sqrt(float((H @ P @ H.T)[0, 0]) + Rf[j])
        u = ctl.step(k, xh)
        out["u"][k] = u
        ekf.predict(u)
        xi = arc(xi, float(u[0]), float(u[1]), ts) + sdQ * s1.standard_normal(3)
    out["t"] = np.arange(n + 1) * ts
    return out
