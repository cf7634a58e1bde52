"""The control design of a ``state_feedback`` task: the discrete model, the estimator and the law it names.

:func:`build_parts` is what building the program and ``netsim validate`` (through the program's
``check_design``, :mod:`netsim.scenario.static_build`) both run, so validation refuses what a run would refuse,
at the same YAML path. See :mod:`netsim.programs.state_feedback` for the parameters.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from netsim.errors import ConfigError

__all__ = ["MODEL_SOURCES", "build_parts", "design_model", "model_source", "part_params"]


def _part(kind: str, name: Any) -> Any:
    from netsim import registry

    return registry.lookup(kind, str(name))


def part_params(kind: str, name: Any) -> Any:
    try:
        obj = _part(kind, name)
    except ConfigError:  # unknown type: the caller reports it at <field>.type
        return None
    if kind == "controller" and name == "pid":
        from netsim.control.pid import PIDParams

        return PIDParams
    return getattr(obj, "Params", None)


# --------------------------------------------------------------------------------------------- design
def _out_index(plant: Any, key: int | str, where: str) -> int:
    if plant is None:
        if isinstance(key, int):
            return key
        raise ConfigError(f"{where}: output '{key}' is a name, but the model is given without a plant; use indices")
    try:
        return int(plant.output_index(key))
    except Exception:  # noqa: BLE001 - the plant's own lookup error, reworded with the field
        names = getattr(plant, "output_names", None)
        raise ConfigError(f"{where}: the plant has no output {key!r}"
                          + (f" (its outputs: {', '.join(map(str, names))})" if names else "")) from None


def _measured_rows(p: Any, scenario: Any, plant: Any, n_out: int) -> tuple[list[list[int]], list[int]]:
    """Per source, the model output rows it measures; and all measured rows in order of first appearance."""
    per: list[list[int]] = []
    for i, src in enumerate(p.measurements):
        where = f"measurements[{i}].outputs"
        if src.outputs is not None:
            rows = [_out_index(plant, o, where) for o in src.outputs]
        elif src.channel is not None:
            ch = scenario.io.get(src.channel) if scenario is not None else None
            if ch is None or getattr(ch, "type", None) not in ("adc", "encoder"):
                raise ConfigError(f"measurements[{i}].channel: '{src.channel}' is not an adc or encoder channel "
                                  "of the scenario's io")
            rows = [_out_index(plant, ch.output, f"measurements[{i}].channel")]
        elif len(p.measurements) == 1:
            rows = list(range(n_out))
        else:
            raise ConfigError(f"{where}: with several measurement sources, say which plant outputs each one "
                              "measures (e.g. 'outputs: [0]')")
        for r in rows:
            if not 0 <= r < n_out:
                raise ConfigError(f"{where}: output {r} does not exist (the model has {n_out} outputs)")
        per.append(rows)
    order: list[int] = []
    for rows in per:
        for r in rows:
            if r in order:
                raise ConfigError("measurements: output {r} is measured by two sources; give each source its own "
                                  "outputs (fusing redundant sensors needs a model row per sensor)".replace("{r}", str(r)))
            order.append(r)
    return per, order


#: Where a task's discrete model comes from (:func:`model_source`).
MODEL_SOURCES = {
    "params": "params.model (given at the task period)",
    "discrete_plant": "the discrete plant's own matrices (its dt is the task period)",
    "zoh": "the plant's continuous (A, B, C, D) discretised at the task period (zero-order hold, c2d)",
}


def model_source(p: Any, plant: Any) -> str | None:
    """Which branch of :func:`design_model` gives the model: a key of :data:`MODEL_SOURCES`, or ``None``
    (no model: :func:`design_model` refuses the task)."""
    if p.model is not None:
        return "params"
    if plant is None:
        return None
    if hasattr(plant, "Ad") and hasattr(plant, "dt_ns"):
        return "discrete_plant"
    if all(hasattr(plant, k) for k in ("A", "B", "C", "D")):
        return "zoh"
    return None


def design_model(p: Any, scenario: Any, plant: Any, period_ns: int) -> tuple[Any, list[list[int]], list[int]]:
    """The :class:`~netsim.control.parts.Design` of a ``state_feedback`` task, with the measured rows.

    Raises
    ------
    ConfigError
        With a message naming the parameter (the caller adds the YAML path).
    """
    from netsim.control.parts import Design

    h = period_ns / 1e9
    source = model_source(p, plant)
    if source == "params":
        from netsim.control.design_checks import (
            as_input_matrix,
            as_matrix,
            check_square,
        )

        A = as_matrix("model.A", p.model.A)
        n = check_square("model.A", A)
        B = as_input_matrix("model.B", p.model.B, n)
        Cf = as_matrix("model.C", p.model.C, (None, n))
        Df = np.zeros((Cf.shape[0], B.shape[1]))
    elif plant is None:
        raise ConfigError("model: the scenario has no plant; give the discrete model as 'model: {A, B, C}'")
    elif source == "discrete_plant":
        if int(plant.dt_ns) != int(period_ns):
            raise ConfigError(f"model: the discrete plant steps every {plant.dt_ns} ns, the task every {period_ns} ns; "
                              "give the model at the task period as 'model: {A, B, C}', or make the periods equal")
        A, B, Cf, Df = plant.Ad, plant.Bd, plant.Cd, plant.Dd
    elif source == "zoh":
        import control

        sysd = control.c2d(control.ss(plant.A, plant.B, plant.C, plant.D), h, "zoh")
        A, B, Cf, Df = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (sysd.A, sysd.B, sysd.C, sysd.D))
    else:
        raise ConfigError(f"model: the plant ({type(plant).__name__}) has no linear model to discretise; give the "
                          "discrete model at the task period as 'model: {A, B, C}' (e.g. its linearisation)")
    per, rows = _measured_rows(p, scenario, None if p.model is not None else plant, Cf.shape[0])
    if np.any(Df[rows] != 0):
        raise ConfigError("measurements: a measured output has feed-through (D != 0); the estimators take y = C x: "
                          "measure another output or give 'model: {A, B, C}'")
    Cr = None
    if p.reference is not None:
        tracked = [rows[0]] if p.tracked is None else [
            _out_index(None if p.model is not None else plant, t, "tracked") for t in p.tracked]
        for t in tracked:
            if not 0 <= t < Cf.shape[0]:
                raise ConfigError(f"tracked: output {t} does not exist (the model has {Cf.shape[0]} outputs)")
        Cr = Cf[tracked]
    x0 = None
    if scenario is not None and scenario.plant is not None and scenario.plant.x0 is not None and p.model is None:
        x0 = np.asarray(scenario.plant.x0, dtype=float)
    return Design(A=np.asarray(A, float), B=np.asarray(B, float), C=np.asarray(Cf[rows], float), period_s=h,
                  Cr=Cr, x0=x0, nonlinear=_continuous_model(plant, rows)), per, rows


def _continuous_model(plant: Any, rows: list[int]) -> Any:
    """The plant's own model ``(f, h, params)`` when it is a single-mode nonlinear plant, else ``None``."""
    from netsim.control.parts import ContinuousModel

    f, h = getattr(plant, "f", None), getattr(plant, "h", None)
    if not (callable(f) and callable(h)) or len(getattr(plant, "modes", {})) > 1:
        return None
    if getattr(plant, "select_mode", None) is not None or max(rows) >= int(plant.n_outputs):
        return None
    return ContinuousModel(f=f, h=h, params=getattr(plant, "params", None), n_states=int(plant.n_states),
                           n_inputs=int(plant.n_inputs), rows=tuple(rows))


