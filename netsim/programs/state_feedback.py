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
sources make up ``y`` and the estimator is the time-varying Kalman filter with no cross-covariance in ``R``
between the sources (independent sensors), each source's measurement is fused on its own at its sample, with
its rows of ``C`` and its block of ``R``: sensors with their own rates, or a lost packet from one of them,
still correct the estimate (``fused`` counts the parts). With any other estimator a sample is fused once all
sources are in; a sample still incomplete when it leaves the filter's history is dropped (counted as
``partial``). A sample without any measurement is prediction only.

*Execution time.* The task's ``execution:`` is charged after the computation; with an MPC law, ``solve_time``
adds ``{base, per_iteration}`` (a model: ``base + per_iteration * solver iterations``, reproducible) or
``{scale}`` (the measured wall time of the step times ``scale``: runs are then not reproducible), so deadline
misses show in the job table.

*Recording.* ``record_as`` records ``u`` at each job; ``record_estimate`` records the estimate the law used
(``<name>[i]`` per state) at the sample instant (the job's release).

*Metrics* (added to every run's metrics as ``control.<node>.<task>.<name>``): ``steps``, ``fused``,
``prediction_only`` (steps without a measurement of the current sample: lost, missing or still on its way),
``stale``, ``duplicates``, ``partial``, and for MPC
``mpc_fallbacks`` (infeasible QP or solver failure: the saturated LQR law was applied), ``mpc_solver_calls``,
``mpc_solver_iterations`` (wall times are left out: the metrics of a run are reproducible).

The ``sensor`` program (:mod:`netsim.programs.sensor`) samples one or more ADC channels, charges its execution
time and sends ``{"value": y, "t_ns": sample time}``. The design (model, estimator, law) is built by
:mod:`netsim.programs.feedback_design`.
"""

from __future__ import annotations

import inspect
import logging
from collections.abc import Generator
from typing import Any, Literal

import numpy as np
from pydantic import Field, ValidationInfo, field_validator, model_validator

from netsim.errors import ConfigError
from netsim.programs.basic import (
    Destination,
    ProgramContext,
    _destination,
    _destination_given,
)
from netsim.programs.feedback_design import build_parts, part_params
from netsim.registry import register
from netsim.units import StrictModel, Time

__all__ = ["MeasurementSource", "ModelSpec", "SolveTime", "StateFeedbackProgram"]

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
    def _one(self) -> MeasurementSource:
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
            raise ValueError(f"{info.field_name} needs a 'type' (e.g. 'type: {example}')")  # noqa: TRY004 - pydantic reports ValueError
        return value

    @model_validator(mode="after")
    def _output(self) -> _Params:
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
            cls = part_params(kind, raw.get("type"))
            if cls is not None:
                out.append((field, cls, {k: v for k, v in raw.items() if k != "type"}))
        return out


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
        # several sources into a filter that can fuse a part of y (independent sensors): fuse each part as it comes
        est = self.estimator
        self.by_part = (len(self.slots) > 1 and bool(getattr(est, "fuses_partial", False))
                        and bool(est.independent_rows(self.slots)))
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
        if self.by_part:
            return self._fuse_parts(k_now)
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

    def _fuse_parts(self, k_now: int) -> bool:
        """Fuse every source's measurement on its own, at its sample (the time-varying Kalman filter)."""
        fused_any = False
        for k in sorted(self.pending):
            got = self.pending.pop(k)
            for src in sorted(got):
                v = got[src]
                if k == k_now:
                    self.y_last[self.slots[src]] = v
                if self.estimator.correct(v, k, rows=self.slots[src]):
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
        x_hat = np.array(est.x_hat, dtype=float)  # the estimate the law uses (recorded as record_estimate)
        if self.fed_state:
            u = np.asarray(self.law.step(x_hat, r), dtype=float).reshape(-1)
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
            self.ctx.record(p.record_estimate, x_hat, job.release)

    def _solve_time(self) -> int:
        st = self.p.solve_time
        if st is None:
            return 0
        if st.scale is not None:
            return round(float(getattr(self.law, "last_solve_time_s", 0.0)) * st.scale * 1e9)
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
