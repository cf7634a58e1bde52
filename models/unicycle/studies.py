"""The experiments of the 2WD cart report (numbers only; :mod:`netsim.models.unicycle.report` writes them up).

Monte-Carlo studies with hundreds of runs per setting use the numpy loop (:mod:`netsim.models.unicycle.reference`, the
same EKF and law without network, ~0.2 s a run); the networked experiments run the scenarios through netsim
sweeps (``replicates``). Every function returns plain numbers and arrays.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any, Callable

import numpy as np

from netsim.casestudy import run_all
from netsim.models.unicycle.design import LQR_Q, LQR_R, PHASES, Phase, Trajectory, cart_frame_error, error_model, lqr_gain
from netsim.models.unicycle.design import Law
from netsim.models.unicycle.metrics import run_measures
from netsim.models.unicycle.model import (
    FRONT_OFFSET, P0, Q_REPORT, R_REPORT, SIDE_DERIVED, SIDE_PRINTED, WALL_FRONT, WALL_SIDE, Side, jac_A, measure,
    measure_jacobian,
)
from netsim.models.unicycle.reference import simulate

__all__ = ["QR_SETTINGS", "mc_runs", "qr_study", "observability", "lqr_facts", "printed_side_study",
           "printed_lqr_study", "PHASE_NAMES", "PHASE_ENDS"]

PHASE_NAMES = [p.name for p in PHASES]
PHASE_ENDS = np.cumsum([p.duration for p in PHASES]).tolist()
#: The four (Q, R) combinations of the report's Fig. 1: factors on the filter's Q and R (the truth keeps Q, R).
QR_SETTINGS = {"(Q, R)": (1.0, 1.0), "(5Q, R)": (5.0, 1.0), "(Q, 5R)": (1.0, 5.0), "(5Q, 5R)": (5.0, 5.0)}


def _one(args: tuple[int, dict[str, Any]]) -> dict[str, Any]:
    seed, kw = args
    import netsim  # noqa: F401  (BLAS pinning in worker processes)

    o = simulate(seed, **kw)
    sd = np.sqrt(np.diagonal(o["P"], axis1=1, axis2=2))
    m = run_measures(o["t"], o["truth"], o["xhat"], sd, np.linalg.det(o["P"]), o["ref"], PHASE_NAMES, PHASE_ENDS)
    e = o["truth"] - o["xhat"]
    return {"m": m, "e": e.astype(np.float32), "xhat": o["xhat"], "sd": sd.astype(np.float32),
            "z": o["z"], "zhat": o["zhat"], "zsd": o["zsd"]}


def mc_runs(n: int, seed0: int = 0, workers: int | None = None, keep: bool = True,
            progress: Callable[[int, int, str], None] | None = None, what: str = "", **kw: Any) -> list[dict]:
    """``n`` runs of :func:`~netsim.models.unicycle.reference.simulate` with seeds ``seed0 .. seed0 + n - 1``, on
    one process pool (:func:`netsim.casestudy.run_all`; ``workers`` default: up to 4, one per CPU)."""
    workers = workers or min(os.cpu_count() or 1, 4)
    out = run_all(_one, [(seed0 + i, kw) for i in range(n)], workers=workers, progress=progress, what=what,
                  chunksize=max(1, n // (4 * workers)))
    if not keep:
        for r in out:
            r.pop("xhat")
    return out


def _window(t: np.ndarray, a: float, b: float) -> np.ndarray:
    return (t >= a - 1e-9) & (t < b - 1e-9)


def qr_study(runs: list[dict], t: np.ndarray) -> dict[str, float]:
    """Measures of one (Q, R) setting over its runs (names in the report's Q/R table)."""
    E = np.stack([r["e"] for r in runs]).astype(float)  # runs x N x 3
    X = np.stack([r["xhat"] for r in runs])
    out: dict[str, float] = {"runs": float(len(runs))}
    st, tu, fr = _window(t, 0, 4), _window(t, 4, 6), _window(t, 6, 10.001)
    for j, s in enumerate(("x", "y", "theta")):
        for name, w in (("straight", st), ("turn", tu), ("front", fr)):
            out[f"rmse_{s}_{name}"] = float(np.sqrt(np.mean(E[:, w, j] ** 2)))
            per_run = E[:, w, j].mean(axis=1)
            out[f"bias_{s}_{name}"] = float(per_run.mean())
            out[f"bias_se_{s}_{name}"] = float(per_run.std(ddof=1) / math.sqrt(len(runs)))
        # smoothness: RMS second difference of the estimate in the straight part (the reference's is 0 there)
        d2 = np.diff(X[:, st, j], n=2, axis=1)
        out[f"rough_{s}_straight"] = float(np.sqrt(np.mean(d2**2)))
        cov = np.array([r["m"][f"cover_{s}_all"] for r in runs])
        out[f"cover_{s}"] = float(cov.mean())
        out[f"cover_se_{s}"] = float(cov.std(ddof=1) / math.sqrt(len(runs)))
    # convergence after the turn: MC RMS error of y and theta in the first and the last second of the front part
    for j, s in ((1, "y"), (2, "theta")):
        out[f"rmse_{s}_6to7"] = float(np.sqrt(np.mean(E[:, _window(t, 6, 7), j] ** 2)))
        out[f"rmse_{s}_9to10"] = float(np.sqrt(np.mean(E[:, _window(t, 9, 10.001), j] ** 2)))
        rms_t = np.sqrt(np.mean(E[:, :, j] ** 2, axis=0))
        i6 = int(np.searchsorted(t, 6.0 - 1e-9))
        below = np.flatnonzero(rms_t[i6:] <= 0.5 * rms_t[i6])
        out[f"halving_{s}_s"] = float(t[i6 + below[0]] - t[i6]) if below.size else float("nan")
    return out


def observability(phase: Phase, theta: float, side: str = "derived") -> dict[str, float]:
    """Rank and smallest singular value of ``[C; C A; C A^2]`` at heading ``theta`` with the phase's sensors on."""
    xi = np.array([-0.2, -0.2, theta])
    A = jac_A(xi, np.array([phase.v, phase.w]))
    rows = []
    if phase.front:
        rows.append(measure_jacobian(xi, FRONT_OFFSET, WALL_FRONT))
    if phase.side:
        rows.append(measure_jacobian(xi, SIDE_DERIVED if side == "derived" else SIDE_PRINTED, WALL_SIDE))
    if not rows:
        return {"rank_C": 0.0, "rank_O": 0.0, "sigma_min_O": 0.0}
    C = np.vstack(rows)
    O = np.vstack([C, C @ A, C @ A @ A])
    sv = np.linalg.svd(O, compute_uv=False)
    return {"rank_C": float(np.linalg.matrix_rank(C)), "rank_O": float(np.linalg.matrix_rank(O, tol=1e-12)),
            "sigma_min_O": float(sv[min(2, len(sv) - 1)] if len(sv) >= 3 else 0.0)}


def lqr_facts() -> dict[float, dict[str, Any]]:
    """Gains, closed-loop eigenvalues and the printed-sign design for each ``v_ref`` of the trajectory."""
    out: dict[float, dict[str, Any]] = {}
    for v in sorted({p.v for p in PHASES}, reverse=True):
        K = lqr_gain(v)
        A, B = error_model(v)
        Kp = lqr_gain(v, a_sign="printed")
        out[v] = {"K": K, "eig": np.linalg.eigvals(A - B @ K), "eig_printed_on_true": np.linalg.eigvals(A - B @ Kp),
                  "lag_e1": v / -K[0, 0]}
    return out


def lqr_noise_free(law: Law = "lqr", a_sign: Side = "derived") -> dict[str, float]:
    """The tracking law on the noise-free cart with a perfect initial estimate (numpy loop): cart-frame errors."""
    o = simulate(0, law=law, a_sign=a_sign, Q_true=np.zeros((3, 3)), R_true=np.zeros(2), P0_=P0 * 1e-12,
                 Q_filter=Q_REPORT, R_filter=R_REPORT)
    e = np.array([cart_frame_error(r, x) for r, x in zip(o["ref"], o["truth"])])
    t = o["t"]
    st = _window(t, 2, 4)
    return {"e1_straight_mean": float(e[st, 0].mean()), "e1_max": float(np.abs(e[:, 0]).max()),
            "e2_max": float(np.abs(e[:, 1]).max()), "e3_max": float(np.abs(e[:, 2]).max()),
            "e3_turn_end": float(e[_window(t, 5.5, 6), 2].mean()), "e_final": float(np.abs(e[-1]).max())}


def printed_side_study(n: int, workers: int | None = None) -> dict[str, float]:
    """The filter with the printed eq (6) side offset, the cart with the side sensor at -Y' as the text says."""
    runs = mc_runs(n, seed0=5000, workers=workers, side_model="printed")
    base = mc_runs(n, seed0=5000, workers=workers)
    out = {}
    for name, rs in (("printed", runs), ("derived", base)):
        E = np.stack([r["e"] for r in rs]).astype(float)
        out[f"{name}_rmse_theta_straight"] = float(np.sqrt(np.mean(E[:, :400, 2] ** 2)))
        out[f"{name}_cover_theta"] = float(np.mean([r["m"]["cover_theta_all"] for r in rs]))
        out[f"{name}_nees"] = float(np.mean([r["m"]["nees_all"] for r in rs]))
    return out


def printed_lqr_study() -> dict[str, float]:
    """Noise-free tracking with K designed on the printed eq (26) against the derived design."""
    d = lqr_noise_free("lqr", "derived")
    p = lqr_noise_free("lqr", "printed")
    return {"derived_e2_max": d["e2_max"], "printed_e2_max": p["e2_max"], "derived_e3_max": d["e3_max"],
            "printed_e3_max": p["e3_max"], "derived_final": d["e_final"], "printed_final": p["e_final"]}


def trajectory() -> Trajectory:
    """The study's reference trajectory."""
    return Trajectory()


__all__ += ["lqr_noise_free", "trajectory", "LQR_Q", "LQR_R", "P0"]


def delay_margin(v_ref: float, max_delay: int = 400) -> int | None:
    """Smallest whole number of samples ``d`` of input delay for which ``u = -K e'`` (no estimator) is unstable
    on the linear error model of eq (26): the spectral radius of the loop augmented with ``d`` delayed inputs."""
    K = lqr_gain(v_ref)
    A, B = error_model(v_ref)
    for d in range(max_delay + 1):
        n = 3 + 2 * d
        M = np.zeros((n, n))
        M[:3, :3] = A
        if d == 0:
            M[:3, :3] = A - B @ K
        else:
            M[:3, 3 + 2 * (d - 1):] = B  # the oldest command acts now
            M[3:5, :3] = -K  # the newest command enters the line
            for i in range(1, d):
                M[3 + 2 * i:5 + 2 * i, 1 + 2 * i:3 + 2 * i] = np.eye(2)
        if max(abs(np.linalg.eigvals(M))) >= 1.0:
            return d
    return None


__all__ += ["delay_margin"]


def wall_distances() -> tuple[float, float]:
    """Smallest and largest noiseless IR reading along the reference trajectory while its sensor is on [m]."""
    traj = Trajectory()
    vals = []
    for k in range(traj.n + 1):
        ph = traj.phase(k * traj.ts)
        xi = traj.poses[k]
        if ph.front:
            vals.append(measure(xi, FRONT_OFFSET, WALL_FRONT))
        if ph.side:
            vals.append(measure(xi, SIDE_DERIVED, WALL_SIDE))
    return float(min(vals)), float(max(vals))


def net_qr_study(summary: Any, folder: Any, t: np.ndarray) -> dict[str, dict[str, float]]:
    """:func:`qr_study` per ``setting`` of a netsim Q/R sweep, from each run's ``signals.csv`` (truth ``x, y,
    theta`` and ``xhat[i]`` on the filter's 10 ms grid) and its coverage metrics."""
    from netsim.results.folder import RunFolder

    out: dict[str, dict[str, float]] = {}
    cols = ["time_s", "x", "y", "theta", "xhat[0]", "xhat[1]", "xhat[2]"]
    for setting, d in summary.groupby("setting", sort=False):
        runs = []
        for _, row in d.iterrows():
            sig = RunFolder(Path(folder) / row["folder"]).signals(cols)
            k = np.rint(sig["time_s"].to_numpy() / (t[1] - t[0])).astype(int)
            keep = (k >= 0) & (k < len(t))
            truth = np.full((len(t), 3), np.nan)
            xhat = np.full((len(t), 3), np.nan)
            truth[k[keep]] = sig[["x", "y", "theta"]].to_numpy()[keep]
            xhat[k[keep]] = sig[["xhat[0]", "xhat[1]", "xhat[2]"]].to_numpy()[keep]
            e = truth - xhat
            e[:, 2] = np.arctan2(np.sin(e[:, 2]), np.cos(e[:, 2]))
            runs.append({"e": e, "xhat": xhat,
                         "m": {f"cover_{s}_all": float(row[f"unicycle.cover_{s}_all"]) for s in ("x", "y", "theta")}})
        out[str(setting)] = qr_study(runs, t)
    return out


__all__ += ["wall_distances", "net_qr_study"]
