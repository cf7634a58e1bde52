"""A generic output-feedback controller program (``state_feedback``) and a time-stamping sensor (``sensor``).

``state_feedback`` runs, once per period, the loop of :mod:`netsim.control.interface`: it fuses the measurements
that arrived, computes ``u = law.step(x_hat, r)``, predicts, charges its execution time, then writes the DAC or
sends ``u``. The estimator and the law are named in YAML with their parameters::

    program: state_feedback
    params:
      measurements: [{network: can, sender: sensor, tag: y}]   # or [{channel: y}]
      estimator: {type: kalman, Q: [0, 1e-4], R: 1e-6}         # kalman | steady_state_kalman | luenberger | none
      law: {type: lqr, Q: [1, 0], R: 1e-4}                     # lqr | state_feedback | mpc | pid
      reference: r                                             # a scenario signal (output reference)
      network: can, to: actuator                               # or output_channel: u

*Model.* The estimator and the law use the discrete model ``(A, B, C)`` at the task period: the plant's
continuous matrices discretised once at build (zero-order hold, python-control's ``c2d``), a discrete plant's
own matrices when its ``dt`` is the period, or ``params.model: {A, B, C}`` (required for other plants). ``C``
holds the rows of the measured outputs (each measurement's ``outputs``, by default the ADC channel's output or,
for the only network source, every plant output). With a ``reference``, the law tracks the outputs
``tracked`` (default: the first measured output; ``Cr`` = their rows of ``C``); without one it regulates the
state to zero. Feed-through ``D`` on a measured output is refused (the estimators take ``y = C x``).

*Measurements* come from ADC channels (sampled at the job's start) or from messages on a network, selected by
``sender`` and ``tag`` (both optional): the program takes the messages that match out of the node's inbox for
that network and leaves the others for other programs, so two sensors can feed one estimator. A message from
the ``sensor`` program carries ``{value, t_ns}``: its sample time. ``fuse_at: sample_time`` (default) fuses it at
the controller sample nearest to that time (:func:`~netsim.control.interface.sample_index`): the Kalman filter
re-filters from its history (``history`` samples), the other estimators use only measurements of the current
sample; ``fuse_at: arrival`` fuses it at the sample where it is read (the baseline it is compared against).
A payload without ``t_ns`` (the ``sampler`` program's float) is fused at arrival. When several measurement
sources make up ``y``, a sample is fused once all of them are in; a sample still incomplete when it leaves the
filter's history is dropped (counted as ``partial``). A sample without any measurement is prediction only.

*Execution time.* The task's ``execution:`` is charged after the computation; with an MPC law, ``solve_time``
adds ``{base, per_iteration}`` (a model: ``base + per_iteration * solver iterations``, reproducible) or
``{scale}`` (the measured wall time of the step times ``scale``: runs are then not reproducible), so deadline
misses show in the job table.

*Metrics* (added to every run's metrics as ``control.<node>.<task>.<name>``): ``steps``, ``fused``,
``prediction_only`` (steps without any fused measurement), ``stale``, ``duplicates``, ``partial``, and for MPC
``mpc_fallbacks`` (infeasible QP or solver failure: the saturated LQR law was applied), ``mpc_solver_calls``,
``mpc_solve_time_max_s``.

``sensor`` samples one or more ADC channels, charges its execution time and sends
``{"value": y, "t_ns": sample time}`` (``y`` a float for one channel, a list for several).
"""

from __future__ import annotations

import inspect
import logging
from typing import Any, Generator, Literal

import numpy as np
from pydantic import Field, ValidationInfo, field_validator, model_validator

from netsim.errors import ConfigError
from netsim.programs.basic import Destination, ProgramContext, _destination, _destination_given
from netsim.registry import register
from netsim.units import StrictModel, Time

__all__ = ["StateFeedbackProgram", "Sensor", "MeasurementSource", "design_model"]

log = logging.getLogger(__name__)

Body = Generator[Any, Any, None]