def _located(exc: ConfigError, prefix: str, raw: dict[str, Any]) -> ConfigError:
    """``exc`` at ``prefix`` (plus the field its message starts with, when that is a key of ``raw``)."""
    head = exc.message.split(" ", 1)[0].rstrip(":,")
    field = head if head in raw else None
    return ConfigError(exc.message, path=f"{prefix}.{field}" if field else prefix)


def _check_sources(p: Any, scenario: Any, node: str | None, pp: str) -> None:
    """Each measurement's channel is an io channel, its network one the node is on, its sender a node there."""
    if scenario is None:
        return
    for i, src in enumerate(p.measurements):
        at = f"{pp}.measurements[{i}]"
        if src.channel is not None and src.channel not in scenario.io:
            known = ", ".join(scenario.io) or "none"
            raise ConfigError(f"unknown io channel '{src.channel}' (known: {known})", path=f"{at}.channel")
        if src.network is not None:
            net = scenario.networks.get(src.network)
            if net is None or (node is not None and node not in net.nodes):
                raise ConfigError(f"node '{node}' is not attached to network '{src.network}'", path=f"{at}.network")
            if src.sender is not None and src.sender not in net.nodes:
                from netsim.kernel.task import did_you_mean

                hint = did_you_mean(src.sender, net.nodes)
                hint = hint if hint.startswith("; did you mean") else ""
                raise ConfigError(f"sender '{src.sender}' is not a node on network '{src.network}'{hint} (its nodes: "
                                  f"{', '.join(net.nodes)})", path=f"{at}.sender")


