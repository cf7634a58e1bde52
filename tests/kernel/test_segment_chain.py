"""Back-to-back CPU segments that nothing can interrupt end without an entry of their own (issue 19).

The kernel asks the event loop (``EventLoop.advance_if_next``) whether a segment's end would be the next entry
processed; then it moves the clock there and goes on, instead of pushing and popping it. Only netsim's own
loop (``run_until``) allows it: simpy's ``sim.run``/``step`` process one entry per step, so they are the
reference here: the same model run both ways must give the same job records, schedule and CPU times.
"""

from __future__ import annotations

from typing import Any

from netsim.env import NORMAL, RECORD, SimEnv
from netsim.kernel import Kernel
from netsim.timebase import MS, US


def _model(chain_segments: int) -> tuple[SimEnv, Kernel]:
    """A background task of many 100 us segments, preempted by a 1 ms / 150 us periodic task, plus a handler
    invoked by a timer every 730 us: segment ends, releases and invocations fall at every possible offset."""
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="fp", context_switch=5 * US)
    log: list[Any] = []

    def background(job: Any) -> Any:
        for i in range(chain_segments):
            yield job.execute(100 * US)
            log.append((job.now, i))  # code between segments runs at each segment's end

    def control(job: Any) -> Any:
        yield job.execute(150 * US)

    def isr(job: Any) -> Any:
        yield job.execute(20 * US)

    k.create_task("background", background, priority=5)
    k.create_task("control", control, period=1 * MS, priority=1)
    k.create_handler("isr", isr)
    k.create_timer("tick", "isr", period=730 * US)
    k.create_job("background")
    k.shared["log"] = log
    return env, k


def _outputs(k: Kernel) -> tuple:
    recs = [(r.task, r.job_id, r.release, r.start, r.finish, r.preemptions, r.cpu_time) for r in k.job_records]
    return recs, list(k.schedule), k.cpu_time, k.segments, k.switches, list(k.shared["log"])


def test_chained_segments_give_what_one_entry_per_segment_gives():
    env_fast, k_fast = _model(200)
    env_fast.run(30 * MS)  # netsim's loop: uninterrupted segment ends chain
    env_ref, k_ref = _model(200)
    env_ref.sim.run(until=30 * MS + 1)  # simpy's loop: one entry per segment end, as before the chaining
    env_ref.finish(30 * MS)
    assert _outputs(k_fast) == _outputs(k_ref)
    # the background job really was preempted and its chain cut (a job record with preemptions), and it ran
    # every segment it could: 200 segments of 100 us end after 20 ms of its own CPU time
    background = [r for r in k_fast.job_records if r.task == "background"]
    assert background[0].preemptions > 0 and background[0].finish is not None
    assert len(k_fast.shared["log"]) == 200
    # and fewer entries went through the heap: at least the ~100 segment ends with nothing else before them
    assert env_fast.sim.events_scheduled() < env_ref.sim.events_scheduled() - 100


def test_one_task_of_back_to_back_segments_needs_no_entry_per_segment():
    env = SimEnv()
    k = Kernel(env, "cpu")

    def body(job: Any) -> Any:
        for _ in range(1000):
            yield job.execute(1000)

    k.create_task("t", body, priority=1)
    k.create_job("t")
    env.run(10 * MS)
    # 1000 segments of 1 us: the job finishes at 1 ms exactly, as one entry per segment would have it
    assert k.segments == 1000
    assert [(r.start, r.finish, r.cpu_time) for r in k.job_records] == [(0, 1000 * 1000, 1000 * 1000)]
    # the start-up check, the release's dispatch and the first segment's end: no entry for the other 999
    assert env.sim.events_scheduled() < 10


def _probe(target: int, other: tuple[int, int] | None, *, at: int = 0, until: int = 30,
           simpy_loop: bool = False) -> tuple[bool, int]:
    """At ``at``, ask ``advance_if_next(target, NORMAL)`` with one other entry ``(time, priority)`` pending;
    returns the answer and the clock right after."""
    env = SimEnv()
    sim = env.sim
    seen: list[tuple[bool, int]] = []

    def probe(_item: tuple) -> None:
        seen.append((sim.advance_if_next(target, NORMAL), sim.now))

    if other is not None:
        sim.call_at(other[0], lambda: None, priority=other[1])
    sim.call_at(at, probe, None)
    if simpy_loop:
        sim.run(until=until + 1)
    else:
        env.run(until)
    return seen[0]


def test_advance_if_next_moves_the_clock_only_when_nothing_comes_first():
    assert _probe(9, (10, NORMAL)) == (True, 9)  # nothing before 9: the clock moves
    assert _probe(10, (10, NORMAL)) == (False, 0)  # an entry of the same time and priority runs first
    assert _probe(20, (20, RECORD)) == (True, 20)  # a NORMAL entry at 20 would run before the RECORD sample
    assert _probe(11, (10, RECORD)) == (False, 0)  # anything earlier runs first
    assert _probe(31, None) == (False, 0)  # beyond the end of the run (env.run(30))
    assert _probe(9, None, simpy_loop=True) == (False, 0)  # simpy's own loop: one entry per step


def test_a_release_with_only_later_rows_due_dispatches_without_a_dispatch_entry():
    # a 1 ms periodic task released together with a RECORD-row sample at every release: the sample runs after
    # the dispatch anyway, so the release dispatches at once (issue 19); before, the pending sample made it
    # push a DISPATCH entry. The sample at each release sees the job already on the CPU, as before.
    env = SimEnv()
    sim = env.sim
    k = Kernel(env, "cpu")
    seen: list[str | None] = []

    def control(job: Any) -> Any:
        yield job.execute(200 * US)

    def sample(_item: tuple) -> None:
        seen.append(k.running)
        if sim.now < 9 * MS:
            sim.call_at(sim.now + 1 * MS, sample, None, priority=RECORD)

    k.create_task("control", control, period=1 * MS, priority=1)
    sim.call_at(0, sample, None, priority=RECORD)
    env.run(10 * MS - 1)
    assert seen == ["control"] * 10
    # response time 200 us: each job starts at its release and runs its one segment
    assert [(r.release, r.start, r.finish) for r in k.job_records] == [
        (i * MS, i * MS, i * MS + 200 * US) for i in range(10)]
    # per period: the release, the segment's end and the sample (plus the start-up check), no DISPATCH entry
    # (which would make it 4 per period)
    assert env.sim.events_scheduled() <= 3 * 10 + 2
