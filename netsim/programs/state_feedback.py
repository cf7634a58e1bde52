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
      input_delay: 30 ms                                       # optional: the estimator knows the actuation delay
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
the controller sample nearest to that time (:func:`~netsim.control.interface.sample_index`): the Kalman filters
and ``ekf`` re-filter from their history (``history`` samples); ``luenberger`` and ``none`` keep no history but
fuse a measurement of the previous sample ``k-1`` read at ``k`` by the exact one-step re-filter (``correct_previous``:
``x_hat[k] += A L (y[k-1] - C x_bar[k-1])`` for the current-form observer, ``+= L (y[k-1] - C x_hat[k-1])`` for the
predictor form, ``x_hat[k] = A C^-1 y[k-1] + B u[k-1]`` for ``none``), so a sensor sampling more than half a
period before the controller (its samples map to ``k-1``) still closes the loop; older ones are ``stale``. A
measurement nearer to a sample before the first one (a task ``offset`` over half a period) is ``stale`` too.
``fuse_at: arrival`` fuses it at the sample where it is read (the baseline it is compared against).
A payload without ``t_ns`` (the ``sampler`` program's float) is fused at arrival. When several measurement
sources make up ``y`` and the estimator is the time-varying Kalman filter with no cross-covariance in ``R``
between the sources (independent sensors), each source's measurement is fused on its own at its sample, with
its rows of ``C`` and its block of ``R``: sensors with their own rates, or a lost packet from one of them,
still correct the estimate (``fused`` counts the parts). With any other estimator a sample is fused once all
sources are in; a sample still incomplete when it leaves the filter's history is dropped (counted as
``partial``). A sample without any measurement is prediction only.

*The input the plant holds* (issue 26 section 5). By default the estimator predicts sample ``k + 1`` with the
``u[k]`` just computed, as if it acted on the plant from the sample instant on. Under a network delay it does
not; three options tell the estimator what the plant really gets (the law is unchanged: ``u = law(x_hat[k|k])``):

* ``input_delay: <time>``: a known constant delay ``tau = d h + tau'`` from the instant ``x_hat[k]`` refers to
  (the sample time of the measurement fused at ``k``) until the plant receives ``u[k]``. The estimator is built
  on ``x[k+1] = A x[k] + Gamma0 u[k-d] + Gamma1 u[k-d-1]`` (the exact ZOH split of the period at ``tau'``,
  :func:`~netsim.control.interface.zoh_split`; ``Gamma1 = 0`` when ``tau'`` is 0), the model of Astrom &
  Wittenmark's augmented state ``[x; u[k-d-1] ... u[k-1]]`` with the known delayed inputs taken out of the
  estimated state (:class:`~netsim.control.interface.InputDelayLine`). Any estimator whose ``build`` uses the
  design's ``B`` (kalman, steady_state_kalman, luenberger, none, the registered ones that declare
  ``input_delay = "any"``, :class:`~netsim.control.parts.EstimatorPart`); ``ekf``: whole
  periods only. A fraction of a period needs the plant's continuous linear model.
* ``applied_input: {network, sender, tag}``: the actuator's reports (``actuator`` program, ``report:``) of each
  input it applied and when. The Kalman filter is built on ``x[k+1] = A x[k] + w[k]`` and fed the effect ``w[k]``
  of the input known to be on the plant over period ``k`` (from the task's release ``offset + k h`` to the next;
  after the last report the last reported value is taken
  as held); a report that changes a past period re-predicts from there (``KalmanFilter.revise_inputs``, within
  ``history`` samples). Kalman filters only, with the plant's continuous linear model. With a constant delay and
  reports that arrive before the next sample it gives the estimate of ``input_delay``.
