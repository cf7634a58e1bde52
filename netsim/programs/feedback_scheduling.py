"""Feedback scheduling (Cervin et al., "Feedback-feedforward scheduling of control tasks", 2002; TrueTime's
feedback-scheduling example): a scheduler task adapts the periods of control tasks at run time so that their
CPU utilisation follows a set-point, and the controllers follow their new periods.

``feedback_scheduler``
    A periodic task (give it the highest priority) that, at each job, measures for every task in ``tasks`` the
    CPU time its jobs used since the last job, and the mean execution time of its jobs that ended meanwhile; it
    estimates each task's execution time ``C_i`` from those (an exponential filter, weight ``forgetting`` on the
    old estimate), and rescales the nominal
    periods ``h_i`` (the tasks' periods when the scheduler is built) by one factor::

        U_nom = sum_i C_i / h_i        h_i' = h_i * U_nom / setpoint     (so that sum_i C_i / h_i' = setpoint)

    the factor kept within ``[min_scale, max_scale]``. It sets the new periods with ``kernel.set_period``
    (TrueTime's ``ttSetPeriod``) and records the utilisation it measured over the last window as ``record_as``
    (default ``cpu_u``: the tasks' CPU time over the window's length). Its ``metrics()`` report the mean of that
    measure over the second half of the run (``utilization_late``) and the last scale factor (``scale``).
    Whether a new period moves the controller's release already scheduled is that task's ``set_period`` rule:
    ``next_release`` (default, TrueTime 1.5: one new period after its last release) or ``keep_armed``
    (TrueTime 2.0: the armed release stays), :mod:`netsim.kernel.arrivals`.
``adaptive_pid``
    :class:`~netsim.programs.basic.PeriodicController`'s loop (``analog_in``, PID, ``execute``, ``analog_out``)
    whose PID is re-discretised for the task's current period at each job, so a period changed at run time
    changes the controller's ``h`` too.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Generator

from pydantic import Field, model_validator

from netsim.control.pid import PID, PIDParams
from netsim.errors import SimulationError
from netsim.registry import register
from netsim.units import StrictModel

if TYPE_CHECKING:
    from netsim.programs.basic import ProgramContext
    from netsim.kernel.job import Job

__all__ = ["FeedbackScheduler", "AdaptivePID", "retune"]

Body = Generator[Any, Any, None]


def retune(pid: PID, h_s: float) -> None:
    """Re-discretise ``pid`` for sampling period ``h_s`` (seconds), keeping its state (the integral, the
    derivative and the previous measurement): the coefficients :class:`~netsim.control.pid.PID` computes from
    ``h``."""
    pid.h = float(h_s)
    pid.ad = pid.Td / (pid.Td + pid.N * pid.h)
    pid.bd = pid.K * pid.N * pid.ad
    pid.bi = 0.0 if pid.Ti is None else pid.K * pid.h / pid.Ti


class _AdaptivePIDParams(PIDParams):
    channel: str
    output_channel: str
    reference: str | None = None
    record_as: str | None = None


@register("program", "adaptive_pid", "periodic PID (analog_in, PID, execute, analog_out) re-tuned for the task's current period at each job")
class AdaptivePID:
    """A single-node PID loop that follows its task's period (changed at run time by a feedback scheduler)."""

    Params = _AdaptivePIDParams

    def __init__(self, ctx: ProgramContext, params: _AdaptivePIDParams) -> None:
        self.ctx = ctx
        self.p = params
        self.pid = PID.from_params(params, ctx.period)
        self.period = ctx.period
        self.ref = ctx.signal(params.reference) if params.reference else (lambda t: 0.0)

    def __call__(self, job: Job) -> Body:
        p = self.p
        period = job.spec.period
        if period is not None and period != self.period and p.h is None:
            self.period = period
            retune(self.pid, period * 1e-9)
        r = self.ref(job.now)
        y = yield job.analog_in(p.channel)
        u = self.pid.step(r, float(y))
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)
        yield job.analog_out(p.output_channel, u)
        if p.record_as:
            self.ctx.record(p.record_as, u, job.now)


