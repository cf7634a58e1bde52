"""Constant bandwidth and total bandwidth servers (netsim.kernel.servers) against schedules worked out by hand.

Every time below is in ms. Notation: a CBS has budget Qs, period Ts, budget left c, deadline d; EDF runs the job
with the earliest deadline, a served job with its server's d.
"""

from __future__ import annotations

import pytest

from netsim.env import SimEnv, schedule_call
from netsim.errors import BuildError, SimulationError
from netsim.kernel import Kernel
from netsim.kernel.events import NORMAL
from netsim.kernel.servers import attach_server, create_cbs, create_tbs
from netsim.timebase import MS


def _work(job):
    """Execute job.data ns (the job's demand, given at its release)."""
    yield job.execute(job.data)


def _periodic(c_ms):
    def body(job):
        yield job.execute(c_ms * MS)

    return body


def _release_at(env, kernel, task, t_ms, demand_ms):
    schedule_call(env.sim, t_ms * MS, NORMAL, lambda _ev: kernel.create_job(task, demand_ms * MS))


def _spans(kernel, task):
    """(start, finish) in ms of each job of ``task`` (unfinished: finish None)."""
    return [(None if r.start is None else r.start / MS, None if r.finish is None else r.finish / MS)
            for r in kernel.job_records if r.task == task]


def _cbs_example(hard):
    """tau1: periodic C=3, T=D=7 (EDF, hard real time). A: aperiodic, served by a CBS Qs=2, Ts=7; jobs A1 at 2
    (demand 3) and A2 at 8 (demand 2). Utilisation 3/7 + 2/7 = 5/7."""
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="edf")
    k.create_task("tau1", _periodic(3), period=7 * MS)
    k.create_task("A", _work)
    srv = create_cbs(k, "cbs", 2 * MS, 7 * MS, hard=hard)
    attach_server(k, "A", "cbs")
    _release_at(env, k, "A", 2, 3)
    _release_at(env, k, "A", 8, 2)
    seen = []
    schedule_call(env.sim, 4 * MS, NORMAL, lambda _ev: seen.append(srv.budget_left))
    env.run(30 * MS)
    return k, srv, seen


def test_soft_cbs_textbook_example_postpones_the_deadline_and_keeps_running():
    k, srv, seen = _cbs_example(hard=False)
    # t=0: tau1#0 (d=7) runs 0-3.
    # t=2: A1 arrives, server idle with c=0, d=0: c*Ts = 0 >= (d - r)*Qs = (0-2)*2 -> c=2, d=2+7=9; 9 > 7: waits.
    # t=3: A1 runs 3-5 (c 2 -> 0; at t=4 one ms of it is used: budget_left 1), 1 ms of work left:
    #      soft -> c=2, d=9+7=16; nothing else ready, A1 runs 5-6 (c=1 left) and finishes at 6.
    # t=7: tau1#1 (d=14) runs 7-10.
    # t=8: A2 arrives, server idle, c=1, d=16: c*Ts = 7 >= (16-8)*2 = 16 fails -> c=1, d=16 kept; 16 > 14: waits.
    # t=10: A2 runs 10-11 (c 1 -> 0), 1 ms left -> c=2, d=23; runs 11-12, finishes at 12 (c=1).
    # t=14: tau1#2 (d=21) runs 14-17; t=21: tau1#3 21-24; t=28: tau1#4 28-31 (cut at 30).
    assert _spans(k, "A") == [(3, 6), (10, 12)]
    assert _spans(k, "tau1")[:4] == [(0, 3), (7, 10), (14, 17), (21, 24)]
    assert seen == [1 * MS]
    assert [(e.t / MS, e.what, e.budget / MS, e.deadline / MS) for e in srv.events] == [
        (2, "reset", 2, 9), (5, "replenish", 2, 16), (11, "replenish", 2, 23)]
    assert srv.replenishments == 2 and srv.throttles == 0
    assert all(r.deadline_met for r in k.job_records if r.task == "tau1" and r.finish is not None)


def test_hard_cbs_suspends_its_job_until_the_replenishment_time():
    k, srv, _ = _cbs_example(hard=True)
    # t=0-3 tau1#0; A1 arrives at 2 (c=2, d=9) and runs 3-5 as in the soft case.
    # t=5: c=0 with 1 ms left; hard: d=9+7=16, A1 suspended until the old d=9, then c=2.
    # t=7: tau1#1 (d=14) runs 7-10. t=8: A2 arrives while A1 is unfinished: the server is busy, A2 queues behind
    #      A1 (same task) with d=16.
    # t=9: c=2, A1 ready with d=16 > 14: waits until tau1#1 ends at 10; A1 runs 10-11 (c=1), finishes at 11.
    # t=11: A2 runs 11-12 (c 1 -> 0), 1 ms left: old d=16 > 12 -> d=23, suspended until 16.
    # t=14: tau1#2 (d=21) runs 14-17. t=16: c=2, A2 ready with d=23 > 21: waits; runs 17-18, finishes at 18.
    assert _spans(k, "A") == [(3, 11), (11, 18)]
    assert _spans(k, "tau1")[:3] == [(0, 3), (7, 10), (14, 17)]
    assert [(e.t / MS, e.what, e.budget / MS, e.deadline / MS) for e in srv.events] == [
        (2, "reset", 2, 9), (5, "throttle", 0, 16), (9, "replenish", 2, 16), (12, "throttle", 0, 23),
        (16, "replenish", 2, 23)]
    assert srv.throttles == 2
    # the schedule trace shows A blocked while the server waits: 5-9 and 12-16
    blocked = [(t0 / MS, t1 / MS) for name, state, t0, t1 in k.schedule if name == "A" and state == "blocked"]
    assert blocked == [(5, 9), (12, 16)]


