"""Task programs of the 2WD cart study: the IR sensors, the EKF + tracking-law node, the wheel drive.

These are study-specific because the generic ``state_feedback`` program (issue 16) cannot express them: it
fuses a sample once *all* of its measurement sources are in (here the two IR sensors have their own rates and
are switched off on their own schedules), its estimators work on a linear model, and its laws track an output
reference, not a pose trajectory in the cart frame.

``ir_sensor``
    Periodic: when the time lies in one of its ``on`` windows (the report switches the sensors off in the
    turn), read the ADC channel (the plant's noiseless wall distance plus the ADC's ``noise_std``), execute,
    send ``{value, t_ns: sample time}`` to the estimator. Outside its windows it sends nothing.
``unicycle_ekf``
    Periodic with period ``Ts``: sample ``k`` is the instant ``k Ts`` (the sensors sample on this grid); the
    job released at ``offset + k Ts`` takes the IR messages out of the inbox (selected by sender and tag),
    fuses each at its own sample (``fuse_at: sample_time``; a late one by re-running the filter from the
    stored prior of its sample with the stored inputs, up to ``history`` samples back; a sample already fused
    for that source is never fused again), records the posterior, computes ``(v, w)`` by the tracking law
    (feed-forward, LQR on the cart-frame error, or both: :class:`~netsim.models.unicycle.design.TrackingLaw`),
    converts it to wheel speeds (eq 2) and sends them to the drive node.
``wheel_drive``
    Event-driven: the newest wheel-speed pair to the two DACs.

The filter's ``side_model`` and the ``unicycle`` plant's ``side`` may differ on purpose (a model-mismatch study:
the filter built on the printed eq 6, the cart as the text describes it), but not silently: :func:`side_warning`
is logged and kept in the run's warnings, and ``netsim validate`` reports it (:meth:`UnicycleEkf.scenario_warnings`).

Counters (``control.<node>.<task>.*`` in the run's metrics): ``steps``, ``fused_front``, ``fused_side``,
``late`` (fused at an earlier sample than the one being processed), ``stale`` (older than ``history``),
``duplicates`` (a second message for a source and sample already fused: ignored), ``prediction_only``
(samples without any measurement when processed).
"""

from __future__ import annotations

import math
from collections.abc import Generator, Mapping
from typing import TYPE_CHECKING, Annotated, Any, Literal

import numpy as np
from pydantic import Field, model_serializer, model_validator

from netsim.models.unicycle.design import PHASES, Phase, TrackingLaw, Trajectory
from netsim.models.unicycle.ekf import CartEkf
from netsim.models.unicycle.model import HALF_WHEELBASE, P0, Q_REPORT, R_REPORT, WHEEL_RADIUS, XI0_HAT, body_to_wheels
from netsim.programs.basic import ProgramContext, _newest
from netsim.programs.inbox import take_matching
from netsim.registry import register
from netsim.units import StrictModel, Time

if TYPE_CHECKING:
    from netsim.kernel.job import Job

__all__ = ["IrSensor", "UnicycleEkf", "WheelDrive", "side_warning"]

Body = Generator[Any, Any, None]
SOURCES = ("front", "side")
#: The columns ``unicycle_ekf`` records, in order (its ``_record``).
RECORDED = ("xhat[0]", "xhat[1]", "xhat[2]", "sd[0]", "sd[1]", "sd[2]", "detP", "zhat[0]", "zsd[0]", "zhat[1]",
            "zsd[1]", "ref[0]", "ref[1]", "ref[2]", "vw[0]", "vw[1]")


@register("program", "ir_sensor", "IR distance sensor: in its on-windows, ADC -> send {value, t_ns} to the estimator")
class IrSensor:
    """A time-stamping IR sensor with an on/off schedule (see the module docstring)."""

    class Params(StrictModel):
        channel: str
        network: str
        to: str
        tag: str = "ir"
        bits: int = Field(64, ge=1)
        priority: int = 0
        on: list[tuple[Time, Time]] | None = Field(
            None, description="windows [start, end) in which the sensor measures; null: always")
        record_as: str | None = None

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.ctx, self.p = ctx, params
        self.sent = 0

    def __call__(self, job: Job) -> Body:
        p = self.p
        t = int(job.now)
        if p.on is not None and not any(a <= t < b for a, b in p.on):
            return
        z = float((yield job.analog_in(p.channel)))
        if p.record_as:
            self.ctx.record(p.record_as, z, t)
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)
        self.sent += 1
        yield job.send(p.network, p.to, {"value": z, "t_ns": t}, p.bits, priority=p.priority, tag=p.tag)

    def metrics(self) -> dict[str, float]:
        """``sent``: samples sent."""
        return {"sent": float(self.sent)}