@register("program", "feedback_scheduler", "rescales the periods of `tasks` so that their CPU utilisation follows `setpoint` (ttSetPeriod)")
class FeedbackScheduler:
    """Measures the controlled tasks' execution times and sets their periods so that their utilisation is the
    set-point (see the module notes)."""

    class Params(StrictModel):
        tasks: list[str] = Field(min_length=1)
        setpoint: float = Field(gt=0, le=1)
        forgetting: float = Field(0.5, ge=0, lt=1)
        min_scale: float = Field(0.25, gt=0)
        max_scale: float = Field(8.0, gt=0)
        record_as: str | None = "cpu_u"

        @model_validator(mode="after")
        def _scales(self) -> "FeedbackScheduler.Params":
            if self.min_scale > self.max_scale:
                raise ValueError("min_scale must not exceed max_scale")
            twice = sorted({t for t in self.tasks if self.tasks.count(t) > 1})
            if twice:
                raise ValueError(f"tasks lists {', '.join(repr(t) for t in twice)} more than once; remove the "
                                 "repeats")
            return self

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.ctx = ctx
        self.p = params
        self.nominal: dict[str, int] = {}  # the tasks' periods at the first job (netsim validate checked the names)
        self.estimate: dict[str, float | None] = {}
        self.last: dict[str, tuple[int, int, int]] = {}  # per task: CPU time, that of its ended jobs, ended jobs
        self.t_last: int | None = None
        self.scale = 1.0
        self.samples: list[tuple[int, float]] = []

    def _nominal_periods(self) -> None:
        tasks = self.ctx.kernel.tasks
        for i, name in enumerate(self.p.tasks):
            task = tasks.get(name)
            if task is None or task.spec.period is None or name == self.ctx.task:
                what = "no task" if task is None else "the scheduler itself" if name == self.ctx.task else "not periodic"
                raise SimulationError(f"feedback_scheduler '{self.ctx.node}.{self.ctx.task}': params.tasks[{i}] "
                                      f"'{name}' is {what}; list other periodic tasks of the same node")
            self.nominal[name] = task.spec.period
        self.estimate = dict.fromkeys(self.nominal)

    def _measure(self, now: int) -> float | None:
        """Update the execution-time estimates; the tasks' utilisation over the window since the last job."""
        if not self.nominal:
            self._nominal_periods()
        tasks = self.ctx.kernel.tasks
        used = 0
        for name in self.nominal:
            t = tasks[name]
            cpu0, ended_cpu0, ended0 = self.last.get(name, (0, 0, 0))
            active_cpu = 0 if t.active is None else t.active.cpu_time
            ended = t.released - (0 if t.active is None else 1) - len(t.queue)  # jobs released and ended
            ended_cpu = t.cpu - active_cpu  # the CPU time of those jobs (queued ones have none yet)
            used += t.cpu - cpu0
            if ended > ended0:  # the mean execution time of the jobs ended in the window
                c = (ended_cpu - ended_cpu0) / (ended - ended0)
                old = self.estimate[name]
                self.estimate[name] = c if old is None else self.p.forgetting * old + (1 - self.p.forgetting) * c
            self.last[name] = (t.cpu, ended_cpu, ended)
        t0, self.t_last = self.t_last, now
        return None if t0 is None or now <= t0 else used / (now - t0)

    def __call__(self, job: Job) -> Body:
        p = self.p
        now = job.now
        u = self._measure(now)
        if u is not None:
            self.samples.append((now, u))
            if p.record_as:
                self.ctx.record(p.record_as, u, now)
        known = {n: c for n, c in self.estimate.items() if c is not None}
        if len(known) == len(self.estimate):
            u_nom = sum(c / self.nominal[n] for n, c in known.items())
            self.scale = min(max(u_nom / p.setpoint, p.min_scale), p.max_scale)
            for name, h in self.nominal.items():
                job.kernel.set_period(name, max(1000, int(round(h * self.scale / 1000)) * 1000))  # whole us
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)

    def metrics(self) -> dict[str, float]:
        """``utilization_late``: mean measured utilisation over the second half of the run; ``scale``."""
        if not self.samples:
            return {"utilization_late": float("nan"), "scale": self.scale}
        t_end = self.samples[-1][0]
        late = [u for t, u in self.samples if t >= t_end / 2]
        return {"utilization_late": sum(late) / len(late), "scale": self.scale}