class MeasurementSource(StrictModel):
    """One source of measurements: an ADC ``channel``, or messages on ``network`` from ``sender`` with ``tag``."""

    channel: str | None = None
    network: str | None = None
    sender: str | None = None
    tag: str | None = None
    outputs: list[int | str] | None = Field(None, description="plant outputs it measures (indices or names)")

    @model_validator(mode="after")
    def _one(self) -> "MeasurementSource":
        if (self.channel is None) == (self.network is None):
            raise ValueError("give either 'channel' (an ADC) or 'network' (messages, with optional sender and tag)")
        if self.channel is not None and (self.sender is not None or self.tag is not None):
            raise ValueError("'sender' and 'tag' select messages: they go with 'network', not 'channel'")
        return self


class ModelSpec(StrictModel):
    """A discrete model at the task period given explicitly (instead of the plant's discretisation)."""

    A: list[list[float]]
    B: list[list[float]]
    C: list[list[float]]


class SolveTime(StrictModel):
    """MPC solve time charged as execution time: a model ``base + per_iteration * iterations``, or the measured
    wall time times ``scale``."""

    base: Time = 0
    per_iteration: Time = 0
    scale: float | None = Field(None, gt=0)


class _Params(StrictModel):
    measurements: list[MeasurementSource] = Field(min_length=1)
    estimator: dict[str, Any] = Field(default_factory=lambda: {"type": "kalman"})
    law: dict[str, Any]
    reference: str | None = None
    tracked: list[int | str] | None = None
    model: ModelSpec | None = None
    fuse_at: Literal["sample_time", "arrival"] = "sample_time"
    solve_time: SolveTime | None = None
    output_channel: str | None = None
    output_channels: list[str] | None = None
    network: str | None = None
    to: Destination
    bits: int = Field(80, ge=1, le=10**9)
    priority: int = 0
    tag: str = "u"
    record_as: str | None = None
    record_estimate: str | None = None

    @field_validator("to")
    @classmethod
    def _to(cls, to: str | None, info: ValidationInfo) -> str | None:
        return _destination_given(to, info)

    @field_validator("estimator", "law")
    @classmethod
    def _typed(cls, value: dict[str, Any], info: ValidationInfo) -> dict[str, Any]:
        if not isinstance(value.get("type"), str):
            example = "kalman" if info.field_name == "estimator" else "lqr"
            raise ValueError(f"{info.field_name} needs a 'type' (e.g. 'type: {example}')")
        return value

    @model_validator(mode="after")
    def _output(self) -> "_Params":
        given = [k for k in ("output_channel", "output_channels", "network") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("give one of 'output_channel', 'output_channels' (one DAC per input) or 'network' "
                             "(and 'to') for the control signal" + (f" (got {', '.join(given)})" if given else ""))
        return self

    def nested_params(self) -> list[tuple[str, Any, dict[str, Any]]]:
        """The estimator's and the law's own parameters with their ``Params`` models (``netsim validate``)."""
        out = []
        for field, kind in (("estimator", "estimator"), ("law", "controller")):
            raw = getattr(self, field)
            cls = _part_params(kind, raw.get("type"))
            if cls is not None:
                out.append((field, cls, {k: v for k, v in raw.items() if k != "type"}))
        return out


def _part(kind: str, name: Any) -> Any:
    from netsim import registry

    return registry.lookup(kind, str(name))


def _part_params(kind: str, name: Any) -> Any:
    try:
        obj = _part(kind, name)
    except ConfigError:
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


def _measured_rows(p: _Params, scenario: Any, plant: Any, n_out: int) -> tuple[list[list[int]], list[int]]:
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


def design_model(p: _Params, scenario: Any, plant: Any, period_ns: int) -> tuple[Any, list[list[int]], list[int]]:
    """The :class:`~netsim.control.parts.Design` of a ``state_feedback`` task, with the measured rows.

    Raises
    ------
    ConfigError
        With a message naming the parameter (the caller adds the YAML path).
    """
    from netsim.control.parts import Design

    h = period_ns / 1e9
    if p.model is not None:
        from netsim.control.design_checks import as_input_matrix, as_matrix, check_square

        A = as_matrix("model.A", p.model.A)
        n = check_square("model.A", A)
        B = as_input_matrix("model.B", p.model.B, n)
        Cf = as_matrix("model.C", p.model.C, (None, n))
        Df = np.zeros((Cf.shape[0], B.shape[1]))
    elif plant is None:
        raise ConfigError("model: the scenario has no plant; give the discrete model as 'model: {A, B, C}'")
    elif hasattr(plant, "Ad") and hasattr(plant, "dt_ns"):
        if int(plant.dt_ns) != int(period_ns):
            raise ConfigError(f"model: the discrete plant steps every {plant.dt_ns} ns, the task every {period_ns} ns; "
                              "give the model at the task period as 'model: {A, B, C}', or make the periods equal")
        A, B, Cf, Df = plant.Ad, plant.Bd, plant.Cd, plant.Dd
    elif all(hasattr(plant, k) for k in ("A", "B", "C", "D")):
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
                  Cr=Cr, x0=x0), per, rows


