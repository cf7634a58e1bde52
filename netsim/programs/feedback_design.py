"""The control design of a ``state_feedback`` task: the discrete model, the estimator and the law it names.

:func:`task_design` is what building the program runs, in ``netsim validate``'s dry run
(:mod:`netsim.build.dry_run`) as in the run, so validation refuses what a run would refuse, at the same YAML
path. It designs once: the result (a :class:`TaskDesign`: the model, the estimator and the law, never stepped)
is kept on the task's validated parameters, keyed by the numbers it was designed from, and the program of the
run takes it (:func:`claim_design`) instead of solving the Riccati equations again. A second run of the same
loaded scenario designs anew (the first run's objects have run). See
:mod:`netsim.programs.state_feedback` for the parameters.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from netsim.errors import ConfigError

if TYPE_CHECKING:
    from netsim.control.parts import Design
    from netsim.programs.state_feedback import _Params as StateFeedbackParams
    from netsim.scenario.schema import Scenario

__all__ = ["MODEL_SOURCES", "TaskDesign", "as_part", "build_parts", "claim_design", "design_model", "model_source",
           "part_params", "task_design"]


def _part(kind: str, name: Any) -> Any:
    from netsim import registry

    return registry.lookup(kind, str(name))


def part_params(kind: str, name: Any) -> Any:
    """The ``Params`` model of the estimator (``kind`` ``estimator``) or law (``controller``) named ``name``."""
    from netsim.control.parts import BUILTIN_LAWS

    if kind == "controller" and name in BUILTIN_LAWS:
        return BUILTIN_LAWS[name].Params
    try:
        obj = _part(kind, name)
    except ConfigError:  # unknown type: the caller reports it at <field>.type
        return None
    from netsim.registry import params_model

    return params_model(obj)


class _LegacyEstimator:
    """A registered estimator written before :class:`~netsim.control.parts.EstimatorPart`: ``build(params,
    design)``, no declared capabilities (the defaults of :class:`~netsim.control.parts.EstimatorPartBase`)."""

    needs_nonlinear_model = False
    input_delay = "any"
    late_inputs = False
    starts_from_measurement = False

    def __init__(self, obj: Any) -> None:
        self.obj = obj

    def build(self, params: Any, design: Design, rng: np.random.Generator) -> Any:
        return self.obj.build(params, design)


class _LegacyLaw:
    """A registered law written before :class:`~netsim.control.parts.LawPart`: ``build(params, design)``, fed the
    state estimate."""

    fed_state = True

    def __init__(self, obj: Any) -> None:
        self.obj = obj

    def build(self, params: Any, design: Design, rng: np.random.Generator) -> Any:
        return self.obj.build(params, design)


def as_part(kind: str, spec: Any, where: str) -> Any:
    """The :class:`~netsim.control.parts.EstimatorPart` / :class:`~netsim.control.parts.LawPart` of a validated
    block: netsim's own part, a registered one declaring the protocol (a subclass of its base), or an older
    registered one behind an adapter (refused at ``<where>.type`` when it has no ``build``)."""
    from netsim.control.parts import EstimatorPartBase, LawPartBase

    part = spec.part
    base = EstimatorPartBase if kind == "estimator" else LawPartBase
    if isinstance(part, type) and issubclass(part, base):
        return part
    if not callable(getattr(part, "build", None)):  # the one look at an object that declares no protocol
        raise ConfigError(f"{kind} '{spec.type}' cannot be built from a scenario (it has no build(params, "
                          "design)); choose another type", path=f"{where}.type")
    return _LegacyEstimator(part) if kind == "estimator" else _LegacyLaw(part)


# --------------------------------------------------------------------------------------------- design
def _out_index(plant: Any, key: int | str, where: str) -> int:
    """The model output row of ``key`` (an index, or a plant output's name); refused at the YAML path ``where``."""
    if plant is None:
        if isinstance(key, int):
            return key
        raise ConfigError(f"output '{key}' is a name, but the model is given without a plant; use indices", path=where)
    try:
        return int(plant.output_index(key))
    except Exception:  # noqa: BLE001 - the plant's own lookup error, reworded with the field
        names = getattr(plant, "output_names", None)
        raise ConfigError(f"the plant has no output {key!r}"
                          + (f" (its outputs: {', '.join(map(str, names))})" if names else ""), path=where) from None


def _measured_rows(p: StateFeedbackParams, scenario: Scenario | None, plant: Any,
                   n_out: int, pp: str) -> tuple[list[list[int]], list[int]]:
    """Per source, the model output rows it measures; and all measured rows in order of first appearance (refused
    at YAML paths under ``pp``, the task's ``params``)."""
    per: list[list[int]] = []
    for i, src in enumerate(p.measurements):
        where = f"{pp}.measurements[{i}].outputs"
        if src.outputs is not None:
            rows = [_out_index(plant, o, where) for o in src.outputs]
        elif src.channel is not None:
            ch = scenario.io.get(src.channel) if scenario is not None else None
            if ch is None or ch.type == "dac":
                raise ConfigError(f"'{src.channel}' is not an adc or encoder channel of the scenario's io",
                                  path=f"{pp}.measurements[{i}].channel")
            rows = [_out_index(plant, ch.output, f"{pp}.measurements[{i}].channel")]
        elif len(p.measurements) == 1:
            rows = list(range(n_out))
        else:
            raise ConfigError("with several measurement sources, say which plant outputs each one measures (e.g. "
                              "'outputs: [0]')", path=where)
        for r in rows:
            if not 0 <= r < n_out:
                raise ConfigError(f"output {r} does not exist (the model has {n_out} outputs)", path=where)
        per.append(rows)
    order: list[int] = []
    for rows in per:
        for r in rows:
            if r in order:
                raise ConfigError(f"output {r} is measured by two sources; give each source its own outputs (fusing "
                                  "redundant sensors needs a model row per sensor)", path=f"{pp}.measurements")
            order.append(r)
    return per, order


#: Where a task's discrete model comes from (:func:`model_source`).
MODEL_SOURCES = {
    "params": "params.model (given at the task period)",
    "discrete_plant": "the discrete plant's own matrices (its dt is the task period)",
    "zoh": "the plant's continuous (A, B, C, D) discretised at the task period (zero-order hold, c2d)",
}


def model_source(p: StateFeedbackParams, plant: Any) -> str | None:
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


def design_model(p: StateFeedbackParams, scenario: Scenario | None, plant: Any,
                 period_ns: int, pp: str = "params") -> tuple[Design, list[list[int]], list[int]]:
    """The :class:`~netsim.control.parts.Design` of a ``state_feedback`` task, with the measured rows.

    Raises
    ------
    ConfigError
        At the YAML path of the parameter under ``pp`` (the task's ``params``: ``<pp>.measurements[0].outputs``,
        ``<pp>.model``, ``<pp>.tracked``); without a path for a matrix of ``model`` that the checks of
        :mod:`netsim.control.design_checks` refuse (their message names it).
    """
    from netsim.control.parts import Design

    h = period_ns / 1e9
    source = model_source(p, plant)
    if p.model is not None:  # source "params"
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
        raise ConfigError("the scenario has no plant; give the discrete model as 'model: {A, B, C}'", path=f"{pp}.model")
    elif source == "discrete_plant":
        if int(plant.dt_ns) != int(period_ns):
            raise ConfigError(f"the discrete plant steps every {plant.dt_ns} ns, the task every {period_ns} ns; give the "
                              "model at the task period as 'model: {A, B, C}', or make the periods equal",
                              path=f"{pp}.model")
        A, B, Cf, Df = plant.Ad, plant.Bd, plant.Cd, plant.Dd
    elif source == "zoh":
        import control

        sysd = control.c2d(control.ss(plant.A, plant.B, plant.C, plant.D), h, "zoh")
        A, B, Cf, Df = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (sysd.A, sysd.B, sysd.C, sysd.D))
    else:
        raise ConfigError(f"the plant ({type(plant).__name__}) has no linear model to discretise; give the discrete "
                          "model at the task period as 'model: {A, B, C}' (e.g. its linearisation)", path=f"{pp}.model")
    per, rows = _measured_rows(p, scenario, None if p.model is not None else plant, Cf.shape[0], pp)
    if np.any(Df[rows] != 0):
        raise ConfigError("a measured output has feed-through (D != 0); the estimators take y = C x: measure another "
                          "output or give 'model: {A, B, C}'", path=f"{pp}.measurements")
    Cr = None
    if p.reference is not None:
        tracked = [rows[0]] if p.tracked is None else [
            _out_index(None if p.model is not None else plant, t, f"{pp}.tracked") for t in p.tracked]
        for t in tracked:
            if not 0 <= t < Cf.shape[0]:
                raise ConfigError(f"output {t} does not exist (the model has {Cf.shape[0]} outputs)", path=f"{pp}.tracked")
        Cr = Cf[tracked]
    x0 = None
    if scenario is not None and scenario.plant is not None and scenario.plant.x0 is not None and p.model is None:
        x0 = np.asarray(scenario.plant.x0, dtype=float)
    return Design(A=np.asarray(A, float), B=np.asarray(B, float), C=np.asarray(Cf[rows], float), period_s=h,
                  Cr=Cr, x0=x0, nonlinear=_continuous_model(plant, rows), period_ns=int(period_ns)), per, rows


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


