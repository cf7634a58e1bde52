"""The input a ``state_feedback`` task's estimator predicts with: ``input_delay`` and ``applied_input``.

:func:`input_options` rebuilds the task's estimator on the model of the input the plant really holds (issue 26
section 5; the equations are in :mod:`netsim.control.interface` and :mod:`netsim.programs.state_feedback`) and
checks ``x0_hat``. Building the program and ``netsim validate`` both call it, so validation refuses what a run
would refuse, at the same YAML path.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from netsim.errors import ConfigError

__all__ = ["input_options"]


def input_options(p: Any, design: Any, estimator: Any, plant: Any, period_ns: int | None, offset_ns: int,
                   path: str) -> tuple[Any, Any, Any]:
    """The estimator rebuilt for ``input_delay`` / ``applied_input``, the delay line and the report timeline.

    ``input_delay = d * period + tau'``: the estimator is built on ``B = [Gamma0 Gamma1]`` (the ZOH split of the
    period at ``tau'``, :func:`~netsim.control.interface.zoh_split`; ``[B 0]`` when ``tau' = 0``) and fed
    ``[u[k-d]; u[k-d-1]]`` (:class:`~netsim.control.interface.InputDelayLine`). ``applied_input``: built on
    ``B = I`` and fed the effect of the reported input over each period
    (:class:`~netsim.control.interface.AppliedInputTimeline`). Also checks ``x0_hat``.

    Raises
    ------
    ConfigError
        At ``<path>.params.input_delay`` / ``.applied_input`` / ``.x0_hat``.
    """
    import dataclasses

    from netsim.control.interface import AppliedInputTimeline, InputDelayLine, zoh_split
    from netsim.programs.feedback_design import model_source

    pp = f"{path}.params"
    kind = str(p.estimator.get("type"))
    if p.x0_hat == "first_measurement" and kind != "none" and not callable(getattr(estimator, "start_from", None)):
        raise ConfigError(f"the estimator '{kind}' cannot start from a measurement; use x0_hat: x0 (and the "
                          "estimator's x0), or a kalman, steady_state_kalman, ekf or luenberger estimator",
                          path=f"{pp}.x0_hat")
    if p.input_delay is None and p.applied_input is None:
        return estimator, None, None
    if p.input_delay is not None and p.applied_input is not None:
        raise ConfigError("give input_delay (a known constant delay) or applied_input (the actuator's reports), not "
                          "both", path=f"{pp}.applied_input")
    if period_ns is None:
        return estimator, None, None  # build_parts has refused it already
    continuous = None
    if p.model is None and model_source(p, plant) == "zoh":
        continuous = (np.atleast_2d(np.asarray(plant.A, dtype=float)), np.asarray(plant.B, dtype=float))
    n, m = design.A.shape[0], design.B.shape[1]
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
        if kind == "ekf":
            if rest:
                raise ConfigError("the ekf estimator takes whole periods of input delay only; give a multiple of the "
                                  f"period (e.g. {lo} or {hi})", path=where)
            line = InputDelayLine(m, d)
            return _FirstHalf(estimator, m), line, None
        if rest:
            _, G0, G1 = zoh_split(*continuous, period_ns * 1e-9, rest * 1e-9)  # type: ignore[misc]
        else:
            G0, G1 = design.B, np.zeros_like(design.B)
        est = _rebuild(p, dataclasses.replace(design, B=np.hstack([G0, G1])), where)
        return est, InputDelayLine(m, d), None
    where = f"{pp}.applied_input"
    if continuous is None:
        raise ConfigError("applied_input needs the plant's continuous linear model (A, B), to integrate the "
                          "reported input over each period; use input_delay with a whole number of periods",
                          path=where)
    if kind == "ekf":
        raise ConfigError("applied_input is for the linear Kalman filters (kalman, steady_state_kalman); with ekf "
                          "use input_delay", path=where)
    est = _rebuild(p, dataclasses.replace(design, B=np.eye(n)), where)
    if not callable(getattr(est, "revise_inputs", None)):
        raise ConfigError(f"the estimator '{kind}' cannot take inputs learned late (it keeps no history): use "
                          "input_delay, or a Kalman filter (kalman, steady_state_kalman)", path=where)
    if int(getattr(est, "history", 0)) < 1:
        raise ConfigError("applied_input re-predicts past periods: give the estimator 'history' >= 1 samples",
                          path=f"{pp}.estimator.history")
    return est, None, AppliedInputTimeline(continuous[0], continuous[1], int(period_ns), offset_ns)


def _rebuild(p: Any, design: Any, where: str) -> Any:
    """The task's estimator built again on ``design`` (its input matrix replaced)."""
    from netsim.programs.feedback_design import part_params
    from netsim.registry import lookup

    raw = p.estimator
    kind = "estimator"
    obj = lookup(kind, str(raw["type"]))
    cls = part_params(kind, raw["type"])
    values = {k: v for k, v in raw.items() if k != "type"}
    params = cls.model_validate(values) if cls is not None else values
    try:
        return obj.build(params, design)
    except ConfigError as exc:
        raise ConfigError(f"the estimator '{raw['type']}' on the model with the delayed input: {exc.message}",
                          path=where) from None


class _FirstHalf:
    """An estimator fed ``u[k-d]`` from an :class:`~netsim.control.interface.InputDelayLine` (whole periods)."""

    def __init__(self, estimator: Any, m: int) -> None:
        self._est, self._m = estimator, m

    def predict(self, u: Any = None) -> None:
        self._est.predict(None if u is None else np.asarray(u)[: self._m])

    def __getattr__(self, name: str) -> Any:
        return getattr(self._est, name)
