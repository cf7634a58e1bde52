"""Linear MPC on a condensed QP built once at construction.

Model ``x[k+1] = A x[k] + B u[k]``; at each sample the law solves, over the horizon ``N``::

    minimise   sum_{k=0}^{N-1} (x_k - x_s)' Q (x_k - x_s) + (u_k - u_s)' R (u_k - u_s) + (x_N - x_s)' P (x_N - x_s)
    subject to u_min <= u_k <= u_max,  du_min <= u_k - u_{k-1} <= du_max (u_{-1}: the input applied last),
               x_min <= x_k <= x_max   for k = 1 .. N,     x_0 = x_hat,

and applies ``u_0``. ``Q`` is the state weight plus ``C' Qy C`` when an output weight ``Qy`` on ``y = C x`` is
given. ``(x_s, u_s)`` is the steady state of the reference (as in :mod:`netsim.control.lqr`:
an output reference through ``Cr``, or a state reference ``x_ref`` / ``[x_ref, u_ref]``). The terminal weight
``P`` defaults to the LQR Riccati solution, so without active constraints ``u_0`` is exactly the LQR law
``u_s - K (x_hat - x_s)`` (dynamic programming).

*Condensing.* With ``U = [u_0; ...; u_{N-1}]`` the predicted states are ``X = Phi x_0 + Gamma U``, the cost
is ``1/2 U' H U + g' U`` with a constant ``H`` and ``g`` linear in ``(x_0, x_s, u_s)``, and the constraints are
``l <= G U <= u`` with a constant ``G`` and bounds affine in ``(x_0, u_{-1})``. All matrices are formed once
here; a step forms ``g``, ``l``, ``u`` by a few matrix-vector products.

*Solving.* A step first forms the unconstrained minimiser ``U* = -H^-1 g`` (a pre-factored matrix product);
when it satisfies every constraint (to 1e-9, absolute) it is the QP's solution and no solver is called. Otherwise the
QP goes to the solver (``daqp`` by default, chosen by measurement: see :mod:`netsim.control.qp_backends`;
``clarabel``, ``osqp`` and ``piqp`` are accepted when installed), warm-started where the solver supports it
(daqp's workspace starts from the previous working set; osqp from the previous solution shifted by one sample).

*Failure.* When the QP is infeasible (e.g. the estimate already violates a state constraint that cannot be
recovered in one sample) or the solver fails, the law applies the saturated LQR law
``clip(u_s - K (x_hat - x_s))`` (clipped to the input box and the rate limits), counts it in
:attr:`fallbacks` and records the solver status in :attr:`last_status`. The applied input is always clipped
to the input and rate limits. :attr:`last_solve_time_s` is the wall time of the last step's optimisation
(shortcut check and solver), for charging as execution time.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from netsim.control.design_checks import as_matrix, as_vector, check_weight
from netsim.control.interface import LawBase
from netsim.control.lqr import _limits, _model, dlqr_gain, output_weighted, reference_gains
from netsim.control.qp_backends import Backend, make_backend
from netsim.errors import ConfigError, SimulationError
from netsim.lazy_import import lazy_module

sla = lazy_module("scipy.linalg")  # imported when an MPC is built, not when a scenario is checked

__all__ = ["LinearMPC", "SOLVERS"]

SOLVERS = ("daqp", "clarabel", "osqp", "piqp")
_SHORTCUT_TOL = 1e-9


class LinearMPC(LawBase):
    """Linear MPC with box, rate and state constraints (see the module docstring).

    Parameters
    ----------
    A, B
        Discrete model (``n x n``, ``n x m``).
    Q, R
        Stage weights (``Q`` positive semidefinite, ``R`` positive definite; scalar or diagonal accepted).
        ``Q`` may be ``None`` when ``Qy`` is given.
    horizon
        Prediction horizon ``N`` (samples, >= 1).
    P
        Terminal weight; default the LQR Riccati solution of ``(A, B, Q, R)``.
    u_min, u_max, du_min, du_max
        Input and input-rate limits per sample (one number or one per input; ``None``: none).
    x_min, x_max
        State limits (``n`` numbers, ``±inf`` or ``None`` for an unconstrained state; ``None``: none).
    Cr
        Reference output matrix; ``None``: state reference (as in :class:`~netsim.control.lqr.StateFeedback`).
    solver
        ``"daqp"`` (default), ``"clarabel"``, ``"osqp"`` or ``"piqp"``.
    tol
        Solver tolerance.
    x0
        Initial state, when known at construction: checked against the state limits and for feasibility.
    u0
        Input applied before the first sample (reference of the first rate limit; default zeros).
    Qy, C
        Optional output weight (``p x p``, positive semidefinite) on ``y = C x``: the stage weight is
        ``Q + C' Qy C`` (:func:`~netsim.control.lqr.output_weighted`), and so is the default terminal weight's.

    Attributes
    ----------
    K, P
        The LQR gain of the fallback law and the terminal weight.
    fallbacks, solver_calls, steps
        Counters: saturated-LQR fallbacks (infeasible QP or solver failure), QPs sent to the solver, steps.
    last_status, last_solve_time_s, total_solve_time_s, max_solve_time_s
        Status and wall time of the optimisation of the last step, and their totals.
    last_iterations, total_iterations
        Solver iterations of the last step (0 when no solver ran) and their total: the input of a
        per-iteration execution-time model.
    """

    reports_solver = True

    def __init__(
        self,
        A: Any,
        B: Any,
        Q: Any,
        R: Any,
        horizon: int,
        *,
        P: Any = None,
        u_min: Any = None,
        u_max: Any = None,
        du_min: Any = None,
        du_max: Any = None,
        x_min: Any = None,
        x_max: Any = None,
        Cr: Any = None,
        solver: str = "daqp",
        tol: float = 1e-9,
        x0: Any = None,
        u0: Any = None,
        Qy: Any = None,
        C: Any = None,
    ) -> None:
        A, B = _model(A, B)
        n, m = B.shape
        self.A, self.B, self.n, self.m = A, B, n, m
        if isinstance(horizon, bool) or int(horizon) != horizon or horizon < 1:
            raise ConfigError(f"horizon must be a whole number of samples >= 1, got {horizon!r}")
        N = self.N = int(horizon)
        if solver not in SOLVERS:
            raise ConfigError(f"solver must be one of {', '.join(SOLVERS)}, got {solver!r}")
        self.Q = output_weighted(Q, Qy, C, n)
        self.R = check_weight("R", R, m, definite=True)
        self.K, P_lqr = dlqr_gain(A, B, self.Q, self.R)
        self.P = P_lqr if P is None else check_weight("P", P, n, definite=False)
        self.u_min, self.u_max = _limits("u_min", u_min, m), _limits("u_max", u_max, m)
        self.du_min, self.du_max = _limits("du_min", du_min, m), _limits("du_max", du_max, m)
        for lo_name, lo, hi_name, hi in (("u_min", self.u_min, "u_max", self.u_max),
                                         ("du_min", self.du_min, "du_max", self.du_max)):  # fmt: skip
            if lo is not None and hi is not None and np.any(lo > hi):
                raise ConfigError(f"{lo_name} ({lo}) must not exceed {hi_name} ({hi})")
        if self.du_min is not None and np.any(self.du_min > 0) or self.du_max is not None and np.any(self.du_max < 0):
            raise ConfigError("du_min must be <= 0 and du_max >= 0 (holding the input must be allowed)")
        self.x_min = None if x_min is None else self._state_limit("x_min", x_min, -np.inf)
        self.x_max = None if x_max is None else self._state_limit("x_max", x_max, np.inf)
        if self.x_min is not None and self.x_max is not None and np.any(self.x_min > self.x_max):
            raise ConfigError(f"x_min ({self.x_min}) must not exceed x_max ({self.x_max})")
        self.Cr = None if Cr is None else as_matrix("Cr", Cr, (None, n))
        if self.Cr is not None:
            self._Nx, self._Nu = reference_gains(A, B, self.Cr)
        else:
            self._Bpinv = np.linalg.pinv(B)
            self._AmI = A - np.eye(n)

        # --- condensed prediction X = Phi x0 + Gamma U (X = [x_1; ...; x_N]) ---
        Phi = np.zeros((N * n, n))
        Gamma = np.zeros((N * n, N * m))
        Ak = np.eye(n)
        powers = []
        for k in range(N):
            powers.append(Ak)  # A^k
            Ak = A @ Ak
            Phi[k * n : (k + 1) * n] = Ak
        for k in range(N):
            for j in range(k + 1):
                Gamma[k * n : (k + 1) * n, j * m : (j + 1) * m] = powers[k - j] @ B
        Qbar = sla.block_diag(*([self.Q] * (N - 1) + [self.P]))
        Rbar = sla.block_diag(*([self.R] * N))
        GtQ = Gamma.T @ Qbar
        H = 2.0 * (GtQ @ Gamma + Rbar)
        self.H = 0.5 * (H + H.T)
        Ixs = np.tile(np.eye(n), (N, 1))
        Ius = np.tile(np.eye(m), (N, 1))
        # g = Gx x0 + Gxs x_s + Gus u_s;  the x_0 stage cost is constant
        self._Gx = 2.0 * GtQ @ Phi
        self._Gxs = -2.0 * GtQ @ Ixs
        self._Gus = -2.0 * Rbar @ Ius
        self._Gall = np.hstack([self._Gx, self._Gxs, self._Gus])  # g = Gall [x0; x_s; u_s]
        try:
            cho = sla.cho_factor(self.H)
        except np.linalg.LinAlgError as exc:
            raise ConfigError("R: the condensed Hessian is not positive definite; make R positive definite") from exc
        # unconstrained minimiser U* = Mall [x0; x_s; u_s]
        self._Mall = -sla.cho_solve(cho, self._Gall)

        # --- constraints lo <= G U <= hi, lo/hi = c + Lx x0 + Lu u_prev ---
        rows_G, rows_lo, rows_hi, rows_Lx, rows_Lu = [], [], [], [], []
        NM = N * m

        def add(Gb, lo, hi, Lx, Lu):
            rows_G.append(Gb)
            rows_lo.append(lo)
            rows_hi.append(hi)
            rows_Lx.append(Lx)
            rows_Lu.append(Lu)

        if self.u_min is not None or self.u_max is not None:
            lo = np.tile(self.u_min if self.u_min is not None else np.full(m, -np.inf), N)
            hi = np.tile(self.u_max if self.u_max is not None else np.full(m, np.inf), N)
            add(np.eye(NM), lo, hi, np.zeros((NM, n)), np.zeros((NM, m)))
        if self.du_min is not None or self.du_max is not None:
            D = np.eye(NM) - np.eye(NM, k=-m)
            lo = np.tile(self.du_min if self.du_min is not None else np.full(m, -np.inf), N)
            hi = np.tile(self.du_max if self.du_max is not None else np.full(m, np.inf), N)
            Lu = np.zeros((NM, m))
            Lu[:m] = np.eye(m)
            add(D, lo, hi, np.zeros((NM, n)), Lu)
        if self.x_min is not None or self.x_max is not None:
            xlo = self.x_min if self.x_min is not None else np.full(n, -np.inf)
            xhi = self.x_max if self.x_max is not None else np.full(n, np.inf)
            sel = np.flatnonzero(np.tile(np.isfinite(xlo) | np.isfinite(xhi), N))
            add(Gamma[sel], np.tile(xlo, N)[sel], np.tile(xhi, N)[sel], -Phi[sel], np.zeros((sel.size, m)))
        if rows_G:
            self._G = np.vstack(rows_G)
            self._c_lo, self._c_hi = np.concatenate(rows_lo), np.concatenate(rows_hi)
            self._Lx, self._Lu = np.vstack(rows_Lx), np.vstack(rows_Lu)
        else:
            self._G = np.zeros((0, NM))
            self._c_lo = self._c_hi = np.zeros(0)
            self._Lx, self._Lu = np.zeros((0, n)), np.zeros((0, m))
        self._L = np.hstack([self._Lx, self._Lu])  # bound shift = L [x0; u_prev]
        self._shifted = bool(np.any(self._L))
        self.solver = solver
        self.tol = float(tol)
        self._backend: Backend | None = None  # created at the first constrained step (imports the solver then)
        self.u0 = np.zeros(m) if u0 is None else as_vector("u0", u0, m)
        self._check_solver_available()
        if x0 is not None:
            self._check_initial_state(as_vector("x0", x0, n))
        self.reset()

    # --- construction helpers --------------------------------------------------------------------------
    def _state_limit(self, name: str, value: Any, default: float) -> np.ndarray:
        v = np.array([default if e is None else e for e in np.atleast_1d(np.asarray(value, dtype=object))], dtype=float)
        if v.size == 1 and self.n > 1:
            v = np.full(self.n, float(v[0]))
        if v.size != self.n:
            raise ConfigError(
                f"{name} must have {self.n} entries (one per state; use null or inf for none), got {v.size}"
            )
        if np.any(np.isnan(v)):
            raise ConfigError(f"{name} contains NaN")
        return v

    def _check_solver_available(self) -> None:
        import importlib.util

        if importlib.util.find_spec(self.solver) is None:
            raise ConfigError(
                f"solver {self.solver!r} is not installed: pip install {self.solver}, or use solver='daqp'"
            )

    def _check_initial_state(self, x0: np.ndarray) -> None:
        for i in range(self.n):
            if self.x_min is not None and x0[i] < self.x_min[i]:
                raise ConfigError(f"x0: state {i} = {x0[i]:.6g} is below x_min[{i}] = {self.x_min[i]:.6g}")
            if self.x_max is not None and x0[i] > self.x_max[i]:
                raise ConfigError(f"x0: state {i} = {x0[i]:.6g} is above x_max[{i}] = {self.x_max[i]:.6g}")
        if self._G.shape[0]:
            lo, hi = self._bounds(x0, self.u0)
            backend = self._make_backend()
            U, status, _ = backend.solve(self._Gx @ x0, lo, hi, None)
            if U is None:
                raise ConfigError(
                    f"x0: the MPC problem is infeasible from the initial state {x0.tolist()} ({status}); relax "
                    "x_min/x_max or the input limits, or lengthen the horizon"
                )

    def _make_backend(self) -> Backend:
        return make_backend(self.solver, self.H, self._G, self.tol, self._c_lo, self._c_hi)

    # --- runtime ----------------------------------------------------------------------------------------
    def reset(self) -> None:
        """Forget the previous solution and input; zero the counters."""
        self.u_prev = self.u0.copy()
        self._U_prev: np.ndarray | None = None
        self.fallbacks = 0
        self.solver_calls = 0
        self.steps = 0
        self.last_status = "not run"
        self.last_iterations = 0
        self.total_iterations = 0
        self.last_solve_time_s = 0.0
        self.total_solve_time_s = 0.0
        self.max_solve_time_s = 0.0

    def _bounds(self, x0: np.ndarray, u_prev: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = self._c_lo, self._c_hi
        if self._shifted:
            shift = self._L @ np.concatenate((x0, u_prev))
            lo, hi = lo + shift, hi + shift
        return lo, hi

    def _target(self, r: Any) -> tuple[np.ndarray, np.ndarray]:
        r = np.asarray(r, dtype=float).reshape(-1)
        n, m = self.n, self.m
        if self.Cr is not None:
            q = self.Cr.shape[0]
            if r.shape[0] == 1 and q > 1:
                r = np.full(q, r[0])
            elif r.shape[0] != q:
                raise SimulationError(f"MPC: the reference has {r.shape[0]} entries, Cr has {q} rows")
            return self._Nx @ r, self._Nu @ r
        if r.shape[0] == 1 and n > 1:
            r = np.full(n, r[0])  # one number: the same reference for every state (0: regulation)
        if r.shape[0] == n:
            return r, -self._Bpinv @ (self._AmI @ r)
        if r.shape[0] == n + m:
            return r[:n], r[n:]
        raise SimulationError(
            f"MPC: a state reference has {n} entries (x_ref) or {n + m} ([x_ref, u_ref]), got {r.shape[0]}"
        )

    def _clip(self, u: np.ndarray) -> np.ndarray:
        if self.du_min is not None:
            u = np.maximum(u, self.u_prev + self.du_min)
        if self.du_max is not None:
            u = np.minimum(u, self.u_prev + self.du_max)
        if self.u_min is not None:
            u = np.maximum(u, self.u_min)
        if self.u_max is not None:
            u = np.minimum(u, self.u_max)
        return u

    def step(self, x_hat: Any, r: Any) -> np.ndarray:
        """Solve the MPC problem from ``x_hat`` towards the reference ``r``; return ``u_0``."""
        t0 = time.perf_counter()
        x0 = np.asarray(x_hat, dtype=float).reshape(-1)
        if x0.shape[0] != self.n:
            raise SimulationError(f"MPC: x_hat has {x0.shape[0]} entries, the model has {self.n} states")
        xs, us = self._target(r)
        m = self.m
        self.last_iterations = 0
        z = np.concatenate((x0, xs, us))
        U = self._Mall @ z
        self.steps += 1
        if self._G.shape[0]:
            lo, hi = self._bounds(x0, self.u_prev)
            GU = self._G @ U
            if (GU <= hi + _SHORTCUT_TOL).all() and (GU >= lo - _SHORTCUT_TOL).all():
                self.last_status = "unconstrained optimum feasible"
            else:
                if self._backend is None:
                    self._backend = self._make_backend()
                g = self._Gall @ z
                warm = None
                if self._backend.warm_start and self._U_prev is not None:
                    warm = np.concatenate([self._U_prev[m:], self._U_prev[-m:]])
                self.solver_calls += 1
                try:
                    Usol, status, self.last_iterations = self._backend.solve(g, lo, hi, warm)
                except Exception as exc:  # a solver crash must not stop the run: fall back, count, report
                    Usol, status = None, f"{self.solver} raised {type(exc).__name__}: {exc}"
                    self.last_iterations = 0
                self.last_status = status
                if Usol is None or not np.all(np.isfinite(Usol)):
                    self.fallbacks += 1
                    U = None
                else:
                    U = Usol
        else:
            self.last_status = "unconstrained"
        if U is None:
            u = self._clip(us - self.K @ (x0 - xs))
            self._U_prev = None
        else:
            u = self._clip(U[:m])
            self._U_prev = U
        self.u_prev = u
        dt = time.perf_counter() - t0
        self.last_solve_time_s = dt
        self.total_iterations += self.last_iterations
        self.total_solve_time_s += dt
        if dt > self.max_solve_time_s:
            self.max_solve_time_s = dt
        return u

    def metrics(self) -> dict[str, float]:
        """Counters and solve times for a run's metrics (``mpc.*`` names without the task prefix)."""
        return {
            "steps": float(self.steps),
            "solver_calls": float(self.solver_calls),
            "fallbacks": float(self.fallbacks),
            "solve_time_mean_s": self.total_solve_time_s / self.steps if self.steps else 0.0,
            "solve_time_max_s": self.max_solve_time_s,
            "solver_iterations": float(self.total_iterations),
        }