def _check_sources(p: StateFeedbackParams, scenario: Scenario | None, node: str | None, pp: str) -> None:
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


def _check_sender_widths(p: StateFeedbackParams, scenario: Scenario | None, node: str | None, pp: str,
                         per: list[list[int]]) -> None:
    """Each ``sensor`` task that sends to this node what a network source takes sends one value per output that
    source measures (a run would stop at the first message: "sent 1 values, it measures 2 outputs")."""
    if scenario is None or node is None:
        return
    for i, src in enumerate(p.measurements):
        if src.network is None:
            continue
        senders = [src.sender] if src.sender is not None else list(scenario.networks[src.network].nodes)
        for name in senders:
            sender = scenario.nodes.get(name)
            for j, task in enumerate(sender.tasks if sender is not None else []):
                sp = task.params
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


def _given_keys(spec: Any) -> set[str]:
    return set(spec.given if isinstance(spec.given, dict) else ()) - {"type"}


@dataclass(eq=False)
class TaskDesign:
    """One ``state_feedback`` task designed: what :func:`task_design` returns and the program runs.

    Attributes
    ----------
    design
        The discrete model the law is designed on (:class:`~netsim.control.parts.Design`).
    per_source, rows
        Per measurement source, the model output rows it measures; all measured rows in order.
    estimator
        The estimator, built on the model of the input the plant holds (``input_delay``, ``applied_input``).
    law, fed_state
        The law; whether it is fed the estimate (else the first measured output).
    inputs
        How the estimator is fed the input (:class:`~netsim.programs.state_feedback_inputs.InputPlan`).
    summaries
        :func:`~netsim.programs.design_summary.summarize` results kept for the run (by their options).
    """

    design: Design
    per_source: list[list[int]]
    rows: list[int]
    estimator: Any
    law: Any
    fed_state: bool
    inputs: Any
    claimed: bool = False
    summaries: dict[Any, Any] = field(default_factory=dict)


