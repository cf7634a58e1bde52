"""Scenario data given from Python: numpy values and python-control systems turned into what a YAML file holds.

A scenario given as a mapping (``netsim.run(dict)``, :func:`~netsim.scenario.load_scenario`, ``overrides=``, a
sweep given as a mapping) may hold the values a control engineer has at hand: a gain straight from
``control.dlqr`` (an ``ndarray``), weights from ``np.diag``, numpy scalars (``np.float64``, ``np.int64``,
``np.bool_``) and python-control systems. They are turned into plain Python data once, at the entry, before the
one validation, so that validation, the resolved ``scenario.yaml`` and the scenario hash all see exactly what
the same scenario written with lists would give (the same hash).

* A numpy array (0-d, 1-d, 2-d ...) becomes its ``tolist()``: a number, a list or a list of rows. A numpy
  scalar becomes the Python number or bool it holds. Non-finite values and object arrays are passed on as they
  are, and get validation's usual messages.
* A python-control ``StateSpace`` or ``TransferFunction`` becomes, where a plant is given (``plant: sys``,
  ``plant: {system: sys, x0: ...}`` or ``plant: {model: sys, x0: ...}``), the described plant
  ``{type: ss, A, B, C, D, dt}`` or ``{type: tf, num, den, dt}``
  (:func:`netsim.plant.described.plant_spec_from_system`; a ``NonlinearIOSystem`` becomes the plant model
  ``nonlinear_io``). Given as a ``model`` elsewhere (the ``state_feedback`` program's discrete model at the
  task period) it becomes ``{A, B, C}``; a transfer function is realised by python-control's ``ss`` first
  (the same realisation a ``tf`` plant gets). Such a model must be discrete, with ``dt`` equal to the task's
  period when the task gives one, and without feed-through (the estimators take ``y = C x``). Anywhere else a
  system is refused with a message saying where systems are accepted.

Examples
--------
>>> import numpy as np
>>> plain_values({"law": {"type": "state_feedback", "K": np.array([[1.5, 0.25]])}, "seed": np.int64(3)})
({'law': {'type': 'state_feedback', 'K': [[1.5, 0.25]]}, 'seed': 3}, [])
"""

from __future__ import annotations

from typing import Any, Sequence

from netsim.errors import ConfigError
from netsim.scenario.paths import PathPart, format_path, parse_path, plain_copy
from netsim.scenario.problems import Problem

__all__ = ["plain_values"]

#: Where a python-control system is accepted, for the message that refuses one elsewhere.
_SYSTEMS_GO = ("a python-control system is accepted as the plant (plant: sys, plant: {system: sys, x0: ...} or "
               "plant: {model: sys, ...}) or as a state_feedback model (params.model: a discrete system)")


def plain_values(data: Any, where: str | Sequence[PathPart] = (), root: Any = None) -> tuple[Any, list[Problem]]:
    """A plain copy of ``data`` (dicts, lists, numbers, text), with numpy values and python-control systems
    turned into the scenario's YAML forms (see the module docstring).

    Parameters
    ----------
    data
        A scenario mapping, or a value to be written at ``where`` (an override).
    where
        The YAML path of ``data`` in the scenario (``()``: the whole scenario).
    root
        The scenario ``data`` is written into (an override's), where a model's task period is looked up.

    Returns
    -------
    data
        The plain copy; nothing is shared with the input.
    problems
        Errors for systems that cannot be turned into the form their place takes (with their YAML path).
    """
    at = parse_path(where) if isinstance(where, str) and where else list(where or ())
    problems: list[Problem] = []
    return _walk(data, at, problems, _task_period(root, at)), problems


def _task_period(root: Any, at: list[PathPart]) -> Any:
    """The ``period`` of the innermost task on the path ``at`` into ``root`` (None when there is none)."""
    period, node = None, root
    for part in at:
        if isinstance(node, dict) and "period" in node and "params" in node:
            period = node["period"]
        try:
            node = node[part]
        except (KeyError, IndexError, TypeError):
            break
    return period


def _is_system(value: Any) -> bool:
    if not (type(value).__module__ or "").startswith("control."):
        return False
    from netsim.plant.described import is_control_system

    return is_control_system(value)