def test_tbs_deadlines_follow_the_formula_and_rank_the_jobs():
    # tau1: periodic C=3, T=D=6 (U=0.5). A: aperiodic, wcet 2, served by a TBS with Us=0.5; its jobs arrive at
    # 3, 7, 8 and use 1, 2, 1 ms (C_k in the formula is the wcet, 2 ms, as TrueTime's TBS uses ttSetWCET):
    # d_k = max(r_k, d_k-1) + C_k / Us:
    #   A1 at 3: d1 = max(3, 0) + 2/0.5 = 7
    #   A2 at 7: d2 = max(7, 7) + 2/0.5 = 11
    #   A3 at 8: d3 = max(8, 11) + 2/0.5 = 15
    # EDF: tau1#0 (d=6) 0-3; A1 (d=7) 3-4; tau1#1 (d=12) from 6, preempted at 7 by A2 (d=11 < 12): A2 7-9;
    # A3 queues behind A2 (same task) and then has d=15 > 12: tau1#1 resumes 9-11; A3 11-12; tau1#2 (d=18) 12-15.
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="edf")
    k.create_task("tau1", _periodic(3), period=6 * MS)
    k.create_task("A", _work, wcet=2 * MS)
    srv = create_tbs(k, "tbs", 0.5)
    attach_server(k, "A", "tbs")
    for t, c in ((3, 1), (7, 2), (8, 1)):
        _release_at(env, k, "A", t, c)
    env.run(20 * MS)
    assert [e.deadline / MS for e in srv.events] == [7, 11, 15]
    assert _spans(k, "A") == [(3, 4), (7, 9), (11, 12)]
    assert _spans(k, "tau1")[:3] == [(0, 3), (6, 11), (12, 15)]
    tau1 = [r for r in k.job_records if r.task == "tau1"]
    assert tau1[1].preemptions == 1


def test_tbs_deadline_is_rounded_up_to_the_ns():
    # Us = 0.3 read as 3/10 exactly: C = 1 ms -> 1e6 * 10 / 3 = 3_333_333.33 ns, rounded up to 3_333_334 ns
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="edf")
    k.create_task("A", _work, wcet=1 * MS)
    srv = create_tbs(k, "tbs", 0.3)
    attach_server(k, "A", "tbs")
    _release_at(env, k, "A", 0, 1)
    env.run(5 * MS)
    assert srv.events[0].deadline == 3_333_334


def _budget_change_run(change):
    """A: periodic T=10, C=3, in a hard CBS Qs=2, Ts=10; optionally Qs set to 3 at t=5 (ttSetCBSParameters)."""
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="edf")
    k.create_task("A", _periodic(3), period=10 * MS)
    srv = create_cbs(k, "cbs", 2 * MS, 10 * MS, hard=True)
    attach_server(k, "A", "cbs")
    if change:
        schedule_call(env.sim, 5 * MS, NORMAL, lambda _ev: srv.set_parameters(3 * MS, 10 * MS))
    env.run(45 * MS)
    return [f for _, f in _spans(k, "A")]


def test_cbs_budget_set_at_run_time_applies_from_the_next_replenishment():
    # Without the change (Qs=2): A#0 runs 0-2 (reset at 0: c=2, d=10), throttled until 10 (d=20).
    # t=10: A#1 is released (queued behind A#0), then c=2: A#0 10-11 (c=1), A#1 11-12 (c=0), 2 ms left ->
    # throttled until 20 (d=30); t=20: c=2, A#1 20-22 finishes (c=0); A#2 (d=30): no budget -> throttled until
    # 30 (d=40); t=30: c=2, A#2 30-32 (c=0), 1 ms left -> throttled until 40; A#2 40-41.
    assert _budget_change_run(False)[:3] == [11, 22, 41]
    # With Qs=3 set at t=5: c and d are kept (c=0 while throttled); the replenishment at 10 gives c=3:
    # A#0 10-11 (c=2), A#1 11-13 (c=0), 1 ms left -> throttled until 20 (d=30); t=20: c=3, A#1 20-21 (c=2);
    # A#2 21-23 (c=0), 1 ms left -> until 30 (d=40); t=30: c=3, A#2 30-31.
    assert _budget_change_run(True)[:3] == [11, 21, 31]


