"""Speed of the pendulum loop (issue 17, opt-in: ``pytest -m benchmark -s tests/models/test_pendulum_speed.py``).

A 10 s closed-loop run (Kalman + LQR, and Kalman + MPC) through netsim, against a plain numpy loop of the same
closed loop: the same nonlinear plant (scipy's RK45 at the same tolerances, restarted at every input change:
each 1 ms disturbance step and each 5 ms control update 0.5 ms after the sample), the same steady-state Kalman
filter and LQR/MPC objects. Prints wall time and control periods per second; the issue's target is a netsim
overhead of at most 5x for LQR (printed, not asserted: it depends on the machine's load).
"""

import time

import numpy as np
import pytest

import netsim
from netsim.models.pendulum import design as pd_
from netsim.models.pendulum import model as pm

pytestmark = pytest.mark.benchmark

DURATION = 10.0


def _numpy_loop(law_kind: str, seed: int = 1) -> tuple[float, float]:
    from scipy.integrate import solve_ivp

    from netsim.control import LQR, KalmanFilter, LinearMPC

    d = pd_.designs()
    lin = d.lin
    kf = KalmanFilter(lin.Ad, lin.Bd, lin.C, d.Qn, d.Rn, steady_state=True)
    if law_kind == "lqr":
        law = LQR(lin.Ad, lin.Bd, np.diag(pd_.Q_LQR), pd_.R_LQR, u_min=-pm.U_MAX, u_max=pm.U_MAX)
    else:
        law = LinearMPC(lin.Ad, lin.Bd, np.diag(pd_.Q_LQR), pd_.R_LQR, pd_.MPC_HORIZON, u_min=-pm.U_MAX,
                        u_max=pm.U_MAX)
    p = pm.PendulumParams()
    rng = np.random.default_rng(seed)
    x = np.array([0.0, 0.0, 0.2, 0.0])
    u_applied, u_next = 0.0, 0.0
    t, h_d = 0.0, pm.DISTURBANCE_HOLD
    n_steps = int(round(DURATION / h_d))
    dist = rng.normal(0.0, pm.DISTURBANCE_STD, n_steps)
    t0 = time.perf_counter()
    for i in range(n_steps):
        # at the sample (every 5th ms): measure, estimate, law; u reaches the plant 0.5 ms later
        segments = [(t, t + h_d)]
        if i % 5 == 0:
            y = pm.output(t, x, None, p) + rng.normal(0.0, pm.SENSOR_STD, 2)
            kf.correct(y)
            u_next = float(np.asarray(law.step(kf.x_hat, 0.0)).reshape(-1)[0])
            kf.predict([u_next])
            segments = [(t, t + 0.0005), (t + 0.0005, t + h_d)]
        for j, (a, b) in enumerate(segments):
            if i % 5 == 0 and j == 1:
                u_applied = u_next
            v = u_applied + dist[i]
            sol = solve_ivp(lambda tt, xx: pm.dynamics(tt, xx, [v], p), (a, b), x, rtol=1e-8, atol=1e-10)
            x = sol.y[:, -1]
        t += h_d
    return time.perf_counter() - t0, float(abs(x[2]))


@pytest.mark.parametrize("law", ["lqr", "mpc"])
def test_speed_of_a_10_s_loop(law):
    scen = "scenarios/pendulum_lqr.yaml" if law == "lqr" else "scenarios/pendulum_mpc.yaml"
    over = {"nodes.rip.tasks[0].params.estimator": {"type": "pendulum_kalman"}, "duration": "10 s"}
    t0 = time.perf_counter()
    res = netsim.run(scen, seed=1, overrides=over)
    wall = time.perf_counter() - t0
    wall_np, alpha_end = _numpy_loop(law)
    periods = DURATION / pm.TS
    print(f"\npendulum {law}: netsim {wall:.2f} s ({periods / wall:.0f} control periods/s), numpy loop "
          f"{wall_np:.2f} s ({periods / wall_np:.0f}/s): ratio {wall / wall_np:.2f} (target <= 5 for LQR)")
    assert res.status == "ok" and float(res.metrics["pendulum.stable"]) == 1.0
    assert alpha_end < 0.05  # the numpy loop balances too: the same closed loop