def _check_sender_widths(p: Any, scenario: Any, node: str | None, pp: str, per: list[list[int]]) -> None:
    """Each ``sensor`` task that sends to this node what a network source takes sends one value per output that
    source measures (a run would stop at the first message: "sent 1 values, it measures 2 outputs")."""
    if scenario is None or node is None:
        return
    for i, src in enumerate(p.measurements):
        if src.network is None:
            continue
        senders = [src.sender] if src.sender is not None else list(scenario.networks[src.network].nodes)
        for name in senders:
            for j, task in enumerate(getattr(scenario.nodes.get(name), "tasks", None) or []):
                sp = task.params if isinstance(task.params, dict) else {}
                channels = sp.get("channels")
                if (name == node or task.program != "sensor" or sp.get("network") != src.network
                        or sp.get("to") not in (node, "all") or not isinstance(channels, list)
                        or (src.tag is not None and sp.get("tag", "y") != src.tag)):
                    continue
                if len(channels) != len(per[i]):
                    n = len(channels)
                    raise ConfigError(
                        f"sender '{name}' (task '{task.name}') sends {n} value{'s' if n != 1 else ''} per message "
                        f"(nodes.{name}.tasks[{j}].params.channels), this source measures {len(per[i])} outputs; "
                        "give the sensor one channel per measured output, or list what it measures in 'outputs:'",
                        path=f"{pp}.measurements[{i}]")


def build_parts(p: Any, scenario: Any, plant: Any, period_ns: int | None, path: str,
                node: str | None = None) -> tuple[Any, ...]:
    """Design, estimator, law (and whether the law is fed the state) of a ``state_feedback`` task at ``path``.

    ``netsim validate`` calls this too (:mod:`netsim.scenario.static_build`), so it refuses what build refuses.

    Raises
    ------
    ConfigError
        At ``<path>.params.<field>`` (``...params.law.Q``, ``...params.estimator``, ``...params.measurements``).
    """
    pp = f"{path}.params"
    _check_sources(p, scenario, node, pp)
    if period_ns is None:
        raise ConfigError("state_feedback runs on a sampling grid: give the task a 'period' (release: periodic)",
                          path=f"{path}.period")
    try:
        design, per, rows = design_model(p, scenario, plant, period_ns)
    except ConfigError as exc:
        if exc.path is not None:
            raise
        where, sep, rest = exc.message.partition(": ")
        root = where.split(".", 1)[0].split("[", 1)[0]
        if sep and " " not in where and root in type(p).model_fields:  # "measurements[0].outputs: ..."
            raise ConfigError(rest, path=f"{pp}.{where}") from None
        raise ConfigError(exc.message, path=pp) from None
    _check_sender_widths(p, scenario, node, pp, per)
    parts: list[Any] = []
    for field, kind in (("estimator", "estimator"), ("law", "controller")):
        raw = getattr(p, field)
        where = f"{pp}.{field}"
        try:
            obj = _part(kind, raw["type"])
        except ConfigError as exc:
            raise ConfigError(exc.message, path=f"{where}.type") from None
        values = {k: v for k, v in raw.items() if k != "type"}
        cls = part_params(kind, raw["type"])
        try:
            params = cls.model_validate(values) if cls is not None else values
        except Exception as exc:  # noqa: BLE001 - validate reports these per field; build names the part
            raise ConfigError(f"{field} '{raw['type']}': {exc}", path=where) from None
        try:
            if kind == "controller" and raw["type"] == "pid":
                from netsim.control.pid import PID, PIDLaw

                parts.append((PIDLaw(PID.from_params(params, period_ns)), False))
                continue
            build = getattr(obj, "build", None)
            if not callable(build):
                raise ConfigError(f"{kind} '{raw['type']}' cannot be built from a scenario (it has no build(params, "
                                  "design)); choose another type", path=f"{where}.type")
            made = build(params, design)
            parts.append((made, bool(getattr(obj, "fed_state", True))))
        except ConfigError as exc:
            if exc.path is not None:
                raise
            raise _located(exc, where, values) from None
        except (ValueError, TypeError, np.linalg.LinAlgError) as exc:
            raise ConfigError(f"{field} '{raw['type']}' cannot be designed: {exc}", path=where) from None
    (estimator, _), (law, fed_state) = parts
    return design, per, rows, estimator, law, fed_state