def _located(exc: ConfigError, prefix: str, raw: dict[str, Any]) -> ConfigError:
    """``exc`` at ``prefix`` (plus the field its message starts with, when that is a key of ``raw``)."""
    head = exc.message.split(" ", 1)[0].rstrip(":,")
    field = head if head in raw else None
    return ConfigError(exc.message, path=f"{prefix}.{field}" if field else prefix)


def _check_sources(p: _Params, scenario: Any, node: str | None, pp: str) -> None:
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
                raise ConfigError(f"sender '{src.sender}' is not a node on network '{src.network}' (its nodes: "
                                  f"{', '.join(net.nodes)})", path=f"{at}.sender")


def build_parts(p: _Params, scenario: Any, plant: Any, period_ns: int | None, path: str,
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
    parts: list[Any] = []
    for field, kind in (("estimator", "estimator"), ("law", "controller")):
        raw = getattr(p, field)
        where = f"{pp}.{field}"
        try:
            obj = _part(kind, raw["type"])
        except ConfigError as exc:
            raise ConfigError(exc.message, path=f"{where}.type") from None
        values = {k: v for k, v in raw.items() if k != "type"}
        cls = _part_params(kind, raw["type"])
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


# --------------------------------------------------------------------------------------------- program
@register("program", "state_feedback",
          "measure (ADC or messages by sender/tag), estimator (kalman, luenberger ...), law (lqr, mpc ...), actuate")
class StateFeedbackProgram:
    """The generic output-feedback controller task (see the module docstring)."""

    Params = _Params

    def __init__(self, ctx: ProgramContext, params: _Params) -> None:
        self.ctx = ctx
        self.p = params
        node = ctx.spec
        path = _task_path(ctx)
        plant = ctx.env.components.get("plant")
        self.period = ctx.period
        self.offset = int(getattr(node, "offset", 0) or 0)
        (self.design, self.per_source, self.rows, self.estimator, self.law,
         self.fed_state) = build_parts(params, ctx.scenario, plant, ctx.period, path, ctx.node)
        self.m = self.design.B.shape[1]
        if params.output_channels is not None and len(params.output_channels) != self.m:
            raise ConfigError(f"output_channels must name {self.m} DAC channels (one per input), got "
                              f"{len(params.output_channels)}", path=f"{path}.params.output_channels")
        if params.output_channel is not None and self.m != 1:
            raise ConfigError(f"the model has {self.m} inputs: give 'output_channels' (one DAC per input)",
                              path=f"{path}.params.output_channel")
        self.ref = ctx.signal(params.reference) if params.reference else None
        self.takes_k = "k" in inspect.signature(self.estimator.correct).parameters
        self.history = int(getattr(self.estimator, "history", 0))
        self.p_rows = len(self.rows)
        # where each source's values go in y (positions in the measured rows)
        self.slots = [[self.rows.index(r) for r in rows] for rows in self.per_source]
        self.pending: dict[int, dict[int, np.ndarray]] = {}
        self.u = np.zeros(self.m)
        self.y_last = np.zeros(self.p_rows)
        self.counts = {"steps": 0, "fused": 0, "prediction_only": 0, "stale": 0, "duplicates": 0, "partial": 0}

    # ------------------------------------------------------------------ measurements
    def _k_of(self, t_ns: int | None, k_now: int) -> int:
        if t_ns is None or self.p.fuse_at == "arrival":
            return k_now
        from netsim.control.interface import sample_index

        try:
            k = sample_index(int(t_ns), self.period, self.offset)  # type: ignore[arg-type]
        except ValueError:
            k = 0
        return min(k, k_now)

    def _offer(self, source: int, k: int, value: Any) -> None:
        v = np.asarray(value, dtype=float).reshape(-1)
        want = len(self.slots[source])
        if v.size != want:
            from netsim.errors import SimulationError

            raise SimulationError(f"{self.ctx.node}.{self.ctx.task}: measurement source {source} sent {v.size} "
                                  f"values, it measures {want} outputs")
        got = self.pending.setdefault(k, {})
        if source in got:
            self.counts["duplicates"] += 1
            return
        got[source] = v

    def _take_messages(self, job: Any, k_now: int) -> None:
        kernel = self.ctx.kernel
        for i, src in enumerate(self.p.measurements):
            if src.network is None:
                continue
            inbox = kernel.inbox(src.network)
            if not inbox:
                continue
            keep = []
            while inbox:
                msg = inbox.popleft()
                if (src.sender is not None and msg.sender != src.sender) or (src.tag is not None and msg.tag != src.tag):
                    keep.append(msg)
                    continue
                payload = msg.payload
                t_ns = None
                if isinstance(payload, dict):
                    t_ns = payload.get("t_ns")
                    payload = payload.get("value")
                self._offer(i, self._k_of(t_ns, k_now), payload)
            inbox.extend(keep)

    def _fuse(self, k_now: int) -> bool:
        fused_any = False
        n_src = len(self.p.measurements)
        for k in sorted(self.pending):
            got = self.pending[k]
            if len(got) < n_src:
                if k < k_now - self.history or (not self.takes_k and k < k_now):
                    self.counts["partial"] += 1
                    del self.pending[k]
                continue
            del self.pending[k]
            y = np.empty(self.p_rows)
            for src, v in got.items():
                y[self.slots[src]] = v
            self.y_last = y
            if self.takes_k:
                ok = self.estimator.correct(y, k)
            elif k == k_now:
                ok = self.estimator.correct(y)
            else:
                ok = False
                self.counts["stale"] += 1
            if ok:  # a refused one is counted by the filter (its stale and duplicates counters)
                self.counts["fused"] += 1
                fused_any = fused_any or k == k_now
        return fused_any

    # ------------------------------------------------------------------ the job
    def __call__(self, job: Any) -> Body:
        from netsim.control.interface import sample_index

        p = self.p
        est = self.estimator
        k_now = sample_index(job.release, self.period, self.offset)  # type: ignore[arg-type]
        k_est = getattr(est, "k", None)
        if k_est is not None:
            while est.k < k_now:  # samples whose job has not run (overrun): predicted with the held input
                est.predict(self.u)
        for i, src in enumerate(p.measurements):
            if src.channel is not None:
                y = yield job.analog_in(src.channel)
                self._offer(i, k_now, y)
        self._take_messages(job, k_now)
        if not self._fuse(k_now):
            self.counts["prediction_only"] += 1
        self.counts["steps"] += 1
        r = self.ref(job.now) if self.ref is not None else 0.0
        if self.fed_state:
            u = np.asarray(self.law.step(est.x_hat, r), dtype=float).reshape(-1)
        else:
            u = np.asarray(self.law.step(self.y_last[:1], r), dtype=float).reshape(-1)
        est.predict(u)
        self.u = u
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)
        extra = self._solve_time()
        if extra > 0:
            yield job.execute(extra)
        if p.output_channel is not None:
            yield job.analog_out(p.output_channel, float(u[0]))
        elif p.output_channels is not None:
            for ch, v in zip(p.output_channels, u):
                yield job.analog_out(ch, float(v))
        else:
            payload: Any = float(u[0]) if self.m == 1 else [float(v) for v in u]
            yield job.send(p.network, _destination(p.to), payload, p.bits, priority=p.priority, tag=p.tag)
        if p.record_as:
            self.ctx.record(p.record_as, float(u[0]) if self.m == 1 else u, job.now)
        if p.record_estimate:
            self.ctx.record(p.record_estimate, np.array(est.x_hat, dtype=float), job.now)

    def _solve_time(self) -> int:
        st = self.p.solve_time
        if st is None:
            return 0
        if st.scale is not None:
            return int(round(float(getattr(self.law, "last_solve_time_s", 0.0)) * st.scale * 1e9))
        return int(st.base + st.per_iteration * int(getattr(self.law, "last_iterations", 0)))

    def metrics(self) -> dict[str, float]:
        """The counters of the run (``control.<node>.<task>.<name>`` in the run's metrics)."""
        out = {k: float(v) for k, v in self.counts.items()}
        est = self.estimator
        for key in ("stale", "duplicates"):
            if hasattr(est, key):
                out[key] = float(max(out[key], getattr(est, key)))
        law_metrics = getattr(self.law, "metrics", None)
        if callable(law_metrics):
            m = law_metrics()
            out["mpc_fallbacks"] = float(m.get("fallbacks", 0.0))
            out["mpc_solver_calls"] = float(m.get("solver_calls", 0.0))
            out["mpc_solve_time_max_s"] = float(m.get("solve_time_max_s", 0.0))
            out["mpc_solver_iterations"] = float(m.get("solver_iterations", 0.0))
        return out

    @staticmethod
    def check_design(scenario: Any, node: str, index: int, spec: Any, plant: Any) -> None:
        """What building this task checks, without a kernel (``netsim validate``); raises ConfigError with a path."""
        params = spec.validated_params()
        path = f"nodes.{node}.tasks[{index}]"
        period = spec.period if spec.release_kind == "periodic" else None
        build_parts(params, scenario, plant, period, path, node)