* ``x0_hat: first_measurement``: the estimate starts from the first measurement fused,
  ``x0 + pinv(C) (y - C x0)`` (states measured directly take their value, directions ``C`` does not see keep
  the estimator's ``x0``); the default ``x0`` starts from the estimator's fixed ``x0``.

*Execution time.* The task's ``execution:`` is charged after the computation; with an MPC law, ``solve_time``
adds ``{base, per_iteration}`` (a model: ``base + per_iteration * solver iterations``, reproducible) or
``{scale}`` (the measured wall time of the step times ``scale``: runs are then not reproducible), so deadline
misses show in the job table.

*Recording.* ``record_as`` records ``u`` at each job; ``record_estimate`` records the estimate the law used
(``<name>[i]`` per state) at the sample instant (the job's release).

*Metrics* (added to every run's metrics as ``control.<node>.<task>.<name>``): ``steps``, ``fused``,
``prediction_only`` (steps without a measurement of the current sample: lost, missing or still on its way),
``stale``, ``duplicates``, ``partial``, with ``applied_input`` ``inputs_reported`` and ``inputs_revised`` (past
samples whose input a report changed), and for MPC
``mpc_fallbacks`` (infeasible QP or solver failure: the saturated LQR law was applied), ``mpc_solver_calls``,
``mpc_solver_iterations`` (wall times are left out: the metrics of a run are reproducible).

Why this module is long: it is one program with about twenty-five documented parameters, and its measurement
routing (sources by sender and tag, sample times, parts of y) and job body belong together; the design lives in
:mod:`netsim.programs.feedback_design`, the input options in :mod:`netsim.programs.state_feedback_inputs`.

The ``sensor`` program (:mod:`netsim.programs.sensor`) samples one or more ADC channels, charges its execution
time and sends ``{"value": y, "t_ns": sample time}``. The design (model, estimator, law) is built by
:mod:`netsim.programs.feedback_design`.
"""

from __future__ import annotations

import logging
from collections.abc import Generator
from typing import TYPE_CHECKING, Any, ClassVar, Literal, cast

import numpy as np
from pydantic import Field, PrivateAttr, ValidationInfo, field_validator, model_validator

from netsim.errors import ConfigError
from netsim.programs.basic import (
    Destination,
    ProgramContext,
    _destination,
    _destination_given,
)
from netsim.control.interface import LawBase, SolverReport, capabilities_of
from netsim.control.part_specs import EstimatorSpec, LawSpec
from netsim.programs.feedback_design import claim_design, task_design
from netsim.programs.inbox import take_matching
from netsim.registry import register
from netsim.units import QuietDefaultsModel, StrictModel, Time

if TYPE_CHECKING:
    from netsim.kernel.job import Job

__all__ = ["AppliedInputSource", "MeasurementSource", "ModelSpec", "SolveTime", "StateFeedbackProgram"]

log = logging.getLogger(__name__)

Body = Generator[Any, Any, None]


class MeasurementSource(StrictModel):
    """One source of measurements: an ADC ``channel``, or messages on ``network`` from ``sender`` with ``tag``."""

    channel: str | None = Field(None, description="an adc or encoder channel of the scenario's io, read at the job's "
                                                  "start (give this or 'network')")
    network: str | None = Field(None, description="a network the node is on: measurements are the messages that "
                                                  "arrive there (give this or 'channel')")
    sender: str | None = Field(None, description="take only the messages from this node (with 'network'; default: "
                                                 "any sender)")
    tag: str | None = Field(None, description="take only the messages with this tag (with 'network'; default: any "
                                              "tag)")
    outputs: list[int | str] | None = Field(None, min_length=1, description="plant outputs it measures (indices or "
                                                              "names), in the order of its values; default: the ADC "
                                                              "channel's output, or every output for the only "
                                                              "network source")

    @model_validator(mode="after")
    def _one(self) -> MeasurementSource:
        if (self.channel is None) == (self.network is None):
            raise ValueError("give either 'channel' (an ADC) or 'network' (messages, with optional sender and tag)")
        if self.channel is not None and (self.sender is not None or self.tag is not None):
            raise ValueError("'sender' and 'tag' select messages: they go with 'network', not 'channel'")
        return self


class AppliedInputSource(StrictModel):
    """Where the actuator's reports of the input it applied arrive (``{value, t_ns}`` messages)."""

    network: str = Field(description="the network the reports arrive on (the actuator's 'report.network')")
    sender: str | None = Field(None, description="take only the reports from this node (default: any sender)")
    tag: str | None = Field("applied", description="take only the messages with this tag (the actuator's "
                                                   "'report.tag', default 'applied'; null: any tag)")


class ModelSpec(StrictModel):
    """A discrete model at the task period given explicitly (instead of the plant's discretisation)."""

    A: list[list[float]] = Field(description="state matrix of x[k+1] = A x[k] + B u[k] at the task period (n x n)")
    B: list[list[float]] = Field(description="input matrix at the task period (n x m, plant input units)")
    C: list[list[float]] = Field(description="output matrix of y = C x, one row per plant output (the measured "
                                             "rows are chosen by 'measurements[].outputs')")


class SolveTime(StrictModel):
    """MPC solve time charged as execution time: a model ``base + per_iteration * iterations``, or the measured
    wall time times ``scale``."""

    base: Time = Field(0, description="time charged per MPC step whatever the iterations (e.g. '0.2 ms')")
    per_iteration: Time = Field(0, description="time charged per QP solver iteration (e.g. '10 us')")
    scale: float | None = Field(None, gt=0, description="charge the measured wall time of the step times this "
                                                        "factor instead (runs are then not reproducible)")


class _Params(QuietDefaultsModel):
    measurements: list[MeasurementSource] = Field(min_length=1, description="the sources whose values make up y "
                                                  "(ADC channels or messages), in the order of y's rows")
    estimator: EstimatorSpec = Field(default_factory=lambda: {"type": "kalman"}, validate_default=True,
                                     description="the state estimator: {type: kalman | steady_state_kalman | ekf | "
                                                  "luenberger | none | <registered>, its parameters} (netsim list "
                                                  "estimator <type>)")
    law: LawSpec = Field(description="the control law: {type: lqr | state_feedback | mpc | pid | "
                                            "<registered>, its parameters} (netsim list controller <type>)")
    reference: str | None = Field(None, description="a scenario signal: the reference of the tracked outputs "
                                                    "(default: none, the law regulates the state to zero)")
    tracked: list[int | str] | None = Field(None, description="the plant outputs the reference applies to (indices "
                                                              "or names; default: the first measured output)")
    model: ModelSpec | None = Field(None, description="the discrete model at the task period (default: the plant's "
                                                      "continuous model discretised by ZOH, or a discrete plant's "
                                                      "own matrices)")
    fuse_at: Literal["sample_time", "arrival"] = Field("sample_time", description="sample_time: a message's "
                                                       "measurement is fused at the sample nearest its t_ns (the "
                                                       "Kalman filters and ekf re-filter from their history; "
                                                       "luenberger and none fuse one of the previous sample one "
                                                       "step late, older ones are stale); arrival: at the sample "
                                                       "where it is read")
    input_delay: Time | None = Field(None, description="known delay from the instant x_hat[k] refers to (the "
                                                       "sample time of the measurement fused at k) until the plant "
                                                       "receives u[k], e.g. "
                                                       "'30 ms': the estimator predicts with the input the plant "
                                                       "holds (exact ZOH split of the period; a fraction of a "
                                                       "period needs the plant's continuous linear model). Default: "
                                                       "none, u[k] acts at the sample instant")
    applied_input: AppliedInputSource | None = Field(None, description="the actuator's reports of the input it "
                                                     "applied and when ({value, t_ns} messages, the actuator's "
                                                     "'report'): the estimator re-predicts past periods with the "
                                                     "input really held on the plant (Kalman filters only; needs "
                                                     "the plant's continuous linear model)")
    x0_hat: Literal["x0", "first_measurement"] = Field("x0", description="x0: the estimate starts from the "
                                                       "estimator's x0 (default zeros); first_measurement: at the "
                                                       "first fused measurement the estimate becomes x0 + pinv(C) "
                                                       "(y - C x0) (measured states take their value, unseen "
                                                       "directions keep x0)")
    solve_time: SolveTime | None = Field(None, description="MPC only: the solver's time charged as execution time")
    output_channel: str | None = Field(None, description="the DAC channel u is written to (one input)")
    output_channels: list[str] | None = Field(None, description="one DAC channel per input, in input order")
    network: str | None = Field(None, description="send u on this network (to the node 'to') instead of a DAC")
    to: Destination = Field(None, description="the node u is sent to on 'network' ('all': broadcast)")
    bits: int = Field(80, ge=1, le=10**9, description="size of the control message in bits")
    priority: int = Field(0, description="priority of the control message on the network (medium-specific)")
    tag: str = Field("u", description="tag of the control message")
    record_as: str | None = Field(None, description="record u under this name at each job (at the job's end)")
    record_estimate: str | None = Field(None, description="record the estimate the law used as <name>[i] per state, "
                                                          "at the sample instant (the job's release)")

    #: Fields added in issue 26, left out of the resolved scenario while at their defaults (its text, and the
    #: golden digests of the shipped scenarios, stay as they were).
    _QUIET_DEFAULTS: ClassVar[dict[str, Any]] = {"input_delay": None, "applied_input": None, "x0_hat": "x0"}
    _designs: dict[str, Any] = PrivateAttr(default_factory=dict)

    @field_validator("to")
    @classmethod
    def _to(cls, to: str | None, info: ValidationInfo) -> str | None:
        return _destination_given(to, info)

    @model_validator(mode="after")
    def _output(self) -> _Params:
        given = [k for k in ("output_channel", "output_channels", "network") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("give one of 'output_channel', 'output_channels' (one DAC per input) or 'network' "
                             "(and 'to') for the control signal" + (f" (got {', '.join(given)})" if given else ""))
        return self

    def design_cache(self) -> dict[str, Any]:
        """The task's designs made in this process, by what they were designed from
        (:func:`~netsim.programs.feedback_design.task_design`)."""
        return self._designs


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
        design = task_design if ctx.dry_run else claim_design  # a dry run leaves the design to the run
        made = design(params, ctx.scenario, plant, ctx.period, path, ctx.node)
        self.task_design = made
        self.design, self.per_source, self.rows = made.design, made.per_source, made.rows
        self.law, self.fed_state = made.law, made.fed_state
        self.m = self.design.B.shape[1]
        self.estimator, self.delay_line, self.timeline = made.inputs.runtime(made.estimator, self.m, ctx.period,
                                                                             self.offset)
        self.started = params.x0_hat != "first_measurement"
        if params.output_channels is not None and len(params.output_channels) != self.m:
            raise ConfigError(f"output_channels must name {self.m} DAC channels (one per input), got "
                              f"{len(params.output_channels)}", path=f"{path}.params.output_channels")
        if params.output_channel is not None and self.m != 1:
            raise ConfigError(f"the model has {self.m} inputs: give 'output_channels' (one DAC per input)",
                              path=f"{path}.params.output_channel")
        self.ref = ctx.signal(params.reference) if params.reference else None
        self.caps = capabilities_of(self.estimator)  # declared by the estimator (issue 28: no probing here)
        self.takes_k = self.caps.fuses_at_sample
        self.history = self.caps.history
        reports = isinstance(self.law, LawBase) and self.law.reports_solver
        self.solver = cast(SolverReport, self.law) if reports else None
        self.p_rows = len(self.rows)
        # where each source's values go in y (positions in the measured rows)
        self.slots = [[self.rows.index(r) for r in rows] for rows in self.per_source]
        self.pending: dict[int, dict[int, np.ndarray]] = {}
        # several sources into a filter that can fuse a part of y (independent sensors): fuse each part as it comes
        est = self.estimator
        self.by_part = (len(self.slots) > 1 and self.caps.fuses_partial and bool(est.independent_rows(self.slots)))
        self.u = np.zeros(self.m)
        self.y_last = np.zeros(self.p_rows)
        self.counts = {"steps": 0, "fused": 0, "prediction_only": 0, "stale": 0, "duplicates": 0, "partial": 0}
        if self.timeline is not None:
            self.counts["inputs_reported"] = 0
            self.counts["inputs_revised"] = 0

    # ------------------------------------------------------------------ the input the plant holds
    def _model_input(self, u: np.ndarray, k: int) -> np.ndarray:
        """The input vector of the estimator's model for the period after sample ``k`` (``u``: computed at ``k``)."""
        if self.delay_line is not None:
            return self.delay_line.push(u)
        if self.timeline is not None:
            return self.timeline.effect(k)
        return u

    def _take_reports(self, k_now: int) -> None:
        """Read the actuator's reports of applied inputs; re-predict the periods they change (option (a))."""
        src = self.p.applied_input
        taken = take_matching(self.ctx.kernel.inbox(src.network), src.sender, src.tag)  # type: ignore[union-attr]
        if not taken:
            return
        first: int | None = None
        tl = self.timeline
        for msg in taken:
            payload = msg.payload
            if not isinstance(payload, dict) or "t_ns" not in payload:
                from netsim.errors import SimulationError

                raise SimulationError(f"{self.ctx.node}.{self.ctx.task}: applied_input: a report from "
                                      f"{msg.sender} is not {{value, t_ns}} (set the actuator's 'report')")
            t = int(payload["t_ns"])
            tl.report(t, payload.get("value"))
            self.counts["inputs_reported"] += 1
            first = t if first is None else min(first, t)
        if first is None:
            return
        est = self.estimator
        j0 = max((first - self.offset) // self.period, est.k - self.history, 0)  # type: ignore[operator]
        self.counts["inputs_revised"] += est.revise_inputs({j: tl.effect(j) for j in range(j0, est.k)})
        tl.forget_before(self.offset + (est.k - self.history - 1) * self.period)

    def _start(self, y: np.ndarray, k: int, rows: Any = None) -> None:
        """``x0_hat: first_measurement``: start the estimate from the first measurement fused."""
        self.started = True
        if not self.caps.starts_from:  # 'none': the measurement is the estimate
            return
        if self.takes_k:
            self.estimator.start_from(y, k, rows=rows)
        else:
            self.estimator.start_from(y)

    def _start_previous(self, y: np.ndarray) -> None:
        """``x0_hat: first_measurement`` from a measurement one sample late (estimators without history)."""
        self.started = True
        if self.caps.starts_previous:  # 'none' has none: the measurement is the estimate
            self.estimator.start_previous(y)

    # ------------------------------------------------------------------ measurements
    def _k_of(self, t_ns: int | None, k_now: int) -> int | None:
        """The sample a measurement belongs to; ``None`` for one nearest to a sample before the first."""
        if t_ns is None or self.p.fuse_at == "arrival":
            return k_now
        from netsim.control.interface import sample_index

        try:
            k = sample_index(int(t_ns), self.period, self.offset)  # type: ignore[arg-type]
        except ValueError:  # taken more than half a period before the first sample (an offset over h/2)
            return None
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

    def _take_messages(self, job: Job, k_now: int) -> None:
        kernel = self.ctx.kernel
        for i, src in enumerate(self.p.measurements):
            if src.network is None:
                continue
            for msg in take_matching(kernel.inbox(src.network), src.sender, src.tag):
                payload = msg.payload
                t_ns = None
                if isinstance(payload, dict):
                    t_ns = payload.get("t_ns")
                    payload = payload.get("value")
                k = self._k_of(t_ns, k_now)
                if k is None:
                    self.counts["stale"] += 1
                    continue
                self._offer(i, k, payload)

    def _fuse(self, k_now: int) -> bool:
        if self.by_part:
            return self._fuse_parts(k_now)
        fused_any = False
        n_src = len(self.p.measurements)
        late = self.estimator.correct_previous if self.caps.corrects_previous and not self.takes_k else None
        oldest = k_now - self.history if self.takes_k else k_now - (late is not None)
        for k in sorted(self.pending):
            got = self.pending[k]
            if len(got) < n_src:
                if k < oldest:
                    self.counts["partial"] += 1
                    del self.pending[k]
                continue
            del self.pending[k]
            y = np.empty(self.p_rows)
            for src, v in got.items():
                y[self.slots[src]] = v
            self.y_last = y
            if self.takes_k:
                if not self.started:
                    self._start(y, k)
                ok = self.estimator.correct(y, k)
            elif k == k_now:
                if not self.started:
                    self._start(y, k)
                ok = self.estimator.correct(y)
            elif k == k_now - 1 and late is not None:  # one sample late: the one-step re-filter
                if not self.started:
                    self._start_previous(y)
                ok = late(y)
                if not ok:
                    self.counts["duplicates"] += 1
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
                if not self.started:
                    self._start(v, k, rows=self.slots[src])
                if self.estimator.correct(v, k, rows=self.slots[src]):
                    self.counts["fused"] += 1
                    fused_any = fused_any or k == k_now
        return fused_any

    # ------------------------------------------------------------------ the job
    def __call__(self, job: Job) -> Body:
        from netsim.control.interface import sample_index

        p = self.p
        est = self.estimator
        k_now = sample_index(job.release, self.period, self.offset)  # type: ignore[arg-type]
        if self.takes_k:
            while est.k < k_now:  # samples whose job has not run (overrun): predicted with the held input
                est.predict(self._model_input(self.u, est.k))
        if self.timeline is not None:
            self._take_reports(k_now)
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
        est.predict(self._model_input(u, k_now))
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
            assert p.network is not None  # _Params._output: exactly one of the three outputs is given
            yield job.send(p.network, _destination(p.to), payload, p.bits, priority=p.priority, tag=p.tag)
        if p.record_as:
            self.ctx.record(p.record_as, float(u[0]) if self.m == 1 else u, job.now)
        if p.record_estimate:
            self.ctx.record(p.record_estimate, x_hat, job.release)

    def _solve_time(self) -> int:
        st = self.p.solve_time
        if st is None:
            return 0
        solver = self.solver
        if st.scale is not None:
            return round(float(solver.last_solve_time_s if solver is not None else 0.0) * st.scale * 1e9)
        return int(st.base + st.per_iteration * int(solver.last_iterations if solver is not None else 0))

    def metrics(self) -> dict[str, float]:
        """The counters of the run (``control.<node>.<task>.<name>`` in the run's metrics)."""
        out = {k: float(v) for k, v in self.counts.items()}
        est = self.estimator
        if self.takes_k:  # an estimator fusing at the sample counts what it refused itself
            out["stale"] = float(max(out["stale"], est.stale))
            out["duplicates"] = float(max(out["duplicates"], est.duplicates))
        if self.solver is not None:
            m = self.solver.metrics()
            out["mpc_fallbacks"] = float(m.get("fallbacks", 0.0))
            out["mpc_solver_calls"] = float(m.get("solver_calls", 0.0))
            out["mpc_solver_iterations"] = float(m.get("solver_iterations", 0.0))
        return out


def _task_path(ctx: ProgramContext) -> str:
    scenario = ctx.scenario
    if scenario is not None and ctx.node in getattr(scenario, "nodes", {}):
        for i, t in enumerate(scenario.nodes[ctx.node].tasks):
            if t.name == ctx.task:
                return f"nodes.{ctx.node}.tasks[{i}]"
    return f"nodes.{ctx.node}"