class _Source(StrictModel):
    source: Literal["front", "side"]
    network: str
    sender: str | None = None
    tag: str | None = None


class _Phase(StrictModel):
    """A piece of the reference trajectory: constant ``(v, w)`` for ``duration``.

    It says nothing about the sensors: when each one measures is its ``ir_sensor`` task's ``on`` windows (the
    ``unicycle`` metric reads the blackout from them too). The ``front``/``side`` flags it had did nothing and
    are refused with a message saying so.
    """

    duration: Time
    v: float
    w: float
    name: str = ""

    @model_validator(mode="before")
    @classmethod
    def _no_sensor_flags(cls, data: Any) -> Any:
        if isinstance(data, dict):
            flags = [k for k in ("front", "side") if k in data]
            if flags:
                raise ValueError(
                    f"'{flags[0]}' is not a setting of a trajectory phase (it never switched a sensor); remove it "
                    "and switch the sensor with its own task's 'on' windows "
                    "(nodes.<sensor>.tasks[i].params.on: [[start, end], ...])")
        return data


def _default_phases() -> list[_Phase]:
    return [_Phase.model_validate({"duration": f"{p.duration:g} s", "v": p.v, "w": p.w, "name": p.name}) for p in PHASES]


def side_warning(plant: Any, side_model: str, where: str = "the unicycle_ekf task") -> str | None:
    """The warning for a filter whose ``side_model`` differs from the ``unicycle`` plant's ``side`` (None if they
    agree, or the plant is not the ``unicycle`` model). ``plant`` is the scenario's plant entry (a mapping or the
    validated spec, with ``model`` and ``params``)."""
    get = plant.get if isinstance(plant, Mapping) else (lambda k, d=None: getattr(plant, k, d))
    if get("model") != "unicycle":
        return None
    params = get("params") or {}
    side = params.get("side", "derived") if isinstance(params, Mapping) else getattr(params, "side", "derived")
    if side == side_model:
        return None
    return (f"{where}: the filter's side_model is '{side_model}' but the cart's side sensor is '{side}' "
            f"(plant.params.side): the filter models the side sensor at the other side of the cart; set both to "
            f"the same value unless this mismatch is the experiment")


@register("program", "unicycle_ekf", "2WD cart: EKF with IR sensors fused at their sample times, cart-frame "
          "tracking law, wheel speeds to the drive")
