"""The 2WD cart model (models/unicycle/model.py): Jacobians, exact arcs, sensors against independent geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import netsim  # noqa: F401  (pins BLAS before numpy work)
from netsim.models.unicycle.model import (
    ALPHA, BETA, FRONT_OFFSET, GAMMA, SIDE_DERIVED, SIDE_PRINTED, WALL_FRONT, WALL_SIDE, arc, body_to_wheels,
    euler_step, jac_A, jac_B, measure, measure_jacobian, rotation, wheels_to_body,
)

POSES = [np.array([-0.3, -0.2, 0.0]), np.array([-0.15, -0.12, 1.3]), np.array([0.4, -1.1, -2.7])]


def _fd(fun, x, eps=1e-6):
    cols = []
    for i in range(len(x)):
        d = np.zeros(len(x))
        d[i] = eps
        cols.append((np.atleast_1d(fun(x + d)) - np.atleast_1d(fun(x - d))) / (2 * eps))
    return np.column_stack(cols)


@pytest.mark.parametrize("xi", POSES)
def test_state_jacobians_equal_finite_differences(xi):
    u = np.array([0.03, 0.5])
    # eq (12) and eq (13) against central differences of eq (10); 1e-9 is far above the FD error (~1e-12)
    assert np.allclose(jac_A(xi, u), _fd(lambda x: euler_step(x, u), xi), atol=1e-9)
    assert np.allclose(jac_B(xi), _fd(lambda v: euler_step(xi, v), u), atol=1e-9)


@pytest.mark.parametrize("xi", POSES)
@pytest.mark.parametrize("offset, wall", [(FRONT_OFFSET, WALL_FRONT), (SIDE_DERIVED, WALL_SIDE),
                                          (SIDE_PRINTED, WALL_SIDE), ((0.02, 0.05), (3.0, -4.0, 1.0))])
def test_measurement_jacobian_equals_finite_differences(xi, offset, wall):
    J = measure_jacobian(xi, offset, wall)
    assert np.allclose(J, _fd(lambda x: measure(x, offset, wall), xi), atol=1e-9)


def test_printed_eq17_is_the_jacobian_of_the_printed_offset():
    # eq (17) as printed: [0, -1, -alpha cos] and [-1, 0, beta sin + gamma cos]
    xi = np.array([-0.2, -0.3, 0.4])
    c, s = math.cos(0.4), math.sin(0.4)
    assert np.allclose(measure_jacobian(xi, FRONT_OFFSET, WALL_FRONT), [[0, -1, -ALPHA * c]])
    assert np.allclose(measure_jacobian(xi, SIDE_PRINTED, WALL_SIDE), [[-1, 0, BETA * s + GAMMA * c]])
    # the side sensor at -Y' (the report's text) flips the gamma term
    assert np.allclose(measure_jacobian(xi, SIDE_DERIVED, WALL_SIDE), [[-1, 0, BETA * s - GAMMA * c]])


@pytest.mark.parametrize("xi", POSES)
def test_sensors_against_independent_geometry(xi):
    # independent: body offset rotated by the 2D rotation matrix, distance by projecting onto the wall normal
    x, y, th = xi
    Rm = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    for off, wall in ((np.array([ALPHA, 0.0]), WALL_FRONT), (np.array([BETA, -GAMMA]), WALL_SIDE)):
        pos = np.array([x, y]) + Rm @ off
        p, q, r = wall
        nrm = np.array([p, q]) / np.hypot(p, q)
        foot = np.array([p, q]) * r / (p * p + q * q)  # a point of the wall
        expected = float(nrm @ (foot - pos))
        assert measure(xi, tuple(off), wall) == pytest.approx(expected, abs=1e-15)
    # eqs (8)-(9) with the side sensor at -Y': z1 = -(y + alpha sin), z2 = -(x + beta cos + gamma sin)
    assert measure(xi, FRONT_OFFSET, WALL_FRONT) == pytest.approx(-(y + ALPHA * math.sin(th)))
    assert measure(xi, SIDE_DERIVED, WALL_SIDE) == pytest.approx(-(x + BETA * math.cos(th) + GAMMA * math.sin(th)))
    # the printed eq (9)
    assert measure(xi, SIDE_PRINTED, WALL_SIDE) == pytest.approx(-(x + BETA * math.cos(th) - GAMMA * math.sin(th)))


def test_side_sensor_on_the_right_faces_the_right_wall():
    # heading +y (theta = pi/2) with the wall x = 0 on the right: the sensor at -Y' is gamma closer to it
    xi = np.array([-0.3, -0.5, math.pi / 2])
    assert measure(xi, SIDE_DERIVED, WALL_SIDE) == pytest.approx(0.3 - GAMMA)
    assert measure(xi, SIDE_PRINTED, WALL_SIDE) == pytest.approx(0.3 + GAMMA)


@pytest.mark.parametrize("v, w, dt", [(0.03, 0.0, 0.37), (0.02, math.pi / 4, 2.0), (-0.1, -3.0, 0.9),
                                      (0.05, 1e-9, 1.0)])
def test_exact_arc_against_fine_numerical_integration(v, w, dt):
    xi0 = np.array([-0.3, -0.2, 0.4])
    sol = solve_ivp(lambda t, s: [v * math.cos(s[2]), v * math.sin(s[2]), w], (0, dt), xi0, rtol=1e-12,
                    atol=1e-14, method="DOP853")
    assert np.allclose(arc(xi0, v, w, dt), sol.y[:, -1], atol=1e-11)


def test_arc_composes_and_differs_from_euler():
    xi0 = np.array([0.0, 0.0, 0.0])
    one = arc(xi0, 0.02, math.pi / 4, 2.0)
    many = xi0
    for _ in range(200):
        many = arc(many, 0.02, math.pi / 4, 0.01)
    assert np.allclose(one, many, atol=1e-14)
    # a quarter circle of radius R = v / w: ends at (R, R, pi/2)
    R = 0.02 / (math.pi / 4)
    assert np.allclose(one, [R, R, math.pi / 2], atol=1e-15)
    eul = xi0
    for _ in range(200):
        eul = euler_step(eul, np.array([0.02, math.pi / 4]), 0.01)
    assert np.abs(eul[:2] - one[:2]).max() > 1e-4  # Euler's error over the turn (0.2 mm): not the truth


def test_wheel_speed_relations_invert():
    wl, wr = body_to_wheels(0.03, 0.7)
    v, w = wheels_to_body(wl, wr)
    assert (v, w) == pytest.approx((0.03, 0.7), abs=1e-15)
    assert wheels_to_body(10.0, 10.0)[1] == 0.0


def test_rotation_eq24_maps_heading_direction_to_x_prime():
    th = 0.9
    e = np.array([math.cos(th), math.sin(th), 0.1])
    assert np.allclose(rotation(th) @ e, [1.0, 0.0, 0.1])
