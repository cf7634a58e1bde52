"""Kernel speed (opt in: ``pytest -m benchmark -s tests/benchmarks/test_bench_kernel.py``).

Figures are ratios to a bare simpy loop of the same number of timeouts run in the same process. Times are
CPU times (``time.process_time``), less sensitive than wall time to other processes on a busy machine.
"""

from __future__ import annotations

import time

import pytest
import simpy

from netsim.env import SimEnv
from netsim.kernel import Kernel
from netsim.timebase import MS, S, US

pytestmark = pytest.mark.benchmark


def _bare_simpy(n: int, delay: int = 1000) -> float:
    """CPU time of a simpy process that yields ``n`` timeouts."""
    env = simpy.Environment()

    def proc():
        for _ in range(n):
            yield env.timeout(delay)

    env.process(proc())
    t0 = time.process_time()
    env.run()
    return time.process_time() - t0


def _best(fn, repeat: int = 3) -> float:
    return min(fn() for _ in range(repeat))


def test_bench_kernel_overhead_per_segment_vs_bare_simpy():
    # One task executing n segments back to back (each a preemptible execute) against a bare simpy process
    # yielding n timeouts; runs interleaved, best of 5 each. Nothing else is scheduled, so each segment's end
    # is the loop's next entry: the kernel goes there without a heap entry (EventLoop.advance_if_next, issue
    # 19); before that, each segment cost one entry (x1.95 of a bare timeout on a loaded machine).
    n = 100_000

    def one_task() -> float:
        env = SimEnv()
        k = Kernel(env, "cpu")

        def body(job):
            for _ in range(n):
                yield job.execute(1000)

        k.create_task("t", body, priority=1)
        k.create_job("t")
        t0 = time.process_time()
        env.run(n * 1000 + 1)
        dt = time.process_time() - t0
        assert k.segments == n
        return dt

    bare, kern = [], []
    for _ in range(5):
        bare.append(_bare_simpy(n))
        kern.append(one_task())
    ratio = min(kern) / min(bare)
    print(f"\nbare simpy: {min(bare) / n * 1e6:.2f} us/timeout; kernel, one task: {min(kern) / n * 1e6:.2f} "
          f"us/segment; ratio x{ratio:.2f} (target <= 3; issue 19: <= 2)")
    assert ratio <= 3.0


def test_bench_kernel_preemptive_task_set_per_segment_vs_bare_simpy():
    # RM set (1, 4), (2, 6), (3, 13) ms with preemptions, 20 simulated seconds; per dispatched segment
    # (execution pieces between preemptions) against one bare simpy timeout.
    horizon = 20 * S

    def run() -> tuple[float, int]:
        env = SimEnv()
        k = Kernel(env, "cpu", policy="rm", trace=False)

        def make(c):
            def body(job):
                yield job.execute(c)

            return body

        for name, c, t in (("a", 1, 4), ("b", 2, 6), ("c", 3, 13)):
            k.create_task(name, make(c * MS), period=t * MS)
        t0 = time.process_time()
        env.run(horizon)
        return time.process_time() - t0, k.segments

    kern, segments = min(run() for _ in range(3))
    bare = _best(lambda: _bare_simpy(segments))
    ratio = kern / bare
    print(f"\nRM set, {segments} segments: kernel {kern / segments * 1e6:.2f} us/segment (incl. releases), "
          f"bare simpy {bare / segments * 1e6:.2f} us/timeout; ratio x{ratio:.2f}")
    # at least one segment per job: 20 s / 4 ms + 20 s / 6 ms + 20 s / 13 ms jobs (the count is the benchmark's
    # denominator, so a wrong count would make the ratio meaningless)
    assert segments >= 5000 + 3333 + 1538


def test_bench_100khz_isr_with_1khz_control_task_for_2_s():
    # Issue 3: a 100 kHz handler (1 us) for 2 simulated seconds (200 000 invocations) with a 1 kHz control
    # task (500 us); target under 5 s wall on this machine.
    def run(trace: bool) -> tuple[float, Kernel]:
        env = SimEnv()
        k = Kernel(env, "ctrl", trace=trace)

        def isr(job):
            yield job.execute(1 * US)

        def control(job):
            yield job.execute(500 * US)

        k.create_handler("isr", isr)
        k.create_timer("tick", "isr", period=10 * US)
        k.create_task("control", control, period=1 * MS, priority=1)
        t0 = time.process_time()
        env.run(2 * S)
        return time.process_time() - t0, k

    wall, k = run(True)
    wall_nt, _ = run(False)
    bare = min(_bare_simpy(200_000, 10 * US) for _ in range(3))
    inv = k.handlers["isr"].invocations
    worst = max(r.response for r in k.job_records if r.finish is not None)
    print(f"\n100 kHz ISR + 1 kHz task, 2 s simulated: {wall:.2f} s CPU with trace, {wall_nt:.2f} s without "
          f"({inv} ISR invocations, {k.segments} segments, worst control response {worst / US:.0f} us); "
          f"bare simpy 100 kHz loop {bare:.2f} s (ratio x{wall / bare:.1f}); "
          f"target < 5 s: {'met' if wall < 5 else 'NOT met (machine load?)'}")
    assert inv == 200_001
    assert worst == 556 * US  # RTA: R = 500 + ceil(R/10) * 1 us


