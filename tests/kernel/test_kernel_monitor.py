"""Monitors: the classic three-task priority inversion, with and without inheritance and with the ceiling.

The task set (times in ms, released once; periods of 100 ms keep them from recurring in the 30 ms run):

- L (least urgent) released at 0: execute 1, enter, execute 4 inside, exit, execute 1.
- H (most urgent) released at 2: execute 1, enter, execute 1 inside, exit, execute 1.
- M (middle) released at 4: execute 5, no monitor.

Without inheritance (protocol ``none``): L runs 0-1, enters, runs 1-2 inside; H preempts at 2, runs 2-3 and
blocks on the monitor at 3; L resumes inside 3-4; M arrives at 4 and preempts L (M beats L), runs 4-9; L
finishes its section 9-11 and exits at 11; H gets the monitor and runs 11-12 inside, 12-13 after: H's response
13 - 2 = 11 ms (it waited behind M). M: 9 - 4 = 5 ms. L: 13-14, response 14 ms.

With inheritance (``inherit``): at 3 L inherits H's urgency, runs 3-4 inside and M's arrival at 4 does not
preempt it; L ends its section at 6 (4 ms inside: 1-2, 3-6), exits and drops back; H runs 6-7 inside, 7-8
after: response 8 - 2 = 6 ms. Then M 8-13: 13 - 4 = 9 ms. L 13-14: 14 ms.

With the immediate ceiling (``ceiling``, users L and H): L runs at H's priority from 1 to 5 (its whole section),
so H, released at 2, does not preempt it (equal urgency never preempts); L exits at 5 and drops back; H runs
5-6, 6-7 inside, 7-8 after: again 6 ms, M 8-13 (9 ms), L 13-14 (14 ms).

The same three tasks under ``dm`` (deadlines H 10, M 15, L 20 ms) and ``edf`` (absolute deadlines H 12, M 19,
L 20 ms: L inherits H's deadline 12, which beats M's 19) give the same times.
"""

from __future__ import annotations

from typing import Any

import pytest

from netsim.env import SimEnv
from netsim.errors import SimulationError
from netsim.kernel import Kernel, Monitor
from netsim.kernel.dispatch import NP_RANK
from netsim.kernel.monitor import _NP_RANK
from netsim.timebase import MS


def section(before: int, inside: int, after: int, mon: Monitor | None):
    """A body: execute ``before``, then ``inside`` in the monitor, then ``after`` (ms)."""

    def body(job: Any) -> Any:
        yield job.execute(before * MS)
        if mon is not None:
            yield job.enter(mon)
        yield job.execute(inside * MS)
        if mon is not None:
            yield job.exit(mon)
        yield job.execute(after * MS)

    return body


def inversion(protocol: str, policy: str = "fp") -> dict[str, int]:
    """Run the three tasks; the response time of each (ms)."""
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy=policy)
    mon = Monitor("res", protocol=protocol, users=("L", "H"))
    prio = {"H": 1, "M": 2, "L": 3}
    deadline = {"H": 10, "M": 15, "L": 20}
    for name, offset, body in (("L", 0, section(1, 4, 1, mon)), ("H", 2, section(1, 1, 1, mon)),
                               ("M", 4, section(5, 0, 0, None))):
        k.create_task(name, body, period=100 * MS, offset=offset * MS, priority=prio[name],
                      deadline=deadline[name] * MS)
    env.run(30 * MS)
    return {r.task: r.response // MS for r in k.job_records if r.response is not None}


@pytest.mark.parametrize("policy", ["fp", "dm", "edf"])
def test_without_inheritance_h_waits_behind_m(policy: str) -> None:
    assert inversion("none", policy) == {"H": 11, "M": 5, "L": 14}


@pytest.mark.parametrize("policy", ["fp", "dm", "edf"])
def test_with_inheritance_h_does_not_wait_behind_m(policy: str) -> None:
    assert inversion("inherit", policy) == {"H": 6, "M": 9, "L": 14}


@pytest.mark.parametrize("policy", ["fp", "dm"])
def test_immediate_ceiling(policy: str) -> None:
    assert inversion("ceiling", policy) == {"H": 6, "M": 9, "L": 14}


def test_ceiling_needs_a_static_policy() -> None:
    with pytest.raises(SimulationError, match="static-priority policy"):
        inversion("ceiling", "edf")


def test_ceiling_refuses_a_user_left_out() -> None:
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="fp")
    mon = Monitor("res", protocol="ceiling", users=("L",))
    k.create_task("L", section(1, 1, 0, mon), period=100 * MS, priority=3)
    k.create_task("H", section(0, 1, 0, mon), period=100 * MS, offset=5 * MS, priority=1)
    with pytest.raises(SimulationError, match="add 'H' to the monitor's users"):
        env.run(10 * MS)


