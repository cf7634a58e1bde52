"""The input a ``state_feedback`` task's estimator predicts with: ``input_delay`` and ``applied_input``.

:func:`input_plan` decides, from the estimator part's declared capabilities (:class:`~netsim.control.parts.
EstimatorPart`), the model the estimator is built on (issue 26 section 5; the equations are in
:mod:`netsim.control.interface` and :mod:`netsim.programs.state_feedback`) and checks ``x0_hat``, before the
estimator is built, so it is built once, on that model. Validation and the run both call it (through
:func:`~netsim.programs.feedback_design.task_design`), so validation refuses what a run would refuse, at the same
YAML path. :meth:`InputPlan.runtime` makes the run's own delay line or report timeline.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from netsim.control.interface import EstimatorBase, EstimatorCapabilities, capabilities_of
from netsim.errors import ConfigError

__all__ = ["InputPlan", "input_plan"]


@dataclass(frozen=True, eq=False)
class InputPlan:
    """How the estimator is fed the input the plant holds.

    Attributes
    ----------
    kind
        ``computed``: ``u[k]`` as computed; ``delayed``: ``[u[k-d]; u[k-d-1]]`` from an
        :class:`~netsim.control.interface.InputDelayLine` (model ``B = [Gamma0 Gamma1]``); ``delayed_first``:
        ``u[k-d]`` only (a part taking whole periods of delay); ``applied``: the effect of the reported input
        over each period (model ``B = I``, :class:`~netsim.control.interface.AppliedInputTimeline`).
    d
        Whole periods of ``input_delay``.
    continuous
        The plant's continuous ``(A, B)`` (for ``applied``).
    """

    kind: Literal["computed", "delayed", "delayed_first", "applied"] = "computed"
    d: int = 0
    continuous: tuple[np.ndarray, np.ndarray] | None = None

    def key(self) -> str:
        """What the estimator's model depends on beyond the design's matrices."""
        return f"{self.kind}:{self.d}"

    def check_built(self, estimator: Any, p: Any, path: str) -> None:
        """``applied_input`` re-predicts past periods: the built estimator keeps ``history >= 1`` samples."""
        if self.kind == "applied" and int(estimator.history) < 1:
            raise ConfigError("applied_input re-predicts past periods: give the estimator 'history' >= 1 samples",
                              path=f"{path}.params.estimator.history")

    def runtime(self, estimator: Any, m: int, period_ns: int, offset_ns: int) -> tuple[Any, Any, Any]:
        """The run's ``(estimator, delay line, timeline)``: fresh delay line / timeline objects."""
        from netsim.control.interface import AppliedInputTimeline, InputDelayLine

        if self.kind == "delayed":
            return estimator, InputDelayLine(m, self.d), None
        if self.kind == "delayed_first":
            return _FirstHalf(estimator, m), InputDelayLine(m, self.d), None
        if self.kind == "applied":
            Ac, Bc = self.continuous  # type: ignore[misc]
            return estimator, None, AppliedInputTimeline(Ac, Bc, int(period_ns), offset_ns)
        return estimator, None, None


def input_plan(p: Any, part: Any, design: Any, continuous: tuple[np.ndarray, np.ndarray] | None, period_ns: int,
               path: str) -> tuple[Any, InputPlan, tuple[str, str] | None]:
    """The model the estimator is built on, how it is fed, and (for a changed model) the lead and YAML path of a
    build error.

    ``input_delay = d * period + tau'``: the estimator is built on ``B = [Gamma0 Gamma1]`` (the ZOH split of the
    period at ``tau'``, :func:`~netsim.control.interface.zoh_split`; ``[B 0]`` when ``tau' = 0``) and fed
    ``[u[k-d]; u[k-d-1]]``. ``applied_input``: built on ``B = I`` and fed the effect of the reported input over
    each period. ``continuous``: the plant's continuous ``(A, B)`` when the model is its ZOH discretisation.
    Also checks ``x0_hat``.

    Raises
    ------
    ConfigError
        At ``<path>.params.input_delay`` / ``.applied_input`` / ``.x0_hat``.
    """
    from netsim.control.interface import zoh_split

    pp = f"{path}.params"
    kind = p.estimator.type
    if p.x0_hat == "first_measurement" and not part.starts_from_measurement:
        raise ConfigError(f"the estimator '{kind}' cannot start from a measurement; use x0_hat: x0 (and the "
                          "estimator's x0), or a kalman, steady_state_kalman, ekf or luenberger estimator",
                          path=f"{pp}.x0_hat")
    if p.input_delay is None and p.applied_input is None:
        return design, InputPlan(), None
    if p.input_delay is not None and p.applied_input is not None:
        raise ConfigError("give input_delay (a known constant delay) or applied_input (the actuator's reports), not "
                          "both", path=f"{pp}.applied_input")
    n = design.A.shape[0]
    if p.input_delay is not None:
        where = f"{pp}.input_delay"
        if p.input_delay < 0:
            raise ConfigError(f"input_delay must be >= 0, got {p.input_delay} ns", path=where)
        d, rest = divmod(int(p.input_delay), int(period_ns))
        lo, hi = f"{d * period_ns / 1e6:g} ms", f"{(d + 1) * period_ns / 1e6:g} ms"
        if rest and continuous is None:
            raise ConfigError(f"input_delay is {d} periods and {rest / 1e6:g} ms: a fraction of a period needs the "
                              "plant's continuous linear model (A, B) for the ZOH split; give a whole number of "
                              f"periods (e.g. {lo} or {hi})", path=where)
        if part.input_delay == "whole_periods":
            if rest:
                raise ConfigError(f"the {kind} estimator takes whole periods of input delay only; give a multiple of "
                                  f"the period (e.g. {lo} or {hi})", path=where)
            return design, InputPlan("delayed_first", d), None
        if rest:
            assert continuous is not None  # refused above
            _, G0, G1 = zoh_split(*continuous, period_ns * 1e-9, rest * 1e-9)
        else:
            G0, G1 = design.B, np.zeros_like(design.B)
        return (dataclasses.replace(design, B=np.hstack([G0, G1])), InputPlan("delayed", d),
                (f"the estimator '{kind}' on the model with the delayed input", where))
    where = f"{pp}.applied_input"
    if continuous is None:
        raise ConfigError("applied_input needs the plant's continuous linear model (A, B), to integrate the "
                          "reported input over each period; use input_delay with a whole number of periods",
                          path=where)
    if not part.late_inputs:
        lead = (f"applied_input is for the linear Kalman filters (kalman, steady_state_kalman); with {kind} use "
                "input_delay") if part.input_delay == "whole_periods" else (
                f"the estimator '{kind}' cannot take inputs learned late (it keeps no history): use input_delay, or "
                "a Kalman filter (kalman, steady_state_kalman)")
        raise ConfigError(lead, path=where)
    return (dataclasses.replace(design, B=np.eye(n)), InputPlan("applied", 0, continuous),
            (f"the estimator '{kind}' on the model with the delayed input", where))


class _FirstHalf(EstimatorBase):
    """An estimator fed ``u[k-d]`` from an :class:`~netsim.control.interface.InputDelayLine` (whole periods)."""

    def __init__(self, estimator: Any, m: int) -> None:
        self._est, self._m = estimator, m

    @property
    def capabilities(self) -> EstimatorCapabilities:
        return capabilities_of(self._est)

    def predict(self, u: Any = None) -> None:
        self._est.predict(None if u is None else np.asarray(u)[: self._m])

    def __getattr__(self, name: str) -> Any:
        return getattr(self._est, name)