def test_set_parameters_refuses_a_bandwidth_above_one():
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="edf")
    srv = create_cbs(k, "cbs", 2 * MS, 10 * MS)
    with pytest.raises(SimulationError, match="exceeds the period"):
        srv.set_parameters(11 * MS, 10 * MS)


@pytest.mark.parametrize("policy, make, match", [
    ("fp", lambda k: create_cbs(k, "s", 1 * MS, 2 * MS), "needs policy 'edf'"),
    ("edf", lambda k: create_cbs(k, "s", 3 * MS, 2 * MS), "exceeds the period"),
    ("edf", lambda k: create_tbs(k, "s", 1.5), "outside"),
    ("edf", lambda k: (create_tbs(k, "a", 0.6), create_tbs(k, "b", 0.6)), "above the CPU"),
])
def test_bad_servers_are_refused(policy, make, match):
    k = Kernel(SimEnv(seed=1), "cpu", policy=policy)
    with pytest.raises(BuildError, match=match):
        make(k)


def test_attach_refuses_unknown_names_and_budget_conflicts():
    k = Kernel(SimEnv(seed=1), "cpu", policy="edf")
    k.create_task("A", _work, wcet=1 * MS)
    k.create_task("B", _work)
    create_cbs(k, "cbs", 1 * MS, 2 * MS)
    create_tbs(k, "tbs", 0.25)
    with pytest.raises(BuildError, match="unknown server 'cbz'; did you mean 'cbs'"):
        attach_server(k, "B", "cbz")
    with pytest.raises(BuildError, match="drop its 'wcet'"):
        attach_server(k, "A", "cbs")
    with pytest.raises(BuildError, match="needs a 'wcet'"):
        attach_server(k, "B", "tbs")


def test_a_node_without_servers_schedules_as_before():
    # the same task set without the server: A is plain EDF without a deadline (last), so A1 waits for tau1
    # and runs 3-6; A2 runs 10-12
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="edf")
    k.create_task("tau1", _periodic(3), period=7 * MS)
    k.create_task("A", _work)
    _release_at(env, k, "A", 2, 3)
    _release_at(env, k, "A", 8, 2)
    env.run(30 * MS)
    assert _spans(k, "A") == [(3, 6), (10, 12)]
    assert k.servers == {}


def test_context_switches_are_not_charged_to_the_server_budget():
    # CBS Qs=2, Ts=10 serving A (T=10, C=2) with a 0.5 ms context switch: each job switches 0-0.5 and executes
    # 0.5-2.5, using exactly its 2 ms of budget: it finishes as the budget reaches 0, so no replenishment
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="edf", context_switch=MS // 2)
    k.create_task("A", _periodic(2), period=10 * MS)
    srv = create_cbs(k, "cbs", 2 * MS, 10 * MS)
    attach_server(k, "A", "cbs")
    env.run(15 * MS)
    assert _spans(k, "A")[:2] == [(0, 2.5), (10, 12.5)]
    assert [e.what for e in srv.events] == ["reset", "reset"] and srv.replenishments == 0


def test_a_job_killed_while_its_hard_server_waits_leaves_the_server_working():
    # hard CBS Qs=2, Ts=10 serving A (T=10, C=3): A#0 runs 0-2 and waits for the replenishment at 10 (d=20); it is
    # killed at 5. At 10 A#1 arrives at an idle server with c=0, d=20: 0 >= (20-10)*2/10 fails, c and d kept; the
    # replenishment at 10 gives c=2: A#1 runs 10-12, waits until 20 (d=30), runs 20-21.
    env = SimEnv(seed=1)
    k = Kernel(env, "cpu", policy="edf")
    k.create_task("A", _periodic(3), period=10 * MS)
    create_cbs(k, "cbs", 2 * MS, 10 * MS, hard=True)
    attach_server(k, "A", "cbs")
    schedule_call(env.sim, 5 * MS, NORMAL, lambda _ev: k.kill_job(k.tasks["A"].active))
    env.run(25 * MS)
    recs = [r for r in k.job_records if r.task == "A"]
    assert (recs[0].killed, recs[0].finish) == (True, 5 * MS)
    assert (recs[1].start, recs[1].finish) == (10 * MS, 21 * MS)


@pytest.mark.parametrize("kernel_kw", [{"cores": 2}, {"speed": 1.0}])
def test_servers_are_refused_on_a_multicore_or_speed_scaling_node(kernel_kw):
    # their dispatcher has no server hooks: a served job would run unbudgeted
    k = Kernel(SimEnv(seed=1), "cpu", policy="edf", **kernel_kw)
    with pytest.raises(BuildError, match="single-core node without speed scaling"):
        create_cbs(k, "cbs", 1 * MS, 2 * MS)