def _key(path: str, node: str | None, period_ns: int, design: Design, plan_key: Any) -> str:
    """What a design depends on: the task, its period, the model's numbers and the plant's own model."""
    h = hashlib.sha256(f"{path}|{node}|{period_ns}|{plan_key}".encode())
    for M in (design.A, design.B, design.C, design.Cr, design.x0):
        h.update(b"-" if M is None else np.ascontiguousarray(M, dtype=float).tobytes() + str(M.shape).encode())
    nl = design.nonlinear
    h.update(b"-" if nl is None else repr((nl.f, nl.h, nl.params, nl.rows)).encode())
    return h.hexdigest()


def _model(p: StateFeedbackParams, scenario: Scenario | None, plant: Any, period_ns: int | None, path: str,
           node: str | None) -> tuple[Design, list[list[int]], list[int]]:
    pp = f"{path}.params"
    _check_sources(p, scenario, node, pp)
    if period_ns is None:
        raise ConfigError("state_feedback runs on a sampling grid: give the task a 'period' (release: periodic)",
                          path=f"{path}.period")
    try:
        design, per, rows = design_model(p, scenario, plant, period_ns, pp)
    except ConfigError as exc:
        if exc.path is not None:  # design_model places its own refusals at their parameter's path
            raise
        raise ConfigError(exc.message, path=pp) from None
    _check_sender_widths(p, scenario, node, pp, per)
    return design, per, rows


