"""Linear MPC: equals the LQR law where no constraint is active, never violates a constraint, agrees with an
independently built (uncondensed, sparse) QP, falls back to saturated LQR when infeasible."""

import importlib.util

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

import netsim.control.mpc as mpc_module
from netsim.control.lqr import LQR
from netsim.control.mpc import LinearMPC
from netsim.errors import ConfigError


def two_masses(h=0.05):
    """Two unit masses joined by a spring (k = 2) and damper (c = 0.2), force on the first; ZOH at h."""
    k, c = 2.0, 0.2
    Ac = np.array([[0, 1, 0, 0], [-k, -c, k, c], [0, 0, 0, 1], [k, c, -k, -c]], dtype=float)
    Bc = np.array([[0.0], [1.0], [0.0], [0.0]])
    M = sla.expm(np.block([[Ac, Bc], [np.zeros((1, 5))]]) * h)
    return M[:4, :4], M[:4, 4:]


A, B = two_masses()
Q = np.diag([1.0, 0.1, 10.0, 0.1])
R = np.array([[0.1]])
Cr = np.array([[0.0, 0.0, 1.0, 0.0]])
LIMITS = dict(
    u_min=-1.0, u_max=1.0, du_min=-0.2, du_max=0.2, x_min=[None, -0.6, None, -0.6], x_max=[None, 0.6, None, 0.6]
)
SOLVERS = [s for s in ("daqp", "clarabel", "piqp", "osqp") if importlib.util.find_spec(s) is not None]


@pytest.fixture
def force_solver(monkeypatch):
    """Make every step go to the QP solver (no unconstrained shortcut)."""
    monkeypatch.setattr(mpc_module, "_SHORTCUT_TOL", -np.inf)


@pytest.mark.parametrize("use_solver", [False, True])
def test_equals_the_lqr_law_where_no_constraint_is_active(use_solver, monkeypatch):
    if use_solver:
        monkeypatch.setattr(mpc_module, "_SHORTCUT_TOL", -np.inf)
    wide = dict(u_min=-1e3, u_max=1e3, x_min=[-1e3] * 4, x_max=[1e3] * 4)
    mpc = LinearMPC(A, B, Q, R, 20, Cr=Cr, **wide)
    lqr = LQR(A, B, Q, R, Cr=Cr)
    rng = np.random.default_rng(0)
    for _ in range(30):
        x = rng.normal(size=4)
        r = rng.normal()
        np.testing.assert_allclose(mpc.step(x, r), lqr.step(x, r), rtol=0, atol=1e-8)
    assert mpc.solver_calls == (30 if use_solver else 0)
    assert mpc.fallbacks == 0


def test_terminal_cost_is_the_lqr_riccati_solution_by_default():
    mpc = LinearMPC(A, B, Q, R, 5)
    np.testing.assert_allclose(mpc.P, sla.solve_discrete_are(A, B, Q, R), rtol=1e-9)


