"""The study's float EKF and tracking law (models/unicycle/ekf.py, design.TrackingLaw) against the toolbox's
ExtendedKalmanFilter and the matrix form of eq (27): the speed work must not change the filter."""

from __future__ import annotations

import math

import numpy as np
import pytest

import netsim  # noqa: F401  (pins BLAS before numpy work)
from netsim.models.unicycle.design import PHASES, TrackingLaw, Trajectory, cart_frame_error, make_ekf
from netsim.models.unicycle.ekf import CartEkf, matrix_to_sym, sym_to_matrix
from netsim.models.unicycle.model import (
    FRONT_OFFSET, P0, Q_REPORT, WALL_FRONT, WALL_SIDE, measure, measure_jacobian, side_offset,
)


@pytest.mark.parametrize("side", ["derived", "printed"])
def test_float_ekf_equals_the_toolbox_ekf_along_a_run(side):
    rng = np.random.default_rng(7)
    Q, R = 30 * Q_REPORT, np.array([1e-4, 4e-4])  # larger Q and smaller R than the report's: larger gains
    tool = make_ekf(Q, R, [-0.3, -0.2, 0.1], P0, 0.01, side)
    mine = CartEkf(Q, R, [-0.3, -0.2, 0.1], P0, 0.01, side)
    for k in range(400):
        for src, every in (("front", 2), ("side", 4)):
            if k % every == 0:
                z = float(rng.normal(-0.2, 0.05))
                tool.correct([z], src)
                mine.correct(z, src)
        # both the estimate and the covariance agree with the toolbox's Joseph form to rounding (1e-12 is
        # some 1e4 ulps of entries of order 1e-3 .. 1)
        assert np.allclose(mine.x, tool.x, rtol=0, atol=1e-12)
        assert np.allclose(mine.covariance(), tool.P, rtol=0, atol=1e-12)
        assert mine.det() == pytest.approx(np.linalg.det(tool.P), rel=1e-9)
        off = side_offset(side)
        for j, (src, o, wall) in enumerate((("front", FRONT_OFFSET, WALL_FRONT), ("side", off, WALL_SIDE))):
            zh, zsd = mine.predicted(src)
            H = measure_jacobian(tool.x, o, wall)
            assert zh == pytest.approx(measure(tool.x, o, wall), abs=1e-12)
            assert zsd == pytest.approx(math.sqrt(float((H @ tool.P @ H.T)[0, 0]) + R[j]), rel=1e-9)
        u = rng.normal([0.03, 0.3], [0.01, 0.5])
        tool.predict(u)
        mine.predict(float(u[0]), float(u[1]))


def test_sym_round_trip_and_non_diagonal_Q_refused():
    M = np.array([[1.0, 2.0, 3.0], [2.0, 4.0, 5.0], [3.0, 5.0, 6.0]])
    assert np.array_equal(sym_to_matrix(matrix_to_sym(M)), M)
    with pytest.raises(ValueError, match="diagonal"):
        CartEkf(Q=np.ones((3, 3)))


@pytest.mark.parametrize("law", ["feedforward", "lqr", "lqr_ff"])
def test_float_law_equals_the_matrix_form_of_eq27(law):
    traj = Trajectory(PHASES)
    ctl = TrackingLaw(traj, law)
    rng = np.random.default_rng(3)
    for k in range(0, traj.n + 1, 37):
        ref, u_ref = traj.at(k)
        xi = ref + rng.normal(0, [0.01, 0.01, 0.1])
        v, w = ctl.step(k, xi)
        if law == "feedforward":
            want = u_ref
        else:
            want = -ctl.gains[float(u_ref[0])] @ cart_frame_error(ref, xi) + (u_ref if law == "lqr_ff" else 0.0)
        assert np.allclose((v, w), want, rtol=0, atol=1e-12)