def _build(kind: str, field_name: str, spec: Any, part: Any, design: Design, rng: np.random.Generator, pp: str,
           wrap: str | None = None, wrap_path: str | None = None) -> Any:
    """``part.build`` with its errors at the YAML path (``wrap``: the message's lead and path for an estimator
    rebuilt on the model of a delayed input)."""
    where = f"{pp}.{field_name}"
    try:
        return part.build(spec.params, design, rng)
    except ConfigError as exc:
        if exc.path is not None:
            raise
        if wrap is not None:
            raise ConfigError(f"{wrap}: {exc.message}", path=wrap_path) from None
        head = exc.message.split(" ", 1)[0].rstrip(":,")
        located = f"{where}.{head}" if head in _given_keys(spec) else where
        raise ConfigError(exc.message, path=located) from None
    except (ValueError, TypeError, np.linalg.LinAlgError) as exc:
        raise ConfigError(f"{field_name} '{spec.type}' cannot be designed: {exc}", path=where) from None


def _design_rng(scenario: Scenario | None, path: str) -> np.random.Generator:
    """The random stream a part's ``build`` gets: ``design:<path>`` of the scenario's seed (the same at
    validation and in the run, so a design made once serves both)."""
    from netsim.env import stream_seed

    seed = scenario.seed if scenario is not None else 0
    return np.random.Generator(np.random.PCG64(stream_seed(seed, f"design:{path}")))


def task_design(p: StateFeedbackParams, scenario: Scenario | None, plant: Any, period_ns: int | None,
                path: str, node: str | None = None) -> TaskDesign:
    """The design of a ``state_feedback`` task at ``path``, made once per model (see the module docstring).

    Raises
    ------
    ConfigError
        At ``<path>.params.<field>`` (``...params.law.Q``, ``...params.estimator``, ``...params.measurements``).
    """
    from netsim.programs.state_feedback_inputs import input_plan

    pp = f"{path}.params"
    design, per, rows = _model(p, scenario, plant, period_ns, path, node)
    est_part = as_part("estimator", p.estimator, f"{pp}.estimator")
    if est_part.needs_nonlinear_model and design.nonlinear is None:
        raise ConfigError(f"type '{p.estimator.type}' filters the plant's own nonlinear model, and this plant has "
                          "none (its model is linear or not given as f and h): use 'kalman' for a linear plant",
                          path=f"{pp}.estimator")
    law_part = as_part("controller", p.law, f"{pp}.law")
    continuous = None
    if p.model is None and model_source(p, plant) == "zoh":  # the plant's continuous (A, B), for the input options
        continuous = (np.atleast_2d(np.asarray(plant.A, dtype=float)), np.asarray(plant.B, dtype=float))
    est_design, plan, wrap = input_plan(p, est_part, design, continuous, int(period_ns), path)  # type: ignore[arg-type]
    key = _key(path, node, int(period_ns), design, plan.key())  # type: ignore[arg-type]
    cache = p.design_cache()
    made = cache.get(key)
    if made is not None:
        return made
    rng = _design_rng(scenario, path)
    estimator = _build("estimator", "estimator", p.estimator, est_part, est_design, rng, pp,
                       *(wrap or (None, None)))
    plan.check_built(estimator, p, path)
    law = _build("controller", "law", p.law, law_part, design, rng, pp)
    made = TaskDesign(design=design, per_source=per, rows=rows, estimator=estimator, law=law,
                      fed_state=bool(law_part.fed_state), inputs=plan)
    cache[key] = made
    return made


def claim_design(p: StateFeedbackParams, scenario: Scenario | None, plant: Any, period_ns: int | None,
                 path: str, node: str | None = None) -> TaskDesign:
    """:func:`task_design` for the program that runs it: the design made at validation when no run has taken
    it yet (its estimator and law have never stepped), else a new one (kept for this run's summaries)."""
    made = task_design(p, scenario, plant, period_ns, path, node)
    if made.claimed:
        cache = p.design_cache()
        for key in [k for k, v in cache.items() if v is made]:
            del cache[key]
        made = task_design(p, scenario, plant, period_ns, path, node)
    made.claimed = True
    return made


def build_parts(p: StateFeedbackParams, scenario: Scenario | None, plant: Any, period_ns: int | None,
                path: str, node: str | None = None) -> tuple[Any, ...]:
    """``(design, per_source, rows, estimator, law, fed_state)`` of :func:`task_design` (its older form)."""
    made = task_design(p, scenario, plant, period_ns, path, node)
    return made.design, made.per_source, made.rows, made.estimator, made.law, made.fed_state