def test_bench_100khz_isr_as_periodic_load_with_1khz_control_task_for_2_s():
    # The same node as above with the ISR as a periodic load (Kernel.create_periodic_load): the same control
    # job records, without 200 000 handler invocations. Printed: CPU time of both and the speed-up.
    def run(load: bool) -> tuple[float, Kernel]:
        env = SimEnv()
        k = Kernel(env, "ctrl")

        def isr(job):
            yield job.execute(1 * US)

        def control(job):
            yield job.execute(500 * US)

        if load:
            k.create_periodic_load("isr", period=10 * US, execution=1 * US)
        else:
            k.create_handler("isr", isr)
            k.create_timer("tick", "isr", period=10 * US)
        k.create_task("control", control, period=1 * MS, priority=1)
        t0 = time.process_time()
        env.run(2 * S)
        return time.process_time() - t0, k

    explicit, k_e = run(False)
    analytic, k_a = min((run(True) for _ in range(3)), key=lambda r: r[0])
    print(f"\n100 kHz ISR + 1 kHz task, 2 s simulated: explicit handler {explicit:.2f} s CPU, periodic load "
          f"{analytic * 1e3:.1f} ms CPU (x{explicit / analytic:.0f} faster; {k_a.segments} segments instead of "
          f"{k_e.segments}); utilization {k_a.utilization():.4f} vs {k_e.utilization():.4f}")
    assert [(r.release, r.start, r.finish, r.preemptions, r.cpu_time) for r in k_a.job_records] == \
        [(r.release, r.start, r.finish, r.preemptions, r.cpu_time) for r in k_e.job_records]
    assert max(r.response for r in k_a.job_records if r.finish is not None) == 556 * US  # RTA, as above


def test_bench_100_task_rm_set_jobs_per_second():
    # Issue 19 asks to keep printing this peer figure: 100 periodic tasks under RM (periods log-uniform in
    # 10 ms .. 1 s, total utilization 0.7 split by UUniFast, fixed seed), 10 s simulated, jobs per CPU second.
    # FIELD_NOTES (turn 2): netsim ~48 k jobs/s, SimSo 0.8.5 ~6 k jobs/s on the same set size (SimSo itself is
    # not installed here: that figure is quoted, not measured).
    import numpy as np

    rng = np.random.default_rng(19)
    n, total_u, horizon = 100, 0.7, 10 * S
    periods = [int(round(10 ** rng.uniform(1, 3))) * MS for _ in range(n)]
    utils, rest = [], total_u
    for i in range(1, n):  # UUniFast (Bini & Buttazzo 2005)
        nxt = rest * rng.uniform() ** (1.0 / (n - i))
        utils.append(rest - nxt)
        rest = nxt
    utils.append(rest)

    def run() -> tuple[float, Kernel]:
        env = SimEnv()
        k = Kernel(env, "cpu", policy="rm", trace=False)

        def make(c: int):
            def body(job):
                yield job.execute(c)

            return body

        for i, (t, u) in enumerate(zip(periods, utils)):
            k.create_task(f"t{i}", make(max(1, int(u * t))), period=t)
        t0 = time.process_time()
        env.run(horizon)
        return time.process_time() - t0, k

    wall, k = min((run() for _ in range(3)), key=lambda r: r[0])
    jobs = len(k.job_records)
    print(f"\n100-task RM set, 10 s simulated: {jobs} jobs in {wall:.3f} s CPU = {jobs / wall:,.0f} jobs/s "
          f"(FIELD_NOTES: netsim ~48 k jobs/s, SimSo 0.8.5 ~6 k jobs/s on an idle machine)")
    # one record per release in [0, 10 s] (finished, or unfinished at the end): floor(H / T) + 1 per task
    assert jobs == sum(horizon // t + 1 for t in periods)
