"""QP solver back-ends of :class:`~netsim.control.mpc.LinearMPC` (daqp, clarabel, osqp, piqp).

Each back-end solves ``min 1/2 U'HU + g'U`` subject to ``lo <= G U <= hi`` for a constant ``H`` and ``G`` given
once, with ``g`` and the bounds new at each call, and returns ``(U or None, status, iterations)``: ``None`` when
the problem is infeasible or the solver did not converge. Each solver is imported when its back-end is made.

The default, daqp (a dual active-set method), was chosen by measurement on a 4-state, horizon-20 problem with
input, rate and state constraints (20 variables, 80 constraint rows, machine with 2 loaded cores): median
17 us per constrained solve with its reusable workspace (which starts from the previous working set), exact
to 4e-15; piqp 210 us and 7e-6; clarabel 990 us and 6e-6 (no warm start for interior-point methods); osqp
73 us median but 1.1 ms at the 90th percentile and 2e-5 at tolerance 1e-6 (and it hits its iteration limit at
1e-9).
"""

from __future__ import annotations

import abc

from typing import Any

import numpy as np

__all__ = ["Backend", "make_backend"]


class Backend(abc.ABC):
    """One QP solver: ``solve(g, lo, hi, warm) -> (U or None, status, iterations)``.

    The problem is ``min 1/2 U'HU + g'U`` subject to ``lo <= G U <= hi``; ``warm`` is a primal guess (used by
    back-ends whose ``warm_start`` is true).
    """

    warm_start = False

    @abc.abstractmethod
    def solve(self, g: np.ndarray, lo: np.ndarray, hi: np.ndarray, warm: np.ndarray | None) -> tuple[Any, str, int]:
        """Solve for the linear term ``g`` and the bounds ``lo``, ``hi``."""


class _Daqp(Backend):
    """DAQP's reusable workspace: set up once; each solve updates ``g`` and the bounds and starts from the
    previous solve's working set (its warm start)."""

    warm_start = False  # the workspace keeps the working set itself; a shifted primal guess is not passed

    def __init__(self, H: np.ndarray, G: np.ndarray, tol: float) -> None:
        import daqp

        self.model = daqp.Model()
        self.H = np.ascontiguousarray(H)
        self.G = np.ascontiguousarray(G)
        self.tol = tol
        self.ready = False

    def solve(self, g, lo, hi, warm):  # noqa: D102
        lo = np.where(np.isfinite(lo), lo, -1e30)
        hi = np.where(np.isfinite(hi), hi, 1e30)
        if not self.ready:
            self.model.setup(self.H, g, self.G, hi, lo)
            self.model.settings = {"primal_tol": self.tol}
            self.ready = True
        else:
            self.model.update(f=g, bupper=hi, blower=lo)
        x, _, flag, info = self.model.solve()
        return (np.array(x) if flag == 1 else None), f"daqp exitflag {flag}", int(info.get("iterations", 0))


class _Osqp(Backend):
    warm_start = True

    def __init__(self, H: np.ndarray, G: np.ndarray, tol: float) -> None:
        import osqp
        import scipy.sparse as sp

        self.solver = osqp.OSQP()
        lo = np.full(G.shape[0], -np.inf)
        self.solver.setup(
            sp.csc_matrix(np.triu(H)), np.zeros(H.shape[0]), sp.csc_matrix(G), lo, -lo,
            verbose=False, polishing=False, eps_abs=tol, eps_rel=tol, warm_starting=True, max_iter=20000,
        )  # fmt: skip

    def solve(self, g, lo, hi, warm):  # noqa: D102
        self.solver.update(q=g, l=lo, u=hi)
        if warm is not None:
            self.solver.warm_start(x=warm)
        res = self.solver.solve(raise_error=False)
        status = str(res.info.status)
        ok = res.info.status_val in (1, 2) and res.x is not None and np.all(np.isfinite(res.x))
        return (np.asarray(res.x) if ok else None), f"osqp {status}", int(res.info.iter)


class _Piqp(Backend):
    def __init__(self, H: np.ndarray, G: np.ndarray, tol: float) -> None:
        import piqp

        self._piqp = piqp
        self.solver = piqp.DenseSolver()
        self.solver.settings.eps_abs = tol
        self.solver.settings.eps_rel = tol
        self.H = np.asfortranarray(H)
        self.G = np.asfortranarray(G)
        self.ready = False

    def solve(self, g, lo, hi, warm):  # noqa: D102
        lo = np.where(np.isfinite(lo), lo, -1e30)
        hi = np.where(np.isfinite(hi), hi, 1e30)
        if not self.ready:
            self.solver.setup(self.H, g, None, None, self.G, lo, hi)
            self.ready = True
        else:
            self.solver.update(c=g, h_l=lo, h_u=hi)
        status = self.solver.solve()
        ok = status == self._piqp.PIQP_SOLVED
        return (np.array(self.solver.result.x) if ok else None), f"piqp {status}", int(self.solver.result.info.iter)


class _Clarabel(Backend):
    def __init__(self, H: np.ndarray, G: np.ndarray, tol: float, hi_rows: np.ndarray, lo_rows: np.ndarray) -> None:
        import clarabel
        import scipy.sparse as sp

        self._clarabel = clarabel
        self.hi_rows, self.lo_rows = hi_rows, lo_rows
        Aineq = np.vstack([G[hi_rows], -G[lo_rows]])
        self.P = sp.csc_matrix(np.triu(H))
        self.A = sp.csc_matrix(Aineq)
        self.cones = [clarabel.NonnegativeConeT(Aineq.shape[0])]
        s = clarabel.DefaultSettings()
        s.verbose = False
        s.tol_gap_abs = s.tol_gap_rel = s.tol_feas = tol
        s.presolve_enable = False  # keeps the constraint rows fixed so data updates are allowed
        self.settings = s
        self.solver: Any = None  # a clarabel.DefaultSolver (untyped), made at the first solve

    def solve(self, g, lo, hi, warm):  # noqa: D102
        b = np.concatenate([hi[self.hi_rows], -lo[self.lo_rows]])
        if self.solver is None:
            self.solver = self._clarabel.DefaultSolver(self.P, g, self.A, b, self.cones, self.settings)
        else:
            self.solver.update(q=g, b=b)
        sol = self.solver.solve()
        ok = str(sol.status) in ("Solved", "AlmostSolved")
        return (np.asarray(sol.x) if ok else None), f"clarabel {sol.status}", int(sol.iterations)


def make_backend(solver: str, H: np.ndarray, G: np.ndarray, tol: float, c_lo: np.ndarray, c_hi: np.ndarray) -> Backend:
    """The back-end of ``solver`` for the QP data ``H``, ``G`` (``c_lo``/``c_hi``: which bounds are finite)."""
    if solver == "daqp":
        return _Daqp(H, G, tol)
    if solver == "osqp":
        return _Osqp(H, G, tol)
    if solver == "piqp":
        return _Piqp(H, G, tol)
    if solver == "clarabel":
        return _Clarabel(H, G, tol, np.flatnonzero(np.isfinite(c_hi)), np.flatnonzero(np.isfinite(c_lo)))
    raise ValueError(f"unknown QP solver {solver!r}")
