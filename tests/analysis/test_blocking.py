"""The blocking term B_i (netsim.analysis.blocking) by hand and against simulated worst cases with monitors."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from netsim.analysis.blocking import CriticalSection, blocking_terms
from netsim.analysis.rta import RTATask, response_times
from netsim.env import SimEnv
from netsim.errors import ConfigError
from netsim.kernel import Kernel, Monitor
from netsim.timebase import MS


def test_inheritance_takes_the_smaller_of_the_two_sums() -> None:
    """H (1) uses m1 and m2; M (2) uses nothing; L1 (3): m1 2, m2 5; L2 (4): m2 3.

    For H and M (both monitors have ceiling 1): per task 5 (L1) + 3 (L2) = 8, per monitor 2 (m1) + 5 (m2) = 7,
    so B = 7 under inheritance; one section, the longest, 5 under the ceiling. L1: only L2's section on m2 (3).
    """
    prio = {"H": 1, "M": 2, "L1": 3, "L2": 4}
    cs = [CriticalSection("H", "m1", 1), CriticalSection("H", "m2", 1), CriticalSection("L1", "m1", 2),
          CriticalSection("L1", "m2", 5), CriticalSection("L2", "m2", 3)]
    assert blocking_terms(prio, cs, "inherit") == {"H": 7, "M": 7, "L1": 3, "L2": 0}
    assert blocking_terms(prio, cs, "ceiling") == {"H": 5, "M": 5, "L1": 3, "L2": 0}
    # per task smaller: L1 holds both monitors for 4, L2 nothing of H's -> 4 per task, 4 + 4 per monitor
    cs2 = [CriticalSection("H", "m1", 1), CriticalSection("H", "m2", 1), CriticalSection("L1", "m1", 4),
           CriticalSection("L1", "m2", 4)]
    assert blocking_terms(prio, cs2, "inherit")["H"] == 4


def test_a_monitor_used_only_by_less_urgent_tasks_does_not_block() -> None:
    """m is used by L1 and L2 only: its ceiling is L1's priority 3, so H and M are never blocked by it."""
    prio = {"H": 1, "M": 2, "L1": 3, "L2": 4}
    cs = [CriticalSection("L1", "m", 2), CriticalSection("L2", "m", 6)]
    assert blocking_terms(prio, cs, "inherit") == {"H": 0, "M": 0, "L1": 6, "L2": 0}


def test_refusals() -> None:
    with pytest.raises(ConfigError, match="'inherit' or 'ceiling'"):
        blocking_terms({"a": 1}, [], "none")
    with pytest.raises(ConfigError, match="'b' has no priority"):
        blocking_terms({"a": 1}, [CriticalSection("b", "m", 1)])


# ----------------------------------------------------------------------------------- against the simulation
def _body(before: int, inside: int, after: int, mon: Monitor | None) -> Any:
    def body(job: Any) -> Any:
        yield job.execute(before)
        if mon is not None and inside:
            yield job.enter(mon)
            yield job.execute(inside)
            yield job.exit(mon)
        yield job.execute(after)

    return body


def _simulate(tasks: list[tuple[str, int, int, int, int, int, int]], protocol: str, t_end: int) -> dict[str, int]:
    """Run (name, priority, period, offset, before, inside, after) on one fp kernel sharing one monitor;
    the worst response of each task."""
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="fp")
    users = [t[0] for t in tasks if t[5]]
    mon = Monitor("res", protocol=protocol, users=users)
    for name, prio, period, offset, before, inside, after in tasks:
        k.create_task(name, _body(before, inside, after, mon), period=period, offset=offset, priority=prio)
    env.run(t_end)
    worst: dict[str, int] = {}
    for r in k.job_records:
        if r.response is not None:
            worst[r.task] = max(worst.get(r.task, 0), r.response)
    return worst


def _bounds(tasks: list[tuple[str, int, int, int, int, int, int]], protocol: str) -> dict[str, int | None]:
    prio = {t[0]: t[1] for t in tasks}
    cs = [CriticalSection(t[0], "res", t[5]) for t in tasks if t[5]]
    b = blocking_terms(prio, cs, protocol)
    rta = [RTATask(t[0], t[4] + t[5] + t[6], t[2], priority=t[1], blocking=b[t[0]]) for t in tasks]
    return response_times(rta)


# The inversion set made periodic, phased for the worst case: L (period 60) enters at 1 ms, when H (20) and M
# (30) arrive. RTA with the blocking term (B_H = B_M = 4, L's section; B_L = 0): R_H = 3 + 4 = 7;
# R_M = 5 + 4 + ceil(12/20) 3 = 12; R_L = 6 + ceil(14/20) 3 + ceil(14/30) 5 = 14. The simulation reaches each
# (H: blocked 2-6 while L ends its section, 7 ms; M runs 8-13 after H, 12 ms; L ends at 14).
INVERSION = [("H", 1, 20 * MS, 1 * MS, 1 * MS, 1 * MS, 1 * MS),
             ("M", 2, 30 * MS, 1 * MS, 5 * MS, 0, 0),
             ("L", 3, 60 * MS, 0, 1 * MS, 4 * MS, 1 * MS)]


@pytest.mark.parametrize("protocol", ["inherit", "ceiling"])
def test_the_bound_is_reached_by_the_worst_phasing(protocol: str) -> None:
    bounds = _bounds(INVERSION, protocol)
    assert bounds == {"H": 7 * MS, "M": 12 * MS, "L": 14 * MS}
    assert _simulate(INVERSION, protocol, 120 * MS) == bounds


def test_without_the_blocking_term_the_simulation_exceeds_rta() -> None:
    """RTA without B says H needs 3 ms; the simulated H needs 7 (inherit), or 12 without inheritance: H runs
    1-2 and blocks, M runs 2-7, L's section 7-11, H 11-13."""
    no_b = response_times([RTATask(t[0], t[4] + t[5] + t[6], t[2], priority=t[1]) for t in INVERSION])
    assert no_b["H"] == 3 * MS
    assert _simulate(INVERSION, "inherit", 120 * MS)["H"] == 7 * MS
    assert _simulate(INVERSION, "none", 120 * MS)["H"] == 12 * MS


@pytest.mark.parametrize("protocol", ["inherit", "ceiling"])
def test_random_task_sets_stay_within_the_bound(protocol: str) -> None:
    """40 random sets of 4 tasks (periods 10-40 ms, whole ms, random offsets and sections): the worst simulated
    response over two hyperperiods never exceeds RTA with the blocking term."""
    rng = np.random.default_rng(20)
    checked = 0
    for _ in range(40):
        tasks = []
        for i in range(4):
            period = int(rng.choice([10, 20, 40])) * MS
            before, inside, after = (int(x) * MS // 4 for x in rng.integers(0, 5, size=3))
            if before + inside + after == 0:
                before = MS // 4
            tasks.append((f"t{i}", i + 1, period, int(rng.integers(0, 8)) * MS // 2, before, inside, after))
        bounds = _bounds(tasks, protocol)
        if any(b is None or b > t[2] for b, t in zip(bounds.values(), tasks)):
            continue  # not schedulable: the bound says nothing about later jobs
        worst = _simulate(tasks, protocol, 2 * 40 * MS + 4 * MS)
        for name, w in worst.items():
            assert w <= bounds[name], (tasks, name, w, bounds[name])
        checked += 1
    assert checked >= 15
