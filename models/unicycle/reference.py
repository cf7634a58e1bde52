"""A plain numpy loop of the 2WD cart study: truth, IR sensors, the same EKF and tracking law, no network.

Timing: sample ``k`` at ``k Ts``; the sensors sample there (front every ``front_every`` samples, side every
``side_every``, in their phases' on-windows), the filter fuses them at once, the law computes ``u_k`` and the
truth moves along the exact arc with ``u_k`` held over ``[k Ts, (k+1) Ts)``, then jumps by ``w_k ~ N(0,
Q_true)``. This is the netsim scenario without network and execution delays; the Monte-Carlo studies with
hundreds of runs per setting use it (and the benchmark compares a netsim run against it).
"""

from __future__ import annotations

from typing import Any, Literal, Sequence

import numpy as np

from netsim.models.unicycle.design import LQR_Q, LQR_R, PHASES, Phase, TrackingLaw, Trajectory
from netsim.models.unicycle.ekf import CartEkf, Sensor
from netsim.models.unicycle.model import (
    FRONT_OFFSET, P0, Q_REPORT, R_REPORT, SIDE_DERIVED, TS, WALL_FRONT, WALL_SIDE, XI0_HAT, arc_floats,
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
    ekf = CartEkf(Q_filter, R_filter, XI0_HAT, P0_, ts, side_model)
    s0, s1, s2, s3 = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(4))
    sdQ = np.sqrt(np.diag(np.asarray(Q_true, dtype=float)))
    sdR = np.sqrt(np.asarray(R_true, dtype=float).reshape(-1))
    n = traj.n
    front, side = Sensor(FRONT_OFFSET, WALL_FRONT, 1.0), Sensor(SIDE_DERIVED, WALL_SIDE, 1.0)  # the truth's
    xi0 = XI0_HAT + np.sqrt(np.diag(np.asarray(P0_, dtype=float))) * s0.standard_normal(3)
    x, y, th = (float(v) for v in xi0)
    # the random numbers of the whole run, drawn per stream in the order one-at-a-time draws would give them
    wq = (s1.standard_normal((n + 1, 3)) * sdQ).tolist()
    on = [traj.phase(k * ts) for k in range(n + 1)]
    k_front = [k for k in range(n + 1) if on[k].front and k % front_every == 0]
    k_side = [k for k in range(n + 1) if on[k].side and k % side_every == 0]
    vf = dict(zip(k_front, (sdR[0] * s2.standard_normal(len(k_front))).tolist()))
    vs = dict(zip(k_side, (sdR[1] * s3.standard_normal(len(k_side))).tolist()))
    truth, xhat, Ps, zhat, zsd, us = [], [], [], [], [], []
    z = np.full((n + 1, 2), np.nan)
    for k in range(n + 1):
        if k in vf:
            z[k, 0] = zk = front.h(x, y, th) + vf[k]
            ekf.correct(zk, "front")
        if k in vs:
            z[k, 1] = zk = side.h(x, y, th) + vs[k]
            ekf.correct(zk, "side")
        truth.append((x, y, th))
        xhat.append(ekf.x)
        Ps.append(ekf.P)
        zf, sf = ekf.predicted("front")
        zs, ss = ekf.predicted("side")
        zhat.append((zf, zs))
        zsd.append((sf, ss))
        v, w = ctl.step(k, ekf.x)
        us.append((v, w))
        ekf.predict(v, w)
        x, y, th = arc_floats(x, y, th, v, w, ts)
        q = wq[k]
        x, y, th = x + q[0], y + q[1], th + q[2]
    P = np.array(Ps)
    out = {"truth": np.array(truth), "xhat": np.array(xhat), "ref": traj.poses.copy(), "zhat": np.array(zhat),
           "zsd": np.array(zsd), "u": np.array(us), "z": z,
           "P": P[:, [0, 1, 2, 1, 3, 4, 2, 4, 5]].reshape(n + 1, 3, 3)}
    out["t"] = np.arange(n + 1) * ts
    return out
