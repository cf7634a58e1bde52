"""The time-triggered dispatcher (netsim.kernel.timetable, policy 'tt') against schedules worked out by hand.

Times in ms. The table of every test: cycle 10; A at 0 (length 3), B at 4 (length 2), A again at 7 (length 2).
"""

from __future__ import annotations

import pytest

from netsim.env import SimEnv
from netsim.errors import BuildError
from netsim.kernel import Kernel
from netsim.kernel.timetable import create_timetable
from netsim.timebase import MS, US

TABLE = [(0, "A", 3 * MS), (4 * MS, "B", 2 * MS), (7 * MS, "A", 2 * MS)]


def _exec(ns):
    def body(job):
        yield job.execute(ns)

    return body


def _run(b_exec, overrun="continue", until=20):
    env = SimEnv(seed=1)
    k = Kernel(env, "ecu", policy="tt")
    k.create_task("A", _exec(2 * MS))
    k.create_task("B", _exec(b_exec))
    k.create_task("C", _exec(3 * MS), period=10 * MS)  # not in the table: runs in the gaps
    table = create_timetable(k, 10 * MS, TABLE, overrun=overrun)
    env.run(until * MS)
    rows = {}
    for r in k.job_records:
        if r.finish is None:  # still running or waiting when the run ends
            continue
        rows.setdefault(r.task, []).append((r.release / MS, None if r.start is None else r.start / MS,
                                            None if r.finish is None else r.finish / MS, r.deadline_met, r.killed))
    return rows, table


def test_slots_activate_their_tasks_every_cycle_and_others_run_in_the_gaps():
    rows, table = _run(1 * MS)
    # cycle 0: A activated at 0 runs 0-2 (deadline = slot end 3); C (released 0, background) runs 2-4, is
    # preempted by B's activation at 4; B runs 4-5 (slot end 6); C resumes 5-6 (3 ms in all); A at 7 runs 7-9
    # (slot end 9). Cycle 1 is the same shifted by 10.
    assert rows["A"] == [(0, 0, 2, True, False), (7, 7, 9, True, False), (10, 10, 12, True, False),
                         (17, 17, 19, True, False)]
    assert rows["B"] == [(4, 4, 5, True, False), (14, 14, 15, True, False)]
    assert rows["C"] == [(0, 2, 6, True, False), (10, 12, 16, True, False)]
    # activations at 0, 4, 7, 10, 14, 17 and 20 (the run's last instant is included)
    assert table.activations == 7 and table.overruns == 0


def test_a_job_overrunning_its_slot_is_a_deadline_violation_and_continues_by_default():
    rows, table = _run(2500 * US, until=10)
    # B needs 2.5 ms in a 2 ms slot: it runs 4-6.5, its slot ended at 6 (a deadline miss, counted at 6); C then
    # runs 6.5-7 (1 ms left after 2-4), A's activation at 7 preempts it (the latest activation first): A 7-9,
    # C 9-9.5.
    assert rows["B"] == [(4, 4, 6.5, False, False)]
    assert rows["A"][1] == (7, 7, 9, True, False)
    assert rows["C"] == [(0, 2, 9.5, True, False)]
    assert table.overruns == 1


def test_overrun_kill_ends_the_job_at_its_slot_end():
    rows, table = _run(2500 * US, overrun="kill", until=10)
    # B is killed at its slot's end (6) after 2 ms; C runs 6-7 and finishes (1 ms left); A 7-9.
    assert rows["B"] == [(4, 4, 6, False, True)]
    assert rows["C"] == [(0, 2, 7, True, False)]
    assert rows["A"][1] == (7, 7, 9, True, False)
    assert table.overruns == 1


def test_a_later_activation_preempts_an_earlier_overrunning_one():
    # B overruns by far (5 ms): it runs 4-7, A's activation at 7 preempts it (A 7-9), B resumes 9-10, the next
    # cycle's A (10) preempts it again (A 10-12), B resumes 12-13 (done at 13, deadline 6 missed); C, background,
    # runs 2-4 and only after B: 13-14, past its own deadline 10
    rows, _ = _run(5 * MS, until=15)
    assert rows["B"][0] == (4, 4, 13, False, False)
    assert rows["C"][0] == (0, 2, 14, False, False)
    assert rows["A"][:3] == [(0, 0, 2, True, False), (7, 7, 9, True, False), (10, 10, 12, True, False)]


def _kernel(policy="tt", **task_kw):
    k = Kernel(SimEnv(seed=1), "ecu", policy=policy)
    k.create_task("A", _exec(1 * MS), **task_kw)
    k.create_task("B", _exec(1 * MS))
    return k


@pytest.mark.parametrize("kernel_kw, cycle, slots, path, match", [
    ({}, 10 * MS, [(0, "Z", 1 * MS)], "timetable.slots[0].task", "no task 'Z'"),
    ({}, 10 * MS, [(9 * MS, "A", 2 * MS)], "timetable.slots[0].length", "after the cycle's end"),
    ({}, 10 * MS, [(0, "A", 3 * MS), (2 * MS, "B", 1 * MS)], "timetable.slots[1].start", "overlaps the slot of 'A'"),
    ({"wcet": 2 * MS}, 10 * MS, [(0, "A", 1 * MS)], "timetable.slots[0].length", "shorter than the task's wcet"),
    ({"period": 10 * MS}, 10 * MS, [(0, "A", 1 * MS)], "timetable.slots[0].task", "drop its period"),
    ({"deadline": 1 * MS}, 10 * MS, [(0, "A", 1 * MS)], "timetable.slots[0].task", "drop its 'deadline'"),
    ({}, 10 * MS, [], "timetable.slots", "no slots"),
])
def test_a_table_that_does_not_fit_is_refused_at_its_path(kernel_kw, cycle, slots, path, match):
    k = _kernel(**kernel_kw)
    with pytest.raises(BuildError, match=match) as info:
        create_timetable(k, cycle, slots)
    assert info.value.path == path


def test_a_timetable_needs_policy_tt():
    with pytest.raises(BuildError, match="needs policy 'tt'"):
        create_timetable(_kernel("edf"), 10 * MS, [(0, "A", 1 * MS)])