def _walk(value: Any, at: list[PathPart], problems: list[Problem], period: Any) -> Any:
    """``value`` (at ``at``) as plain data; ``period`` is the ``period`` of the nearest task around it."""
    if at == ["plant"]:
        value = _plant(value, problems)
    if isinstance(value, dict):
        if "period" in value and "params" in value:
            period = value["period"]
        out = {}
        for key, item in value.items():
            key = plain_copy(key)
            if at == ["baseline", "overrides"] and isinstance(key, str):
                try:  # a baseline override's key is a path of the scenario: a system there is read as at that path
                    child = parse_path(key)
                except ConfigError:
                    child = [*at, key]
            else:
                child = [*at, key]
            out[key] = _walk(item, child, problems, period)
        return out
    if isinstance(value, (list, tuple)):
        return [_walk(item, [*at, i], problems, period) for i, item in enumerate(value)]
    if _is_system(value):
        return _system(value, at, problems, period)
    return plain_copy(value)


def _plant(plant: Any, problems: list[Problem]) -> Any:
    """The ``plant`` entry with a system given as itself, as ``system`` or as ``model`` replaced by its spec."""
    if _is_system(plant):
        plant = {"system": plant}
    elif isinstance(plant, dict) and "system" not in plant and _is_system(plant.get("model")):
        plant = {("system" if k == "model" else k): v for k, v in plant.items()}
    if not (isinstance(plant, dict) and _is_system(plant.get("system"))):
        return plant
    from netsim.plant.described import resolve_plant_object

    try:
        return resolve_plant_object({"plant": plant})["plant"]
    except ConfigError as exc:
        problems.append(Problem("plant", exc.message))
        return {k: v for k, v in plant.items() if k != "system"}


def _system(sys: Any, at: list[PathPart], problems: list[Problem], period: Any) -> Any:
    """A system found at ``at`` (not the plant): a ``model`` becomes ``{A, B, C}``; anywhere else a problem."""
    where = format_path(at)
    if at and at[0] == "plant":
        problems.append(Problem(where, "give the python-control system as the whole plant (plant: sys, or in "
                                       "overrides {'plant': sys}); its matrices then become plant: {type: ss, ...}"))
        return None
    if not at or at[-1] != "model":
        problems.append(Problem(where, f"{_SYSTEMS_GO}; here give numbers (e.g. sys.A.tolist())"))
        return None
    spec, message = _model_spec(sys, period)
    if message:
        problems.append(Problem(where, message))
    return spec


def _model_spec(sys: Any, period: Any) -> tuple[dict[str, Any] | None, str | None]:
    """``{A, B, C}`` of a discrete LTI system given as a controller's model, or the reason it cannot be one."""
    import control
    import numpy as np

    if not isinstance(sys, (control.StateSpace, control.TransferFunction)):
        return None, (f"a model is a discrete linear system (StateSpace or TransferFunction), got "
                      f"{type(sys).__name__}")
    dt = sys.dt
    if dt in (0, None) or dt is False:
        return None, ("the system is continuous (dt = 0), and a model is the discrete model at the task period: "
                      "give control.c2d(sys, period_in_seconds), or leave model out to discretise the plant")
    if isinstance(sys, control.TransferFunction):
        sys = control.ss(sys)  # python-control's realisation, as for a tf plant
    A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (sys.A, sys.B, sys.C, sys.D))
    if D.size and np.any(D != 0):
        return None, ("the system has feed-through (D is not zero); a model is y = C x (the estimators take no "
                      "D): give a strictly proper system")
    period_ns = _period_ns(period)
    if dt is not True and period_ns is not None:
        from netsim.timebase import format_time, from_seconds

        if from_seconds(float(dt)) != period_ns:
            return None, (f"the system's dt = {float(dt)!r} s is not the task period ({format_time(period_ns)}); a "
                          "model is discrete at the task period: discretise at the period")
    return {"A": A.tolist(), "B": B.tolist(), "C": C.tolist()}, None


def _period_ns(period: Any) -> int | None:
    """The task period in nanoseconds when it is given as a time, else None (the schema reports it)."""
    if period is None:
        return None
    from netsim.timebase import parse_time

    try:
        return parse_time(plain_copy(period))
    except (ValueError, TypeError):  # a malformed period: the schema reports it at its path
        return None
