"""State feedback and discrete LQR, with reference feed-forward, integral action and trajectory tracking.

Model: ``x[k+1] = A x[k] + B u[k]``; the law is fed a state estimate ``x_hat`` and a reference ``r``.

*Output reference* (``Cr`` given, ``r`` has one entry per row of ``Cr``): the steady state that holds
``Cr x = r`` solves ``[[A - I, B], [Cr, 0]] [Nx; Nu] = [0; I]`` and the law is
``u = Nu r - K (x_hat - Nx r)`` (with ``feedforward=False``: ``u = -K x_hat``).

*Integral action* (``integral=True``, needs ``Cr``): the integrator ``z[k+1] = z[k] + (r[k] - Cr x_hat[k])``
augments the model, the LQR is designed on ``([[A, 0], [-Cr, I]], [[B], [0]])`` with weight
``blkdiag(Q, Qi)`` and the law adds ``- Ki z``. The integrator does not move while the output is
saturated (``u_min``/``u_max``) in the direction that would wind it up.

*State reference and trajectory tracking* (``Cr`` is ``None``): ``r`` is a state reference ``x_ref`` (``n``
entries; one number is the same for every state, so ``0`` regulates) or ``[x_ref, u_ref]`` (``n + m`` entries)
and ``u = u_ref - K (x_hat - x_ref)``. Without ``u_ref`` the
least-squares equilibrium input of ``x_ref`` is used; :func:`trajectory_feedforward` gives ``u_ref`` along a
state trajectory (``B u_ref[k] = x_ref[k+1] - A x_ref[k]`` in least squares), with which a feasible trajectory
is tracked with error dynamics ``e[k+1] = (A - B K) e[k]``.

The gain comes from python-control's ``dlqr`` once, at construction; :meth:`StateFeedback.step` is numpy only.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from netsim.control.design_checks import (
    as_input_matrix,
    as_matrix,
    check_square,
    check_stabilizable,
    check_weight,
)
from netsim.control.interface import LawBase
from netsim.errors import ConfigError, SimulationError

__all__ = ["StateFeedback", "LQR", "dlqr_gain", "output_weighted", "reference_gains", "trajectory_feedforward"]


def _model(A: Any, B: Any) -> tuple[np.ndarray, np.ndarray]:
    A = as_matrix("A", A)
    n = check_square("A", A)
    return A, as_input_matrix("B", B, n)


def _limits(name: str, value: Any, m: int) -> np.ndarray | None:
    if value is None:
        return None
    v = np.array(value, dtype=float).reshape(-1)
    if v.size == 1:
        v = np.full(m, float(v[0]))
    if v.size != m:
        raise ConfigError(f"{name} must be one number or {m} numbers (one per input), got {v.size}")
    return v


def output_weighted(Q: Any, Qy: Any, C: Any, n: int) -> np.ndarray:
    """The state weight ``Q + C' Qy C``: a state weight ``Q`` plus an output weight ``Qy`` on ``y = C x``.

    Either may be ``None`` (taken as zero), not both. ``Qy`` is ``p x p`` for the ``p`` rows of ``C`` (a number
    is a multiple of the identity, a list the diagonal), so an output can be weighted without knowing the
    state realisation (a ``tf`` plant's, for instance).

    Raises
    ------
    ConfigError
        Neither weight given, ``Qy`` without ``C``, or a weight of the wrong size or not positive semidefinite.
    """
    if Q is None and Qy is None:
        raise ConfigError("Q: give a state weight Q, an output weight Qy (on y = C x), or both")
    W = np.zeros((n, n)) if Q is None else check_weight("Q", Q, n, definite=False)
    if Qy is None:
        return W
    if C is None:
        raise ConfigError("Qy: an output weight needs the output matrix C (y = C x)")
    C = as_matrix("C", C, (None, n))
    Wy = check_weight("Qy", Qy, C.shape[0], definite=False)
    W = W + C.T @ Wy @ C
    return 0.5 * (W + W.T)


def dlqr_gain(A: Any, B: Any, Q: Any, R: Any, N: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """LQR gain ``K`` and Riccati solution ``P`` of ``sum x'Qx + u'Ru + 2x'Nu`` by python-control's ``dlqr``.

    Raises
    ------
    ConfigError
        Wrong dimensions, ``Q`` not positive semidefinite, ``R`` not positive definite, ``(A, B)`` not
        stabilisable (naming the mode), or a Riccati equation without a stabilising solution.
    """
    A, B = _model(A, B)
    n, m = B.shape
    Q = check_weight("Q", Q, n, definite=False)
    R = check_weight("R", R, m, definite=True)
    Nm = np.zeros((n, m)) if N is None else as_matrix("N", N, (n, m))
    check_stabilizable(A, B)
    import control  # lazy: python-control takes about a second to import

    try:
        K, P, _ = control.dlqr(A, B, Q, R, Nm)
    except Exception as exc:  # slycot/python-control raise ValueError, ArithmeticError, SlycotError ...
        raise ConfigError(
            f"Q: the LQR Riccati equation has no stabilising solution ({exc}); make Q weight every unstable mode"
        ) from exc
    return np.asarray(K, dtype=float), np.asarray(P, dtype=float)


def reference_gains(A: np.ndarray, B: np.ndarray, Cr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(Nx, Nu)`` with ``x = Nx r``, ``u = Nu r`` the equilibrium holding ``Cr x = r``.

    Raises
    ------
    ConfigError
        When no equilibrium holds every reference (more references than inputs, or a zero of the plant at 1).
    """
    n, m = B.shape
    q = Cr.shape[0]
    M = np.block([[A - np.eye(n), B], [Cr, np.zeros((q, m))]])
    rhs = np.vstack([np.zeros((n, q)), np.eye(q)])
    sol, *_ = np.linalg.lstsq(M, rhs, rcond=None)
    if np.max(np.abs(M @ sol - rhs)) > 1e-8:
        raise ConfigError(
            "Cr: no steady state holds the reference (more references than inputs, or the plant has a zero at "
            "z = 1); track fewer outputs or turn feedforward off and use integral action"
        )
    return sol[:n], sol[n:]


def trajectory_feedforward(A: Any, B: Any, X_ref: Any) -> np.ndarray:
    """Least-squares feed-forward inputs along a state trajectory: ``B u[k] = X_ref[k+1] - A X_ref[k]``.

    Parameters
    ----------
    A, B
        Discrete model.
    X_ref
        Reference states, shape ``(T, n)``.

    Returns
    -------
    numpy.ndarray
        ``(T - 1, m)`` inputs; exact when the trajectory is one the model can follow.
    """
    A, B = _model(A, B)
    X = as_matrix("X_ref", X_ref, (None, A.shape[0]))
    D = X[1:] - X[:-1] @ A.T
    U, *_ = np.linalg.lstsq(B, D.T, rcond=None)
    return U.T


class StateFeedback(LawBase):
    """``u = u_ff(r) - K x_hat`` (and ``- Ki z`` with integral action), optionally saturated.

    Parameters
    ----------
    A, B
        Discrete model (used for the feed-forward).
    K
        State gain (``m x n``).
    Cr
        Reference output matrix (``q x n``): ``r`` is an output reference. ``None``: ``r`` is a state reference
        ``x_ref`` or ``[x_ref, u_ref]`` (see the module docstring).
    Ki
        Integral gain (``m x q``, needs ``Cr``), or ``None`` for no integral action.
    feedforward
        Add the steady-state feed-forward of an output reference (default ``True``).
    u_min, u_max
        Optional input limits (one number, or one per input).
    """

    def __init__(
        self,
        A: Any,
        B: Any,
        K: Any,
        *,
        Cr: Any = None,
        Ki: Any = None,
        feedforward: bool = True,
        u_min: Any = None,
        u_max: Any = None,
    ) -> None:
        self.A, self.B = _model(A, B)
        n, m = self.B.shape
        self.n, self.m = n, m
        self.K = as_matrix("K", K, (m, n))
        self.Cr = None if Cr is None else as_matrix("Cr", Cr, (None, n))
        self.q = n if self.Cr is None else self.Cr.shape[0]
        if Ki is not None and self.Cr is None:
            raise ConfigError("Ki: integral action needs Cr (the outputs whose error is integrated)")
        self.Ki = None if Ki is None else as_matrix("Ki", Ki, (m, self.q))
        self.feedforward = bool(feedforward)
        self.u_min = _limits("u_min", u_min, m)
        self.u_max = _limits("u_max", u_max, m)
        if self.u_min is not None and self.u_max is not None and np.any(self.u_min >= self.u_max):
            raise ConfigError(f"u_min ({self.u_min}) must be below u_max ({self.u_max}) for every input")
        if self.Cr is not None:
            if self.feedforward:
                Nx, Nu = reference_gains(self.A, self.B, self.Cr)
                self._Fr = Nu + self.K @ Nx  # u = -K x + Fr r
            else:
                self._Fr = np.zeros((m, self.q))
        else:
            self._Bpinv = np.linalg.pinv(self.B)
            self._AmI = self.A - np.eye(n)
        self.reset()

    def reset(self) -> None:
        """Zero the integrator."""
        self.z = np.zeros(self.q if self.Ki is not None else 0)
        self.u = np.zeros(self.m)

    def _clip(self, v: np.ndarray) -> np.ndarray:
        if self.u_min is not None:
            v = np.maximum(v, self.u_min)
        if self.u_max is not None:
            v = np.minimum(v, self.u_max)
        return v

    def step(self, x_hat: Any, r: Any) -> np.ndarray:
        """Control signal for the estimate ``x_hat`` and reference ``r`` (see the class and module docstrings)."""
        x = np.asarray(x_hat, dtype=float).reshape(-1)
        if x.shape[0] != self.n:
            raise SimulationError(f"state feedback: x_hat has {x.shape[0]} entries, the model has {self.n} states")
        r = np.asarray(r, dtype=float).reshape(-1)
        if self.Cr is not None:
            if r.shape[0] == 1 and self.q > 1:
                r = np.full(self.q, r[0])
            elif r.shape[0] != self.q:
                raise SimulationError(f"state feedback: the reference has {r.shape[0]} entries, Cr has {self.q} rows")
            v = self._Fr @ r - self.K @ x
        else:
            n = self.n
            if r.shape[0] == 1 and n > 1:
                r = np.full(n, r[0])  # one number: the same reference for every state (0: regulation)
            if r.shape[0] == n:
                u_ref = -self._Bpinv @ (self._AmI @ r)  # least-squares equilibrium input of x_ref
            elif r.shape[0] == n + self.m:
                u_ref = r[n:]
                r = r[:n]
            else:
                raise SimulationError(
                    f"state feedback: a state reference has {n} entries (x_ref) or {n + self.m} ([x_ref, u_ref]), "
                    f"got {r.shape[0]}"
                )
            v = u_ref - self.K @ (x - r)
        if self.Ki is None:
            u = self._clip(v)
        else:
            v = v - self.Ki @ self.z
            u = self._clip(v)
            e = r - self.Cr @ x
            # conditional integration: the integrator is frozen when an input is saturated and integrating e
            # would push that input further into the limit (dv is the change of v integration would cause)
            dv = -self.Ki @ e
            if not np.any(((u < v) & (dv > 0)) | ((u > v) & (dv < 0))):
                self.z = self.z + e
        self.u = u
        return u


class LQR(StateFeedback):
    """Discrete LQR state feedback: gain from python-control's ``dlqr`` at construction.

    Minimises ``sum x'Q x + u'R u + 2 x'N u`` for ``x[k+1] = A x[k] + B u[k]``, where an output weight ``Qy``
    on ``y = C x`` adds ``C' Qy C`` to ``Q`` (:func:`output_weighted`). With ``integral=True`` the
    design is on the model augmented with the integral of ``r - Cr x`` (weight ``Qi``, default the identity),
    and :attr:`K`, :attr:`Ki` are the two blocks of the augmented gain.

    Parameters
    ----------
    A, B, Q, R, N
        Model and weights (``Q`` positive semidefinite, ``R`` positive definite, ``N`` cross weight or ``None``).
        ``Q`` may be ``None`` when ``Qy`` is given.
    Qy, C
        Optional output weight (``p x p``, positive semidefinite) on ``y = C x``; the state weight of the design
        is ``Q + C' Qy C``.
    Cr, feedforward, u_min, u_max
        As in :class:`StateFeedback`.
    integral
        Add integral action on ``r - Cr x`` (needs ``Cr``).
    Qi
        Weight of the integrator states (``q x q``).

    Attributes
    ----------
    P
        Solution of the Riccati equation (of the augmented model with integral action); the MPC terminal cost.
    """

    def __init__(
        self,
        A: Any,
        B: Any,
        Q: Any,
        R: Any,
        *,
        N: Any = None,
        Cr: Any = None,
        integral: bool = False,
        Qi: Any = None,
        feedforward: bool = True,
        u_min: Any = None,
        u_max: Any = None,
        Qy: Any = None,
        C: Any = None,
    ) -> None:
        A_, B_ = _model(A, B)
        n, m = B_.shape
        Q = output_weighted(Q, Qy, C, n)
        Ki = None
        if integral:
            if Cr is None:
                raise ConfigError("integral: integral action needs Cr (the outputs whose error is integrated)")
            Cr_ = as_matrix("Cr", Cr, (None, n))
            q = Cr_.shape[0]
            Aa = np.block([[A_, np.zeros((n, q))], [-Cr_, np.eye(q)]])
            Ba = np.vstack([B_, np.zeros((q, m))])
            Qa = np.zeros((n + q, n + q))
            Qa[:n, :n] = check_weight("Q", Q, n, definite=False)
            Qa[n:, n:] = check_weight("Qi", np.eye(q) if Qi is None else Qi, q, definite=False)
            Na = None if N is None else np.vstack([as_matrix("N", N, (n, m)), np.zeros((q, m))])
            try:
                check_stabilizable(Aa, Ba, what="(A, B) augmented with the integrators of r - Cr x")
            except ConfigError as exc:
                raise ConfigError(
                    f"integral: {exc.message} (an integrator mode at 1 means the plant has a zero at z = 1 or "
                    "more tracked outputs than inputs)"
                ) from exc
            Ka, P = dlqr_gain(Aa, Ba, Qa, R, Na)
            K, Ki = Ka[:, :n], Ka[:, n:]
        else:
            K, P = dlqr_gain(A_, B_, Q, R, N)
        self.P = P
        super().__init__(A_, B_, K, Cr=Cr, Ki=Ki, feedforward=feedforward, u_min=u_min, u_max=u_max)