class UnicycleEkf:
    """The estimator and controller node of the study (see the module docstring)."""

    class Params(StrictModel):
        measurements: list[_Source] = Field(min_length=1)
        Q: list[float] = Field(default_factory=lambda: np.diag(Q_REPORT).tolist(), min_length=3, max_length=3)
        R: list[float] = Field(default_factory=lambda: R_REPORT.tolist(), min_length=2, max_length=2,
                               description="variances of the front and side readings [m^2]")
        P0: list[float] = Field(default_factory=lambda: np.diag(P0).tolist(), min_length=3, max_length=3)
        x0: list[float] = Field(default_factory=lambda: XI0_HAT.tolist(), min_length=3, max_length=3)
        side_model: Literal["derived", "printed"] = Field(
            "derived", description="side sensor offset the filter models (as the plant's side); a value other "
                                   "than plant.params.side is warned about")
        fuse_at: Literal["sample_time", "arrival"] = "sample_time"
        history: int = Field(50, ge=0)
        start: list[float] = Field(default_factory=lambda: XI0_HAT.tolist(), min_length=3, max_length=3)
        phases: list[_Phase] = Field(default_factory=_default_phases, min_length=1,
                                     description="reference trajectory: [{duration, v, w, name}, ...]; when the "
                                                 "sensors measure is their own tasks' 'on' windows")
        law: Literal["feedforward", "lqr", "lqr_ff"] = "feedforward"
        # diagonals of Q (each >= 0) and R (each > 0): a negative weight made slycot raise at build (issue 14 B)
        lqr_Q: list[Annotated[float, Field(ge=0)]] = Field(default_factory=lambda: [1e4, 1e4, 100.0], min_length=3,
                                                           max_length=3)
        lqr_R: list[Annotated[float, Field(gt=0)]] = Field(default_factory=lambda: [400.0, 1.0], min_length=2,
                                                          max_length=2)
        a_sign: Literal["derived", "printed"] = "derived"
        wheel_radius: float = Field(WHEEL_RADIUS, gt=0)
        half_wheelbase: float = Field(HALF_WHEELBASE, gt=0)
        network: str
        to: str
        bits: int = Field(64, ge=1)
        priority: int = 1
        tag: str = "u"
        record: bool = True
        input_delay: int = Field(0, ge=0, le=10_000, description="whole task periods between computing a command "
                                 "and the cart applying it: the filter predicts period k with the command of "
                                 "k - input_delay (issue 26 s5; default 0: with the command at once)")

        @model_serializer(mode="wrap")
        def _quiet_input_delay(self, handler: Any) -> Any:
            data = handler(self)  # left out at its default: resolved scenarios (golden digests) stay as they were
            if isinstance(data, dict) and data.get("input_delay") == 0:
                del data["input_delay"]
            return data

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.ctx, self.p = ctx, params
        if ctx.period is None:
            raise ValueError("unicycle_ekf must run as a periodic task (give period:)")
        self.period = int(ctx.period)
        self.offset = int(getattr(ctx.spec, "offset", 0) or 0)
        ts = self.period * 1e-9
        p = params
        self.ekf = CartEkf(p.Q, p.R, p.x0, np.diag(p.P0), ts, p.side_model)
        phases = [Phase(ph.duration * 1e-9, ph.v, ph.w, name=ph.name) for ph in p.phases]
        self.traj = Trajectory(phases, p.start, ts)
        self.law = TrackingLaw(self.traj, p.law, np.diag(p.lqr_Q), np.diag(p.lqr_R), p.a_sign)
        self.k = 0
        # per sample: [prior x, prior P, input (v, w) or None, {source: reading}]; x and P are tuples (CartEkf)
        self.hist: dict[int, list[Any]] = {0: [self.ekf.x, self.ekf.P, None, {}]}
        self._oldest = 0
        self.u = (0.0, 0.0)
        self._line = [(0.0, 0.0)] * params.input_delay  # commands computed but not yet on the cart (input_delay)
        self.counts = {"steps": 0, "fused_front": 0, "fused_side": 0, "late": 0, "stale": 0, "duplicates": 0,
                       "prediction_only": 0}
        self._wheels = (p.wheel_radius, p.half_wheelbase)
        self._sinks: list[tuple[int, Any, Any]] | None = None  # see _record
        #: texts the runner logs and keeps in the run's warnings (meta.json)
        self.build_warnings: list[str] = []
        plant = getattr(ctx.scenario, "plant", None)
        text = None if plant is None else side_warning(plant, p.side_model, f"task {ctx.node}.{ctx.task}")
        if text is not None:
            self.build_warnings.append(text)

    @staticmethod
    def scenario_warnings(scenario: Mapping[str, Any], params: Mapping[str, Any]) -> list[tuple[str, str]]:
        """``netsim validate``'s warnings for this task: ``(key under the task's params, text)``."""
        plant = scenario.get("plant") if isinstance(scenario, Mapping) else None
        if not isinstance(plant, Mapping):
            return []
        text = side_warning(plant, params.get("side_model", "derived"))
        return [] if text is None else [("side_model", text)]

    # ------------------------------------------------------------------ filter bookkeeping
    def _advance(self) -> None:
        """Predict from sample ``self.k`` to the next with the input stored there (or the held one)."""
        h = self.hist[self.k]
        if h[2] is None:
            h[2] = self.u
        self.ekf.predict(*h[2])
        self.k += 1
        self.hist[self.k] = [self.ekf.x, self.ekf.P, None, {}]

    def _correct(self, k: int) -> int:
        meas = self.hist[k][3]
        if not meas:
            return 0
        for s in SOURCES:
            y = meas.get(s)
            if y is not None:
                self.ekf.correct(y, s)
        return len(meas)

    def _take(self, k_now: int) -> int:
        """Messages into the history; returns the earliest sample that got a new measurement."""
        kernel = self.ctx.kernel
        earliest = k_now + 1
        for src in self.p.measurements:
            for msg in take_matching(kernel.inbox(src.network), src.sender, src.tag):
                pl = msg.payload
                y, t = (float(pl["value"]), pl.get("t_ns")) if isinstance(pl, dict) else (float(pl), None)
                if t is None or self.p.fuse_at == "arrival":
                    k = k_now
                else:
                    k = min(k_now, (int(t) + self.period // 2) // self.period)
                h = self.hist.get(k)
                if h is None:
                    self.counts["stale"] += 1
                    continue
                if src.source in h[3]:
                    self.counts["duplicates"] += 1
                    continue
                h[3][src.source] = y
                self.counts["fused_" + src.source] += 1
                if k < k_now:
                    self.counts["late"] += 1
                earliest = min(earliest, k)
        return earliest

    def __call__(self, job: Job) -> Body:
        k_now = (int(job.release) - self.offset) // self.period
        while self.k < k_now:  # jobs that did not run: predicted with the held input
            self._advance()
        earliest = self._take(k_now)
        ekf, hist = self.ekf, self.hist
        if earliest < k_now:  # re-filter from the prior of the earliest sample that got a late measurement
            h = hist[earliest]
            ekf.reset(h[0], h[1])
            ekf.k = self.k = earliest
            while self.k < k_now:
                h = hist[self.k]
                self._correct(self.k)
                ekf.predict(*h[2])
                self.k += 1
                h = hist[self.k]
                h[0], h[1] = ekf.x, ekf.P
        if self._correct(k_now) == 0:
            self.counts["prediction_only"] += 1
        self.counts["steps"] += 1
        v, w = self.law.step(k_now, ekf.x)
        self.u = (v, w)
        if self._line:  # input_delay: period k_now is predicted with the command of k_now - input_delay
            self._line.append(self.u)
            hist[k_now][2] = self._line.pop(0)
        else:
            hist[k_now][2] = self.u
        if self.p.record:
            self._record(k_now)
        self._advance()
        while self._oldest < self.k - self.p.history:
            hist.pop(self._oldest, None)
            self._oldest += 1
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)
        wl, wr = body_to_wheels(v, w, *self._wheels)
        yield job.send(self.p.network, self.p.to, [wl, wr], self.p.bits, priority=self.p.priority, tag=self.p.tag)

    def _record(self, k: int) -> None:
        """Record the posterior, its bands and the predicted readings at the sample instant (the columns
        ``xhat[0]`` ..., as vectors would give).

        The first call records through ``ctx.record`` (which creates the recorder's series of the wanted columns);
        later calls append to those series directly (the recorder's public ``times``/``values``), the same samples
        without the per-call name checks, which took a tenth of a run."""
        ekf = self.ekf
        x, P = ekf.x, ekf.P
        zf, sf = ekf.predicted("front")
        zs, ss = ekf.predicted("side")
        ref = self.law.ref_at(k)
        row = (x[0], x[1], x[2], math.sqrt(P[0]), math.sqrt(P[3]), math.sqrt(P[5]), ekf.det(), zf, sf, zs, ss,
               ref[0], ref[1], ref[2], self.u[0], self.u[1])
        t = k * self.period
        sinks = self._sinks
        if sinks is None:
            rec = self.ctx.record
            for name, v in zip(RECORDED, row):
                rec(name, float(v), t)
            recorder = getattr(self.ctx.env, "recorder", None)
            times = getattr(recorder, "times", {})
            values = getattr(recorder, "values", {})
            self._sinks = [(i, times[n].append, values[n].append) for i, n in enumerate(RECORDED)
                           if n in times and n in values]
            return
        for i, t_app, v_app in sinks:
            t_app(t)
            v_app(float(row[i]))

    def metrics(self) -> dict[str, float]:
        """The counters of the run (module docstring)."""
        return {k: float(v) for k, v in self.counts.items()}


@register("program", "wheel_drive", "2WD cart drive: the newest [omega_L, omega_R] message to two DACs")
class WheelDrive:
    """Event-driven drive node: writes the two wheel-speed DACs."""

    class Params(StrictModel):
        network: str
        left: str
        right: str

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.ctx, self.p = ctx, params

    def __call__(self, job: Job) -> Body:
        msg = yield from _newest(job, self.p.network)
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)
        if msg is None:
            return
        wl, wr = msg.payload
        yield job.analog_out(self.p.left, float(wl))
        yield job.analog_out(self.p.right, float(wr))
