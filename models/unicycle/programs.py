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
    (feed-forward, LQR on the cart-frame error, or both: :class:`~models.unicycle.design.TrackingLaw`),
    converts it to wheel speeds (eq 2) and sends them to the drive node.
``wheel_drive``
    Event-driven: the newest wheel-speed pair to the two DACs.

Counters (``control.<node>.<task>.*`` in the run's metrics): ``steps``, ``fused_front``, ``fused_side``,
``late`` (fused at an earlier sample than the one being processed), ``stale`` (older than ``history``),
``duplicates`` (a second message for a source and sample already fused: ignored), ``prediction_only``
(samples without any measurement when processed).
"""

from __future__ import annotations

import math
from collections.abc import Generator
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field

from models.unicycle.design import PHASES, Phase, TrackingLaw, Trajectory, make_ekf
from models.unicycle.model import (
    FRONT_OFFSET, HALF_WHEELBASE, P0, Q_REPORT, R_REPORT, WALL_FRONT, WALL_SIDE, WHEEL_RADIUS, XI0_HAT,
    body_to_wheels, measure, measure_jacobian, side_offset,
)
from netsim.programs.basic import ProgramContext, _newest
from netsim.registry import register
from netsim.units import StrictModel, Time

__all__ = ["IrSensor", "UnicycleEkf", "WheelDrive"]

Body = Generator[Any, Any, None]
SOURCES = ("front", "side")


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

    def __call__(self, job: Any) -> Body:
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
    duration: Time
    v: float
    w: float
    front: bool = True
    side: bool = True
    name: str = ""


def _default_phases() -> list[_Phase]:
    return [_Phase(duration=f"{p.duration:g} s", v=p.v, w=p.w, front=p.front, side=p.side, name=p.name)
            for p in PHASES]


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
        side_model: Literal["derived", "printed"] = "derived"
        fuse_at: Literal["sample_time", "arrival"] = "sample_time"
        history: int = Field(50, ge=0)
        start: list[float] = Field(default_factory=lambda: XI0_HAT.tolist(), min_length=3, max_length=3)
        phases: list[_Phase] = Field(default_factory=_default_phases, min_length=1)
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

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.ctx, self.p = ctx, params
        if ctx.period is None:
            raise ValueError("unicycle_ekf must run as a periodic task (give period:)")
        self.period = int(ctx.period)
        self.offset = int(getattr(ctx.spec, "offset", 0) or 0)
        ts = self.period * 1e-9
        p = params
        self.ekf = make_ekf(np.diag(p.Q), p.R, p.x0, np.diag(p.P0), ts, p.side_model)
        phases = [Phase(ph.duration * 1e-9, ph.v, ph.w, ph.front, ph.side, ph.name) for ph in p.phases]
        self.traj = Trajectory(phases, p.start, ts)
        self.law = TrackingLaw(self.traj, p.law, np.diag(p.lqr_Q), np.diag(p.lqr_R), p.a_sign)
        self.off_side = side_offset(p.side_model)
        self.R = np.array(p.R, dtype=float)
        self.k = 0
        self.hist: dict[int, dict[str, Any]] = {0: {"x": self.ekf.x.copy(), "P": self.ekf.P.copy(), "u": None,
                                                    "meas": {}}}
        self.u = np.zeros(2)
        self.counts = {"steps": 0, "fused_front": 0, "fused_side": 0, "late": 0, "stale": 0, "duplicates": 0,
                       "prediction_only": 0}

    # ------------------------------------------------------------------ filter bookkeeping
    def _advance(self) -> None:
        """Predict from sample ``self.k`` to the next with the input stored there (or the held one)."""
        h = self.hist[self.k]
        if h["u"] is None:
            h["u"] = self.u.copy()
        self.ekf.predict(h["u"])
        self.k += 1
        self.hist[self.k] = {"x": self.ekf.x.copy(), "P": self.ekf.P.copy(), "u": None, "meas": {}}

    def _correct(self, k: int) -> int:
        n = 0
        for s in SOURCES:
            y = self.hist[k]["meas"].get(s)
            if y is not None and self.ekf.correct([y], s):
                n += 1
        return n

    def _take(self, k_now: int) -> int:
        """Messages into the history; returns the earliest sample that got a new measurement."""
        kernel = self.ctx.kernel
        earliest = k_now + 1
        for src in self.p.measurements:
            inbox = kernel.inbox(src.network)
            keep = []
            while inbox:
                msg = inbox.popleft()
                if (src.sender is not None and msg.sender != src.sender) or (src.tag is not None and msg.tag != src.tag):
                    keep.append(msg)
                    continue
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
                if src.source in h["meas"]:
                    self.counts["duplicates"] += 1
                    continue
                h["meas"][src.source] = y
                self.counts["fused_" + src.source] += 1
                if k < k_now:
                    self.counts["late"] += 1
                earliest = min(earliest, k)
            inbox.extend(keep)
        return earliest

    def __call__(self, job: Any) -> Body:
        k_now = (int(job.release) - self.offset) // self.period
        while self.k < k_now:  # jobs that did not run: predicted with the held input
            self._advance()
        earliest = self._take(k_now)
        if earliest < k_now:  # re-filter from the prior of the earliest sample that got a late measurement
            h = self.hist[earliest]
            self.ekf.reset(h["x"], h["P"])
            self.ekf.k = self.k = earliest
            while self.k < k_now:
                self._correct(self.k)
                self.ekf.predict(self.hist[self.k]["u"])
                self.k += 1
                self.hist[self.k]["x"], self.hist[self.k]["P"] = self.ekf.x.copy(), self.ekf.P.copy()
        if self._correct(k_now) == 0:
            self.counts["prediction_only"] += 1
        self.counts["steps"] += 1
        x_hat = self.ekf.x.copy()
        v, w = (float(a) for a in self.law.step(k_now, x_hat))
        self.u = np.array([v, w])
        self.hist[k_now]["u"] = self.u.copy()
        if self.p.record:
            self._record(k_now, x_hat)
        self._advance()
        for old in [k for k in self.hist if k < self.k - self.p.history]:
            del self.hist[old]
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)
        wl, wr = body_to_wheels(v, w, self.p.wheel_radius, self.p.half_wheelbase)
        yield job.send(self.p.network, self.p.to, [wl, wr], self.p.bits, priority=self.p.priority, tag=self.p.tag)

    def _record(self, k: int, x_hat: np.ndarray) -> None:
        """Record the posterior, its bands and the predicted readings at the sample instant (floats: the recorder's
        fast path; the same columns as vectors would give, ``xhat[0]`` ...)."""
        t = k * self.period
        P = self.ekf.P
        rec = self.ctx.record
        for i in range(3):
            rec(f"xhat[{i}]", float(x_hat[i]), t)
        for i in range(3):
            rec(f"sd[{i}]", math.sqrt(float(P[i, i])), t)
        rec("detP", float(np.linalg.det(P)), t)
        for i, (off, wall, r) in enumerate(((FRONT_OFFSET, WALL_FRONT, self.R[0]),
                                            (self.off_side, WALL_SIDE, self.R[1]))):
            H = measure_jacobian(x_hat, off, wall)[0]
            rec(f"zhat[{i}]", measure(x_hat, off, wall), t)
            rec(f"zsd[{i}]", math.sqrt(float(H @ P @ H) + r), t)
        ref, _ = self.traj.at(k)
        for i in range(3):
            rec(f"ref[{i}]", float(ref[i]), t)
        rec("vw[0]", float(self.u[0]), t)
        rec("vw[1]", float(self.u[1]), t)

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

    def __call__(self, job: Any) -> Body:
        msg = yield from _newest(job, self.p.network)
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)
        if msg is None:
            return
        wl, wr = msg.payload
        yield job.analog_out(self.p.left, float(wl))
        yield job.analog_out(self.p.right, float(wr))