def _task_path(ctx: ProgramContext) -> str:
    scenario = ctx.scenario
    if scenario is not None and ctx.node in getattr(scenario, "nodes", {}):
        for i, t in enumerate(scenario.nodes[ctx.node].tasks):
            if t.name == ctx.task:
                return f"nodes.{ctx.node}.tasks[{i}]"
    return f"nodes.{ctx.node}"


@register("program", "sensor", "analog_in(channels), execute, send {value, t_ns: sample time} to `to` on `network`")
class Sensor:
    """Time-driven sensor whose messages carry their sample time (for ``state_feedback``'s ``fuse_at``)."""

    class Params(StrictModel):
        channels: list[str] = Field(min_length=1)
        network: str
        to: Destination
        bits: int = Field(80, ge=1, le=10**9)
        priority: int = 0
        tag: str = "y"
        after_send: Time = 0
        record_as: str | None = None

        @field_validator("to")
        @classmethod
        def _to(cls, to: str | None, info: ValidationInfo) -> str | None:
            return _destination_given(to, info)

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.ctx = ctx
        self.p = params

    def __call__(self, job: Any) -> Body:
        p = self.p
        t = job.now
        ys = []
        for ch in p.channels:
            ys.append(float((yield job.analog_in(ch))))
        if p.record_as:
            self.ctx.record(p.record_as, ys[0] if len(ys) == 1 else np.array(ys), t)
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)
        value: Any = ys[0] if len(ys) == 1 else ys
        yield job.send(p.network, _destination(p.to), {"value": value, "t_ns": int(t)}, p.bits,
                       priority=p.priority, tag=p.tag)
        if p.after_send:
            yield job.execute(p.after_send)