def reference_qp_u0(x0, u_prev, r, N=20):
    """MPC's first input from an uncondensed QP (states and inputs both variables, dynamics as equalities),
    built here independently and solved by clarabel at tight tolerance."""
    import clarabel

    n, m = 4, 1
    Pq = sla.solve_discrete_are(A, B, Q, R)
    M = np.block([[A - np.eye(n), B], [Cr, np.zeros((1, m))]])
    ss = np.linalg.solve(M, np.r_[np.zeros(n), r])
    xs, us = ss[:n], ss[n:]
    nz = N * n + N * m  # z = [x_1..x_N, u_0..u_{N-1}]
    iu = N * n
    Pm = sla.block_diag(*([Q] * (N - 1) + [Pq] + [R] * N))
    q = -Pm @ np.r_[np.tile(xs, N), np.tile(us, N)]
    # dynamics x_{k+1} - A x_k - B u_k = 0
    Aeq = np.zeros((N * n, nz))
    beq = np.zeros(N * n)
    for k in range(N):
        Aeq[k * n : (k + 1) * n, k * n : (k + 1) * n] = np.eye(n)
        Aeq[k * n : (k + 1) * n, iu + k * m : iu + (k + 1) * m] = -B
        if k == 0:
            beq[:n] = A @ x0
        else:
            Aeq[k * n : (k + 1) * n, (k - 1) * n : k * n] = -A
    rows, b = [], []
    for k in range(N):
        e = np.zeros(nz)
        e[iu + k] = 1.0
        rows += [e, -e]
        b += [1.0, 1.0]
        d = e.copy()
        if k > 0:
            d[iu + k - 1] = -1.0
        rows += [d, -d]
        b += [0.2 + (u_prev if k == 0 else 0.0), 0.2 - (u_prev if k == 0 else 0.0)]
        for i in (1, 3):
            s = np.zeros(nz)
            s[k * n + i] = 1.0
            rows += [s, -s]
            b += [0.6, 0.6]
    G = np.vstack([Aeq, np.array(rows)])
    h = np.r_[beq, b]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = 1e-11
    sol = clarabel.DefaultSolver(
        sp.csc_matrix(np.triu(Pm)), q, sp.csc_matrix(G), h,
        [clarabel.ZeroConeT(N * n), clarabel.NonnegativeConeT(len(rows))], settings,
    ).solve()  # fmt: skip
    if str(sol.status) != "Solved":
        return None
    return np.array(sol.x)[iu : iu + m]


@pytest.mark.parametrize("solver", SOLVERS)
def test_constrained_steps_agree_with_an_independent_qp_and_never_violate_a_constraint(solver):
    # osqp is a first-order method: 1e-9 makes it hit its iteration limit, 1e-6 is its practical tolerance
    mpc = LinearMPC(A, B, Q, R, 20, Cr=Cr, solver=solver, tol=1e-6 if solver == "osqp" else 1e-9, **LIMITS)
    # accuracy: daqp (active set) is exact to rounding; the interior-point solvers to about 1e-6; osqp (first
    # order) to about 1e-3 (measured, see the project notes)
    tol = {"daqp": 1e-8, "clarabel": 1e-5, "piqp": 1e-5, "osqp": 2e-2}[solver]
    x = np.zeros(4)
    u_prev = 0.0
    checked = 0
    for k in range(160):
        r = 1.0 if k < 80 else -0.5
        u = mpc.step(x, r)
        assert -1.0 - 1e-12 <= u[0] <= 1.0 + 1e-12
        assert abs(u[0] - u_prev) <= 0.2 + 1e-12
        if k % 8 == 0:
            ref = reference_qp_u0(x, u_prev, r)
            # osqp's inexact inputs can leave a state on its limit from which the exact problem is infeasible
            if ref is not None or solver != "osqp":
                np.testing.assert_allclose(u, ref, atol=tol)
                checked += 1
        x = A @ x + B @ u
        u_prev = u[0]
        # the model is exact here, so the predicted state constraints hold for the plant (to the solver's
        # feasibility tolerance: osqp's 1e-6 shows as violations of about 2e-7)
        xtol = 1e-5 if solver == "osqp" else 1e-8
        assert abs(x[1]) <= 0.6 + xtol and abs(x[3]) <= 0.6 + xtol
    assert mpc.solver_calls > 20  # constraints were active on many steps
    assert mpc.fallbacks == 0
    assert checked >= (15 if solver == "osqp" else 20)


def test_reference_is_reached_and_input_limit_active():
    mpc = LinearMPC(A, B, Q, R, 20, Cr=Cr, **LIMITS)
    x = np.zeros(4)
    us = []
    for _ in range(400):
        u = mpc.step(x, 1.0)
        us.append(u[0])
        x = A @ x + B @ u
    assert max(us) == pytest.approx(1.0)  # the input limit was active
    assert abs(x[2] - 1.0) < 1e-6


