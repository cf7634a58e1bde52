"""Luenberger observer for a discrete model, gain by pole placement, in predictor or current form.

Model: ``x[k+1] = A x[k] + B u[k]``, ``y[k] = C x[k]``.

*Predictor form* (the estimate at ``k`` uses measurements up to ``y[k-1]``: it leaves a whole sample for the
computation)::

    x_hat[k+1] = A x_hat[k] + B u[k] + L (y[k] - C x_hat[k])
    e[k+1] = (A - L C) e[k],            e = x - x_hat

with ``L`` placing the eigenvalues of ``A - L C`` at the requested poles (``L' = place(A', C', poles)``).

*Current (filter) form* (the estimate at ``k`` already uses ``y[k]``)::

    x_bar[k] = A x_hat[k-1] + B u[k-1]                  (prediction)
    x_hat[k] = x_bar[k] + L (y[k] - C x_bar[k])         (correction)
    e[k+1] = (I - L C) A e[k]  =  (A - L C A) e[k]

with ``L`` placing the eigenvalues of ``A - L C A`` at the requested poles (``L' = place(A', (C A)', poles)``;
this needs ``(A, C A)`` observable, so ``A`` may not have a zero eigenvalue in an unobservable direction).
The prediction error ``x - x_bar`` has the same eigenvalues (``A (I - L C)`` is similar to ``(I - L C) A``).

*A measurement one sample late* (:meth:`LuenbergerObserver.correct_previous`: ``y[k-1]`` reaches the estimator
at sample ``k`` and sample ``k-1`` fused none). The observer re-filters that one step exactly: with ``x_bar[k-1]``
the estimate held at the start of sample ``k-1`` (before any correction there), ::

    x_hat[k] <- x_hat[k] + A L (y[k-1] - C x_bar[k-1])     (current form)
    x_hat[k] <- x_hat[k] + L (y[k-1] - C x_hat[k-1])       (predictor form: its own update, one sample late)

which is the estimate the observer would hold had ``y[k-1]`` come in time (the model is linear and the input
``u[k-1]`` is known), so a sensor sampling more than half a period before the controller is not dropped.

The gain is computed once at construction with python-control's ``acker`` (one output: handles repeated
poles) or ``place`` (several outputs); the steps are plain numpy.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from netsim.control.design_checks import (
    as_input_matrix,
    as_matrix,
    as_vector,
    check_poles,
    check_square,
    uncontrollable_modes,
)
from netsim.control.interface import EstimatorBase, EstimatorCapabilities
from netsim.errors import ConfigError, SimulationError

__all__ = ["LuenbergerObserver", "observer_gain"]


def observer_gain(A: Any, C: Any, poles: Any, form: Literal["predictor", "current"] = "predictor") -> np.ndarray:
    """Gain ``L`` (``n x p``) placing the observer error eigenvalues of ``form`` at ``poles``.

    Raises
    ------
    ConfigError
        Poles not strictly inside the unit circle or not in conjugate pairs, a mode the measurement cannot
        see (named by its eigenvalue), or a placement python-control cannot achieve.
    """
    A = as_matrix("A", A)
    n = check_square("A", A)
    C = as_matrix("C", C, (None, n))
    p = check_poles("poles", poles, n)
    if form not in ("predictor", "current"):
        raise ConfigError(f"form must be 'predictor' or 'current', got {form!r}")
    Cf = C if form == "predictor" else C @ A
    what = "(A, C)" if form == "predictor" else "(A, C A) (current form)"
    hidden = uncontrollable_modes(A.T, Cf.T, only_unstable=False)
    if hidden:
        modes = ", ".join(f"{complex(m):.6g}" for m in hidden)
        extra = (
            " (A has a zero eigenvalue there: use the predictor form)"
            if form == "current" and any(abs(m) < 1e-12 for m in hidden)
            else ""
        )
        raise ConfigError(
            f"poles: the pair {what} is not observable, so the observer cannot place the mode(s) at eigenvalue "
            f"{modes}{extra}; measure another output"
        )
    import control  # lazy: python-control takes about a second to import

    try:
        if Cf.shape[0] == 1:
            Lt = control.acker(A.T, Cf.T, p)
        else:
            Lt = control.place(A.T, Cf.T, p)
    except Exception as exc:  # python-control/scipy raise ValueError, LinAlgError, ControlDimension ...
        asked = ", ".join(f"{complex(q):.6g}" for q in p)
        raise ConfigError(f"poles: python-control could not place the observer poles {asked} ({exc})") from exc
    L = np.asarray(Lt, dtype=float).reshape(Cf.shape[0], n).T
    # compare characteristic polynomials: well conditioned even for repeated poles, whose computed
    # eigenvalues scatter by eps^(1/multiplicity)
    got = np.poly(A - L @ Cf)
    want = np.real(np.poly(p))
    if np.max(np.abs(got - want)) > 1e-8 * max(1.0, float(np.max(np.abs(want)))):
        asked = ", ".join(f"{complex(q):.6g}" for q in p)
        raise ConfigError(
            f"poles: the placement is ill-conditioned (asked {asked}, got the eigenvalues "
            f"{', '.join(f'{complex(q):.6g}' for q in np.linalg.eigvals(A - L @ Cf))}); choose poles further apart "
            "or use fewer repeated poles"
        )
    return L


class LuenbergerObserver(EstimatorBase):
    """Discrete Luenberger observer (see the module docstring for both forms and their error dynamics).

    Parameters
    ----------
    A, B, C
        Discrete model; ``B`` may be ``None`` (no input).
    poles
        ``n`` observer poles, strictly inside the unit circle, complex ones in conjugate pairs.
    form
        ``"current"`` (default, as the YAML ``estimator: {type: luenberger}``: the estimate at ``k`` uses ``y[k]``)
        or ``"predictor"`` (estimate at ``k`` from ``y`` up to ``k-1``).
    x0
        Initial estimate (default zeros).

    Notes
    -----
    In a loop (:class:`~netsim.control.interface.OutputFeedback`): :meth:`correct` with ``y[k]``, the law reads
    :attr:`x_hat`, then :meth:`predict` with ``u[k]``. In the predictor form ``correct`` only stores ``y[k]``
    for the next prediction; a sample without measurement predicts open loop (``x_hat <- A x_hat + B u``).
    """

    def __init__(
        self,
        A: Any,
        B: Any,
        C: Any,
        poles: Any,
        *,
        form: Literal["predictor", "current"] = "current",
        x0: Any = None,
    ) -> None:
        self.A = as_matrix("A", A)
        n = check_square("A", self.A)
        self.B = np.zeros((n, 0)) if B is None else as_input_matrix("B", B, n)
        self.C = as_matrix("C", C, (None, n))
        self.n, self.m, self.p = n, self.B.shape[1], self.C.shape[0]
        self.form = form
        self.L = observer_gain(self.A, self.C, poles, form)
        self.poles = check_poles("poles", poles, n)
        self.x0 = np.zeros(n) if x0 is None else as_vector("x0", x0, n)
        self.reset()

    @property
    def capabilities(self) -> EstimatorCapabilities:
        """No history: a measurement of the previous sample is fused one step late (``correct_previous``); starts
        from a first measurement (``start_from``, ``start_previous``)."""
        return EstimatorCapabilities(corrects_previous=True, starts_from=True, starts_previous=True)

    def reset(self, x0: Any = None) -> None:
        """Back to the initial estimate, no stored measurement."""
        self.x = self.x0.copy() if x0 is None else as_vector("x0", x0, self.n)
        self._y: np.ndarray | None = None
        self._prior = self.x.copy()  # the estimate at the start of this sample, before any correction
        self._prev_prior: np.ndarray | None = None  # the same at the previous sample (None: no previous sample)
        self._prev_fused = False  # whether the previous sample fused a measurement

    @property
    def x_hat(self) -> np.ndarray:
        """Estimate at the current sample."""
        return self.x

    @property
    def error_matrix(self) -> np.ndarray:
        """Matrix of the error dynamics: ``A - L C`` (predictor) or ``(I - L C) A`` (current)."""
        if self.form == "predictor":
            return self.A - self.L @ self.C
        return (np.eye(self.n) - self.L @ self.C) @ self.A

    def start_from(self, y: Any) -> None:
        """Start the estimate from the measurement of the current sample: ``x_hat <- x_hat + pinv(C) (y - C x_hat)``
        (:func:`~netsim.control.interface.first_measurement_estimate`); call it before :meth:`correct`."""
        from netsim.control.interface import first_measurement_estimate

        self.x = first_measurement_estimate(self.C, y, self.x)
        self._prior = self.x.copy()

    def _measurement(self, y: Any) -> np.ndarray:
        y = np.asarray(y, dtype=float).reshape(-1)
        if y.shape[0] != self.p:
            raise SimulationError(f"Luenberger observer: the measurement has {y.shape[0]} entries, C has {self.p} rows")
        return y

    def start_previous(self, y: Any) -> None:
        """Start the estimate from a measurement of the previous sample (``x0_hat: first_measurement`` when the
        first measurement is one sample late): as if :meth:`start_from` had run there; call it before
        :meth:`correct_previous`."""
        from netsim.control.interface import first_measurement_estimate

        if self._prev_prior is None:
            return
        d = first_measurement_estimate(self.C, self._measurement(y), self._prev_prior) - self._prev_prior
        self._prev_prior = self._prev_prior + d
        self.x = self.x + self.A @ d
        self._prior = self._prior + self.A @ d

    def correct_previous(self, y: Any) -> bool:
        """Fuse the measurement ``y[k-1]`` of the previous sample now (the one-step re-filter of the module
        docstring); call it before :meth:`correct`. ``False`` (nothing changed) at the first sample or when the
        previous sample fused a measurement already."""
        if self._prev_prior is None or self._prev_fused or self._y is not None:
            return False
        e = self._measurement(y) - self.C @ self._prev_prior
        dx = (self.A @ self.L @ e) if self.form == "current" else self.L @ e
        self.x = self.x + dx
        self._prior = self._prior + dx
        self._prev_fused = True
        return True

    def correct(self, y: Any) -> bool:
        """Use the measurement of the current sample; ``False`` if one was already used at this sample."""
        if self._y is not None:
            return False
        y = self._measurement(y)
        self._y = y
        if self.form == "current":
            self.x = self.x + self.L @ (y - self.C @ self.x)
        return True

    def predict(self, u: Any = None) -> None:
        """Move to the next sample with input ``u``."""
        if self.m:
            u = np.zeros(self.m) if u is None else np.asarray(u, dtype=float).reshape(-1)
            x = self.A @ self.x + self.B @ u
        else:
            x = self.A @ self.x
        if self.form == "predictor" and self._y is not None:
            x = x + self.L @ (self._y - self.C @ self.x)
        self._prev_prior, self._prev_fused = self._prior, self._y is not None
        self.x = x
        self._prior = x.copy()
        self._y = None
