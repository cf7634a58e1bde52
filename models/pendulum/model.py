"""The rotary inverted (Furuta) pendulum of seed 002: nonlinear Lagrange dynamics with the DC motor, and the
linearisation about the upright discretised by zero-order hold.

State ``x = [theta, theta_dot, alpha, alpha_dot]`` (arm angle, arm rate, pendulum angle from upright, pendulum
rate; rad and rad/s), input the motor voltage ``u`` (V), outputs ``y = [theta, alpha]`` (``C`` as in the slides).

Parameters (:class:`PendulumParams`)
------------------------------------
The slides give none. We use the published nominal values of the Quanser QUBE-Servo 2 with its rotary pendulum
module, as printed in Quanser's parameter script ``qube2_rotpen_param.m`` of the QUBE-Servo 2 courseware (the
copy read: github.com/weilunwc/rotary_pendulum, file ``qube2_rotpen_param.m``):

========  ==============================  =========================================
``Rm``    8.4 ohm                         motor terminal resistance
``km``    0.042 V s/rad (= kt, N m/A)      back-EMF and torque constant
``mr``    0.095 kg, ``Lr`` 0.085 m         rotary arm; ``Jr = mr Lr^2 / 12`` about the motor axis
``Dr``    0.0015 N m s/rad                 arm viscous damping (Quanser: "tuned heuristically")
``mp``    0.024 kg, ``Lp`` 0.129 m         pendulum link; ``Jp = mp Lp^2 / 12`` about its centre
``Dp``    0.0005 N m s/rad                 pendulum viscous damping (same script)
``g``     9.81 m/s^2
========  ==============================  =========================================

The pendulum is a uniform rod pivoted at one end (centre of mass at ``l = Lp / 2``), its pivot at distance ``Lr``
from the motor axis (Quanser's modelling convention). Motor inductance (1.16 mH, 0.14 ms electrical time
constant) is neglected as in Quanser's model: the torque is ``tau = km (u - km theta_dot) / Rm``.

Equations (derived here with the Lagrangian; ``alpha`` > 0 tips the pendulum towards positive arm motion)::

    T = 1/2 Jr th'^2 + 1/2 mp Lr^2 th'^2 + mp l Lr cos(a) th' a' + 1/2 J0 (a'^2 + sin(a)^2 th'^2)
    V = mp g l cos(a),                       J0 = Jp + mp l^2 (pendulum about its pivot)

    [Jr + mp Lr^2 + J0 sin^2 a,  mp l Lr cos a] [th'']   [tau - Dr th' - 2 J0 sin a cos a th' a' + mp l Lr sin a a'^2]
    [mp l Lr cos a,              J0           ] [a'' ] = [-Dp a' + J0 sin a cos a th'^2 + mp g l sin a             ]

The energy ``T + V`` is conserved without damping and input (``tests/models/test_pendulum_model.py``).

Other choices of the study (the same in every scenario; stated again in the YAML comments)
------------------------------------------------------------------------------------------
* ``TS = 5 ms`` (200 Hz): the slides' poles 0.55-0.82 are then observer time constants of 8-25 ms, faster
  than the LQR loop's slowest modes, as the slides ask ("faster than the closed-loop control poles").
* Sensors: the QUBE-Servo 2 encoders, 2048 counts per revolution in quadrature on both angles; quantisation
  step ``q = 2 pi / 2048`` rad, modelled as white noise of variance ``q^2 / 12`` (std 0.89 mrad) per angle
  (``SENSOR_STD``), or as the quantisation itself in the quantised scenario.
* Input disturbance: white voltage noise held over 1 ms, std ``DISTURBANCE_STD = 0.05 V`` (motor cogging,
  PWM ripple, friction the model lacks); Qn of the Kalman filter is that noise mapped through the discrete
  model (:func:`process_noise_cov`).
* Weights: LQR ``Q = diag(5, 0, 20, 0)``, ``R = 1`` (angles in rad, voltage in V), the MPC the same with
  horizon 20 (100 ms) and ``|u| <= 3 V`` (also the DAC's limit, so the LQR is clipped there); the initial tilt
  of 0.2 rad, with every estimator starting from zero, makes the loop ask for more than 3 V in the first
  samples, so the limit is active in the transient.
* Estimators start from a zero estimate (the slides' firmware: the pendulum is held near upright when the
  program starts); the finite differences start from the first measurement.
* Execution time of the control task 0.5 ms (u written 0.5 ms after the sample; the design ignores it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import Field

from netsim.registry import register
from netsim.units import StrictModel

__all__ = [
    "PendulumParams",
    "TS",
    "SENSOR_STD",
    "ENCODER_STEP",
    "DISTURBANCE_STD",
    "DISTURBANCE_HOLD",
    "U_MAX",
    "C_MEAS",
    "dynamics",
    "energy",
    "linearise",
    "discretise",
    "Linear",
    "process_noise_cov",
    "observability_rank",
    "furuta_pendulum",
]

#: Controller period of the study (s).
TS = 0.005
#: Encoder step of the QUBE-Servo 2 (2048 counts per revolution in quadrature), rad.
ENCODER_STEP = 2.0 * math.pi / 2048.0
#: Std of an angle measurement when the quantisation is modelled as white noise: ``q / sqrt(12)``.
SENSOR_STD = ENCODER_STEP / math.sqrt(12.0)
#: Std of the white input-voltage disturbance (V) and how long each value is held (s).
DISTURBANCE_STD = 0.05
DISTURBANCE_HOLD = 0.001
#: The MPC input limit (V).
U_MAX = 3.0
#: Measured outputs: theta and alpha.
C_MEAS = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])


class PendulumParams(StrictModel):
    """Physical parameters of the rotary pendulum (defaults: Quanser QUBE-Servo 2, see the module docstring)."""

    Rm: float = Field(8.4, gt=0, description="motor resistance (ohm)")
    km: float = Field(0.042, ge=0, description="back-EMF = torque constant (V s/rad)")
    mr: float = Field(0.095, gt=0, description="rotary arm mass (kg)")
    Lr: float = Field(0.085, gt=0, description="rotary arm length; pendulum pivot radius (m)")
    Dr: float = Field(0.0015, ge=0, description="arm viscous damping (N m s/rad)")
    mp: float = Field(0.024, gt=0, description="pendulum mass (kg)")
    Lp: float = Field(0.129, gt=0, description="pendulum length (m)")
    Dp: float = Field(0.0005, ge=0, description="pendulum viscous damping (N m s/rad)")
    g: float = Field(9.81, ge=0, description="gravity (m/s^2)")
    disturbance_std: float = Field(DISTURBANCE_STD, ge=0, description="std of the white input-voltage disturbance (V)")
    disturbance_hold: float = Field(DISTURBANCE_HOLD, gt=0, description="hold time of each disturbance value (s)")

    @property
    def Jr(self) -> float:
        """Arm inertia about the motor axis, ``mr Lr^2 / 12`` (Quanser)."""
        return self.mr * self.Lr**2 / 12.0

    @property
    def l(self) -> float:  # noqa: E743 - the textbook name of the pendulum's centre-of-mass distance
        """Pendulum centre-of-mass distance from its pivot, ``Lp / 2``."""
        return self.Lp / 2.0

    @property
    def J0(self) -> float:
        """Pendulum inertia about its pivot, ``mp Lp^2 / 12 + mp l^2 = mp Lp^2 / 3``."""
        return self.mp * self.Lp**2 / 12.0 + self.mp * self.l**2


def _gufunc_solve1() -> Any:
    """The gufunc behind ``np.linalg.solve`` for one right-hand side (the same LAPACK dgesv call, without the
    ~5 us of the public function's checks), or None on a numpy without it (then the public function is used)."""
    try:
        from numpy.linalg import _umath_linalg
    except ImportError:  # pragma: no cover - the module is private to numpy
        return None
    return getattr(_umath_linalg, "solve1", None)


_solve1: Any = _gufunc_solve1()


class _Rhs:
    """``dx/dt`` of the pendulum with the parameter arithmetic done once (plain floats, no pydantic per call).

    Every product and sum is evaluated in the order :func:`dynamics` wrote it before (Python's ``a * b * c`` is
    ``(a * b) * c``, so only whole left prefixes are folded into constants) and the 2x2 system goes to the same
    LAPACK routine as ``np.linalg.solve``: the result is bit for bit that of the per-call parameter lookups
    (the golden traces ``pendulum_*`` guard it).
    """

    __slots__ = ("p", "km", "Rm", "Dr", "neg_Dp", "J0", "two_J0", "I0", "mlLr", "mlg", "_M", "_m", "_b")

    def __init__(self, p: PendulumParams) -> None:
        self.p = p
        J0, ml = p.J0, p.mp * p.l
        self.km, self.Rm, self.Dr, self.neg_Dp = p.km, p.Rm, p.Dr, -p.Dp
        self.J0, self.two_J0 = J0, 2.0 * J0
        self.I0 = p.Jr + p.mp * p.Lr**2  # arm inertia about the motor axis with the pendulum's mass at the pivot
        self.mlLr, self.mlg = ml * p.Lr, ml * p.g
        # the solve's inputs, refilled per call (the gufunc copies them into its own LAPACK buffers)
        self._M = np.empty((2, 2))
        self._m, self._b = self._M.reshape(-1), np.empty(2)

    def __call__(self, t: float, x: Any, u: Any, params: PendulumParams | None = None) -> np.ndarray:
        """``dx/dt`` at ``(t, x, u)``; ``params`` other than the ones this was built from go to :func:`dynamics`."""
        if params is not None and params is not self.p:
            return dynamics(t, x, u, params)
        if type(x) is np.ndarray and x.shape == (4,) and x.dtype == np.float64:
            _, th_d, a, a_d = x.tolist()
        else:
            xa = np.asarray(x, dtype=float)
            th_d, a, a_d = float(xa[1]), float(xa[2]), float(xa[3])
        if type(u) is np.ndarray and u.ndim == 1 and u.dtype == np.float64 and u.shape[0]:
            v = float(u[0])
        else:
            v = float(np.asarray(u, dtype=float).reshape(-1)[0]) if np.size(u) else 0.0
        km = self.km
        tau = km * (v - km * th_d) / self.Rm
        s, c = math.sin(a), math.cos(a)
        J0, mlLr = self.J0, self.mlLr
        M, m, rhs = self._M, self._m, self._b
        m[0] = self.I0 + J0 * s * s
        m[1] = m[2] = mlLr * c
        m[3] = J0
        rhs[0] = tau - self.Dr * th_d - self.two_J0 * s * c * th_d * a_d + mlLr * s * a_d * a_d
        rhs[1] = self.neg_Dp * a_d + J0 * s * c * th_d * th_d + self.mlg * s
        if _solve1 is None:
            acc0, acc1 = np.linalg.solve(M, rhs).tolist()
        else:
            acc0, acc1 = _solve1(M, rhs, signature="dd->d").tolist()
            if not (math.isfinite(acc0) and math.isfinite(acc1)):  # np.linalg.solve's errors and warnings
                acc0, acc1 = np.linalg.solve(M, rhs).tolist()
        return np.array([th_d, acc0, a_d, acc1])


def dynamics(t: float, x: Any, u: Any, p: PendulumParams) -> np.ndarray:
    """``dx/dt`` of the nonlinear pendulum with motor (``u``: voltage, first entry)."""
    return _Rhs(p)(t, x, u)


def output(t: float, x: Any, u: Any, p: PendulumParams) -> np.ndarray:
    """``y = [theta, alpha]``."""
    return np.array([float(x[0]), float(x[2])])


def energy(x: Any, p: PendulumParams) -> float:
    """Mechanical energy ``T + V`` (J), zero potential at the pivot height."""
    th_d, a, a_d = float(x[1]), float(x[2]), float(x[3])
    s, c = math.sin(a), math.cos(a)
    T = (0.5 * (p.Jr + p.mp * p.Lr**2) * th_d**2 + p.mp * p.l * p.Lr * c * th_d * a_d
         + 0.5 * p.J0 * (a_d**2 + s * s * th_d**2))
    return T + p.mp * p.g * p.l * c


def linearise(p: PendulumParams) -> tuple[np.ndarray, np.ndarray]:
    """Continuous ``(A, B)`` of the pendulum linearised about the upright ``x = 0, u = 0`` (analytic)."""
    ml = p.mp * p.l
    M0 = np.array([[p.Jr + p.mp * p.Lr**2, ml * p.Lr], [ml * p.Lr, p.J0]])
    Minv = np.linalg.inv(M0)
    # generalised forces, linear part: [tau - Dr th', -Dp a' + m g l a], tau = km/Rm u - km^2/Rm th'
    Kx = np.array([[0.0, -(p.Dr + p.km**2 / p.Rm), 0.0, 0.0], [0.0, 0.0, ml * p.g, -p.Dp]])
    Ku = np.array([[p.km / p.Rm], [0.0]])
    acc_x, acc_u = Minv @ Kx, Minv @ Ku
    A = np.zeros((4, 4))
    A[0, 1] = A[2, 3] = 1.0
    A[1], A[3] = acc_x[0], acc_x[1]
    B = np.zeros((4, 1))
    B[1, 0], B[3, 0] = acc_u[0, 0], acc_u[1, 0]
    return A, B


@dataclass(frozen=True)
class Linear:
    """The discrete linear model at period ``h``: ``x[k+1] = Ad x[k] + Bd u[k]``, ``y = C x``, with ``(A, B)``."""

    A: np.ndarray
    B: np.ndarray
    Ad: np.ndarray
    Bd: np.ndarray
    C: np.ndarray
    h: float


def discretise(p: PendulumParams | None = None, h: float = TS) -> Linear:
    """Zero-order-hold discretisation of :func:`linearise` at ``h`` (matrix exponential of the block matrix)."""
    from scipy.linalg import expm

    p = PendulumParams() if p is None else p
    A, B = linearise(p)
    blk = np.zeros((5, 5))
    blk[:4, :4], blk[:4, 4:] = A, B
    E = expm(blk * h)
    return Linear(A=A, B=B, Ad=E[:4, :4], Bd=E[:4, 4:], C=C_MEAS.copy(), h=h)


def process_noise_cov(lin: Linear, std: float = DISTURBANCE_STD, hold: float = DISTURBANCE_HOLD) -> np.ndarray:
    """Qn of the discrete model for a white voltage disturbance of std ``std`` held over ``hold`` seconds.

    Over one period ``h`` (``h / hold`` whole holds) the state picks up ``sum_j G_j d_j``, ``G_j`` the response
    to a unit voltage over hold ``j``; the covariance is ``std^2 sum_j G_j G_j'``.
    """
    from scipy.linalg import expm

    n_hold = int(round(lin.h / hold))
    if n_hold < 1 or abs(n_hold * hold - lin.h) > 1e-12:
        raise ValueError(f"hold ({hold} s) must divide the period ({lin.h} s)")
    blk = np.zeros((5, 5))
    blk[:4, :4], blk[:4, 4:] = lin.A, lin.B
    E = expm(blk * hold)
    Ah, Bh = E[:4, :4], E[:4, 4:]
    Q = np.zeros((4, 4))
    for j in range(n_hold):
        G = np.linalg.matrix_power(Ah, n_hold - 1 - j) @ Bh
        Q += G @ G.T
    return _variance(std, None) * Q


def observability_rank(Ad: np.ndarray, C: np.ndarray) -> int:
    """Rank of ``[C; C Ad; C Ad^2; C Ad^3]`` (the slides' observability test)."""
    n = Ad.shape[0]
    O = np.vstack([C @ np.linalg.matrix_power(Ad, i) for i in range(n)])
    return int(np.linalg.matrix_rank(O))


class PendulumPlant:
    """Marker base for documentation; the plant is a :class:`netsim.plant.NonlinearPlant` (see the factory)."""


def _variance(std: float, where: str | None) -> float:
    """``std ** 2``, or a :class:`~netsim.errors.ConfigError` (at ``where.disturbance_std`` when ``where`` is
    given) saying what to write when the square overflows a float (a std past about 1.3e154 V; netsim's number
    limit, 1e15, is far below it, so only a direct Python call gets this far)."""
    from netsim.errors import ConfigError
    from netsim.units import NUMBER_LIMIT

    try:
        var = std**2
    except OverflowError:
        var = math.inf
    if not math.isfinite(var):
        raise ConfigError(f"a disturbance std of {std:g} V has a variance too large for a float; write a std of at "
                          f"most {NUMBER_LIMIT:g} V (the QUBE-Servo 2's is {DISTURBANCE_STD:g} V)",
                          path=f"{where}.disturbance_std" if where else None)
    return var


@register("plant", "furuta_pendulum",
          "rotary inverted (Furuta) pendulum with DC motor, Quanser QUBE-Servo 2 values; input voltage, y = [theta, alpha]")
def furuta_pendulum(params: PendulumParams | None = None, **kwargs: object):  # -> netsim.plant.NonlinearPlant
    """The nonlinear pendulum (the truth), with its continuous linearisation about the upright as ``A, B, C, D``.

    The ``A, B, C, D`` attributes let the generic ``state_feedback`` program design its estimator and law on the
    ZOH discretisation of the linearisation at its own period, as it does for a linear plant. A nonzero
    ``disturbance_std`` adds the white input-voltage disturbance (a discrete disturbance model held over
    ``disturbance_hold``, drawn from the run's stream ``plant.pendulum.disturbance.u``).
    """
    from netsim.plant import LTIDisturbance, NonlinearPlant

    p = params if params is not None else PendulumParams.model_validate(kwargs)
    plant = NonlinearPlant(_Rhs(p), output, 4, 1, 2, params=p, input_names=["u"], output_names=["theta", "alpha"],
                           state_names=["theta", "theta_dot", "alpha", "alpha_dot"], name="pendulum",
                           divergence_bound=1e3)
    A, B = linearise(p)
    plant.A, plant.B, plant.C, plant.D = A, B, C_MEAS.copy(), np.zeros((2, 1))
    if p.disturbance_std > 0:
        dt_ns = int(round(p.disturbance_hold * 1e9))
        plant.add_disturbance("u", LTIDisturbance([[0.0]], [[1.0]], [[1.0]], dt_ns=dt_ns,
                                                  noise_cov=_variance(p.disturbance_std, "plant.params")))
    return plant


furuta_pendulum.Params = PendulumParams  # type: ignore[attr-defined]