def test_infeasible_problem_falls_back_to_saturated_lqr_and_counts_it():
    mpc = LinearMPC(A, B, Q, R, 20, Cr=Cr, **LIMITS)
    # second mass already at 2 m/s: with |u| <= 1 no input brings |v2| under 0.6 in one sample
    x = np.array([0.0, 0.0, 0.0, 2.0])
    u = mpc.step(x, 0.0)
    assert mpc.fallbacks == 1
    assert "exitflag" in mpc.last_status
    lqr_u = np.clip(-mpc.K @ x, -0.2, 0.2)  # saturated LQR, rate limit from u_prev = 0 is the tighter one
    np.testing.assert_allclose(u, lqr_u, rtol=1e-12)
    assert mpc.metrics()["fallbacks"] == 1.0
    # the solver's workspace recovers: later steps from feasible states are optimal again
    x, u_prev = np.array([0.1, 0.2, 0.0, 0.1]), float(u[0])
    for _ in range(20):
        u = mpc.step(x, 1.0)
        np.testing.assert_allclose(u, reference_qp_u0(x, u_prev, 1.0), atol=1e-7)
        x, u_prev = A @ x + B @ u, float(u[0])
    assert mpc.fallbacks == 1


def test_solver_exception_falls_back(force_solver):
    mpc = LinearMPC(A, B, Q, R, 10, Cr=Cr, **LIMITS)

    class Broken:
        warm_start = False

        def solve(self, *a):
            raise RuntimeError("solver crashed")

    mpc._backend = Broken()
    u = mpc.step(np.zeros(4), 0.5)
    assert mpc.fallbacks == 1 and "solver crashed" in mpc.last_status
    assert -0.2 <= u[0] <= 0.2


def test_initial_state_violating_a_constraint_is_refused():
    with pytest.raises(ConfigError, match=r"x0: state 3 = 0.9 is above x_max\[3\] = 0.6"):
        LinearMPC(A, B, Q, R, 10, x0=[0, 0, 0, 0.9], **LIMITS)
    with pytest.raises(ConfigError, match="x0: the MPC problem is infeasible"):
        LinearMPC(A, B, Q, R, 10, x0=[0, 0.59, 0, 0], u0=[1.0], u_min=-1, u_max=1, du_min=-0.01, du_max=0.01,
                  x_min=[None, -0.6, None, None], x_max=[None, 0.6, None, None])  # fmt: skip


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        (dict(horizon=0), "horizon must be"),
        (dict(solver="cvxopt"), "solver must be one of"),
        (dict(u_min=2.0, u_max=1.0), "u_min"),
        (dict(du_min=0.1), "du_min must be <= 0"),
        (dict(x_min=[0.0, 0.0]), "x_min must have 4 entries"),
        (dict(P=-np.eye(4)), "P must be positive semidefinite"),
        (dict(R=0.0), "R must be positive definite"),
    ],
)
def test_bad_parameters_are_refused_naming_them(kw, match):
    args = dict(A=A, B=B, Q=Q, R=R, horizon=10)
    for k in list(kw):
        if k in args:
            args[k] = kw.pop(k)
    with pytest.raises(ConfigError, match=match):
        LinearMPC(args["A"], args["B"], args["Q"], args["R"], args["horizon"], **kw)


def test_solve_time_is_reported():
    mpc = LinearMPC(A, B, Q, R, 20, Cr=Cr, **LIMITS)
    for _ in range(5):
        mpc.step(np.zeros(4), 1.0)
    assert mpc.solver_calls >= 1 and mpc.last_iterations > 0  # the input limit is active from rest
    m = mpc.metrics()
    assert m["steps"] == 5.0
    assert m["solver_iterations"] >= mpc.last_iterations
    assert 0 < m["solve_time_mean_s"] <= m["solve_time_max_s"] < 1.0
