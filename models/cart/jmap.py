"""Offline JMAP reconstruction of a cart trajectory from all its encoder samples (paper section VII).

The paper reconstructs the velocity of an experiment with "a simple form of the JMAP estimator": only
``p`` and ``v`` are states, the effect of ``u`` is ignored, and the measurement constraints (eq. 7) are
relaxed to allow each measurement to have arrived one sample too soon or too late; the optimisation is
solved for the whole trajectory at once.

Formulation
-----------
States ``x(k) = (p(k), v(k))`` at the sample instants ``k = 0..N-1`` (period ``h``). The process noise
``w(k) = x(k+1) - A x(k)`` of a double integrator driven by white acceleration noise has covariance
``R = [[h^3/3, h^2/2], [h^2/2, h]]`` (times the noise intensity, which does not change the optimum), and
JMAP minimises ``sum_k w(k)' R^-1 w(k)`` (eq. 8 without the prior term) subject to the interval
constraints. The cost is the minimum acceleration energy, so the solution is a smoothing cubic spline.

Timing relaxation: a measurement labelled ``k`` may belong to ``k-1``, ``k`` or ``k+1``; equivalently the
position at ``k`` lies in the interval of one of the measurements labelled ``k-1..k+1``. The union of those
intervals is replaced by its hull ``[min lo, max hi]`` (convex; exact when the counts are adjacent, and for
monotone motion the same as ``p(k+1) >= lo(k)``, ``p(k-1) <= hi(k)``).

The QP is solved by clarabel with a banded sparse ``P`` (scipy.sparse), in units of one quantization step
and one sample for good scaling.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from netsim.errors import SimulationError
from netsim.lazy_import import lazy_module

sp = lazy_module("scipy.sparse")  # imported at first use (30 ms): a lookup of another cart plugin needs none

__all__ = ["JmapResult", "reconstruct", "interval_bounds"]

log = logging.getLogger(__name__)


@dataclass
class JmapResult:
    """Reconstructed trajectory at the sample instants."""

    p: np.ndarray  # m
    v: np.ndarray  # m/s
    status: str
    solve_time: float  # s


def interval_bounds(counts: np.ndarray, slack: int = 1, rounding: str = "round") -> tuple[np.ndarray, np.ndarray]:
    """Bounds ``(lo, hi)`` of ``p(k)`` in quantization steps, with the +-``slack`` sample relaxation."""
    c = np.asarray(counts, dtype=float)
    shift = 0.5 if rounding == "round" else 0.0
    lo, hi = c - shift, c - shift + 1.0
    if slack > 0:
        n = len(c)
        lo_r, hi_r = lo.copy(), hi.copy()
        for s in range(1, slack + 1):
            for sign in (-1, 1):
                idx = np.clip(np.arange(n) + sign * s, 0, n - 1)
                lo_r = np.minimum(lo_r, lo[idx])
                hi_r = np.maximum(hi_r, hi[idx])
        lo, hi = lo_r, hi_r
    return lo, hi


def reconstruct(
    counts: np.ndarray,
    h: float,
    delta: float,
    *,
    slack: int = 1,
    rounding: str = "round",
    v0: float | None = None,
    p0: float | None = None,
) -> JmapResult:
    """JMAP trajectory given the encoder counts sampled every ``h`` seconds.

    Parameters
    ----------
    counts
        Encoder counts at the sample instants.
    h
        Sample period in s.
    delta
        Quantization step of the counts in m.
    slack
        Timing relaxation in samples (paper: 1; 0 gives the plain interval constraints of eq. 7).
    rounding
        Meaning of a count (``"round"``: eq. 1).
    v0, p0
        Known initial velocity/position (m/s, m), e.g. the cart at rest; ``None`` leaves them free.

    Raises
    ------
    SimulationError
        When the solver does not find an optimum.
    """
    import time

    import clarabel

    counts = np.asarray(counts)
    n = len(counts)
    if n < 3:
        raise SimulationError(f"JMAP reconstruction needs at least 3 samples, got {n}")
    lo, hi = interval_bounds(counts, slack, rounding)
    # units: positions in steps, velocities in steps per sample -> R = [[1/3, 1/2], [1/2, 1]]
    rinv = np.array([[12.0, -6.0], [-6.0, 4.0]])
    m = n - 1
    # D maps x = (p0, v0, p1, v1, ...) to w(k) = x(k+1) - A x(k), A = [[1, 1], [0, 1]]:
    #   w_p(k) = p(k+1) - p(k) - v(k),   w_v(k) = v(k+1) - v(k)
    k = np.arange(m)
    rows = np.concatenate([2 * k, 2 * k, 2 * k, 2 * k + 1, 2 * k + 1])
    cols = np.concatenate([2 * k + 2, 2 * k, 2 * k + 1, 2 * k + 3, 2 * k + 1])
    vals = np.concatenate([np.ones(m), -np.ones(m), -np.ones(m), np.ones(m), -np.ones(m)])
    d = sp.csc_matrix((vals, (rows, cols)), shape=(2 * m, 2 * n))
    w = sp.kron(sp.identity(m, format="csc"), sp.csc_matrix(rinv), format="csc")
    p_mat = sp.triu((d.T @ w @ d).tocsc(), format="csc")
    q_vec = np.zeros(2 * n)
    sel = sp.csc_matrix((np.ones(n), (np.arange(n), 2 * np.arange(n))), shape=(n, 2 * n))
    blocks = [sel, -sel]
    rhs = [hi, -lo]
    cones = [clarabel.NonnegativeConeT(2 * n)]
    eq_rows = []
    eq_rhs = []
    if p0 is not None:
        eq_rows.append(0)
        eq_rhs.append(p0 / delta)
    if v0 is not None:
        eq_rows.append(1)
        eq_rhs.append(v0 * h / delta)
    if eq_rows:
        e = sp.csc_matrix((np.ones(len(eq_rows)), (np.arange(len(eq_rows)), eq_rows)), shape=(len(eq_rows), 2 * n))
        blocks = [e] + blocks
        rhs = [np.asarray(eq_rhs)] + rhs
        cones = [clarabel.ZeroConeT(len(eq_rows))] + cones
    a_mat = sp.vstack(blocks, format="csc")
    b_vec = np.concatenate(rhs)
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    t0 = time.perf_counter()
    solver = clarabel.DefaultSolver(p_mat, q_vec, a_mat, b_vec, cones, settings)
    sol = solver.solve()
    elapsed = time.perf_counter() - t0
    status = str(sol.status)
    if "Solved" not in status:
        raise SimulationError(f"JMAP reconstruction failed: clarabel status {status}")
    x = np.asarray(sol.x).reshape(n, 2)
    log.debug("JMAP: %d samples, %s in %.3f s", n, status, elapsed)
    return JmapResult(p=x[:, 0] * delta, v=x[:, 1] * delta / h, status=status, solve_time=elapsed)