def test_transitive_inheritance() -> None:
    """H waits for B held by M2, which waits for A held by L: L runs at H's urgency (M1 cannot preempt it).

    L (prio 4) at 0: enter A, execute 4 inside A. M2 (prio 3) at 1 preempts L: enters B, blocks on A (L inherits
    3) and L resumes. H (prio 1) at 2 preempts L: blocks on B (M2 inherits 1, and through A so does L). M1
    (prio 2) at 3 does not preempt L. L's 4 ms inside A are 0-4 (it is never off the CPU for long): it exits and
    finishes at 4. M2 gets A (at urgency 1, from H), executes 1 inside A 4-5, exits A and B and finishes at 5; H
    gets B, runs 5-6 (finish 6); M1 runs 6-8. Without the transitive step M1 would preempt L at 3 and H would
    finish at 8.
    """
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="fp")
    a, b = Monitor("A"), Monitor("B")

    def low(job: Any) -> Any:
        yield job.enter(a)
        yield job.execute(4 * MS)
        yield job.exit(a)

    def mid2(job: Any) -> Any:
        yield job.enter(b)
        yield job.enter(a)
        yield job.execute(1 * MS)
        yield job.exit(a)
        yield job.exit(b)

    def high(job: Any) -> Any:
        yield job.enter(b)
        yield job.execute(1 * MS)
        yield job.exit(b)

    k.create_task("L", low, period=100 * MS, priority=4)
    k.create_task("M2", mid2, period=100 * MS, offset=1 * MS, priority=3)
    k.create_task("H", high, period=100 * MS, offset=2 * MS, priority=1)
    k.create_task("M1", section(2, 0, 0, None), period=100 * MS, offset=3 * MS, priority=2)
    env.run(20 * MS)
    finish = {r.task: r.finish // MS for r in k.job_records}
    assert finish == {"L": 4, "M2": 5, "H": 6, "M1": 8}


def test_kill_releases_the_monitor_and_drops_inheritance() -> None:
    """L holds the monitor and H waits; killing L at 3 ms hands the monitor to H at once."""
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="fp")
    mon = Monitor("res")
    k.create_task("L", section(0, 10, 0, mon), period=100 * MS, priority=3)
    k.create_task("H", section(0, 1, 0, mon), period=100 * MS, offset=1 * MS, priority=1)
    env.sim.call_at(3 * MS, lambda: k.kill_job(k.tasks["L"].active))  # type: ignore[attr-defined]
    env.run(20 * MS)
    rec = {r.task: r for r in k.job_records}
    assert rec["L"].killed and rec["L"].finish == 3 * MS
    assert rec["H"].finish == 4 * MS  # gets the monitor at 3, 1 ms inside
    assert mon.owner is None and mon.entries == 2 and mon.contended == 1


def test_misuse_is_reported() -> None:
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="fp")
    mon = Monitor("res")

    def twice(job: Any) -> Any:
        yield job.enter(mon)
        yield job.enter(mon)

    k.create_task("T", twice, period=100 * MS, priority=1)
    with pytest.raises(SimulationError, match="not re-entrant"):
        env.run(1 * MS)

    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="fp")

    def stray_exit(job: Any) -> Any:
        yield job.exit(mon)

    k.create_task("T", stray_exit, period=100 * MS, priority=1)
    with pytest.raises(SimulationError, match="without holding it"):
        env.run(1 * MS)
    with pytest.raises(SimulationError, match="protocol must be one of"):
        Monitor("x", protocol="pip")


def test_np_rank_copy_matches_the_dispatcher() -> None:
    assert _NP_RANK == NP_RANK


def test_abort_on_miss_inside_a_monitor_hands_it_over() -> None:
    """L (abort_on_miss, deadline 5 ms) holds the monitor for 10 ms; H waits from 1 ms. L is killed at its
    deadline (5 ms) and H gets the monitor then: 1 ms inside, finish 6 ms."""
    from netsim.kernel import TaskSpec

    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="fp")
    mon = Monitor("res")
    k.add_task(TaskSpec("L", period=100 * MS, deadline=5 * MS, priority=3, abort_on_miss=True),
               section(0, 10, 0, mon))
    k.create_task("H", section(0, 1, 0, mon), period=100 * MS, offset=1 * MS, priority=1)
    env.run(20 * MS)
    rec = {r.task: r for r in k.job_records}
    assert rec["L"].killed and rec["L"].finish == 5 * MS
    assert rec["H"].finish == 6 * MS
