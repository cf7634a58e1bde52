"""Multiprocessor nodes (netsim.kernel.multicore): global and partitioned scheduling, migration cost, checks.

Every expected time below is worked out by hand in the comment next to it (units: ms = 1_000_000 ns).
"""

from __future__ import annotations

import pytest

from netsim.env import SimEnv
from netsim.errors import BuildError
from netsim.kernel import Kernel
from netsim.kernel.kernel import MulticoreKernel
from netsim.kernel.task import TaskSpec
from netsim.timebase import MS


def _exec(c: int):
    def body(job):
        yield job.execute(c)
    return body


def _records(k: Kernel) -> dict[tuple[str, int], object]:
    return {(r.task, r.job_id): r for r in k.job_records}


def _dhall(multicore: str, t_end: int):
    # Dhall's effect with e = 0.1 time units, one unit = 10 ms (so e = 1 ms):
    #   tau1, tau2: C = 2e = 2 ms, T = D = 1 unit = 10 ms   (u = 0.2 each)
    #   tau3:       C = 1 unit = 10 ms, T = D = 1 + e = 11 ms (u = 10/11 = 0.909)
    # total utilisation 0.2 + 0.2 + 0.909 = 1.309, on m = 2 cores (it tends to 1 as e -> 0).
    env = SimEnv()
    k = Kernel(env, "cpu", policy="edf", cores=2, multicore=multicore)
    for name, c, t, core in (("tau1", 2 * MS, 10 * MS, 0), ("tau2", 2 * MS, 10 * MS, 0), ("tau3", 10 * MS, 11 * MS, 1)):
        spec = TaskSpec(name, period=t)
        k.add_task(spec, _exec(c))
        if multicore == "partitioned":
            k.assign_core(name, core)
    env.run(t_end)
    return k


def test_global_edf_on_two_cores_misses_tau3_first_deadline_dhalls_effect():
    k = _dhall("global", 12 * MS + 1)
    rec = _records(k)
    # t = 0: the absolute deadlines are 10, 10, 11 ms: EDF puts tau1 and tau2 on the two cores, tau3 waits.
    assert (rec["tau1", 0].finish, rec["tau2", 0].finish) == (2 * MS, 2 * MS)
    # tau3 starts at 2 ms and needs 10 ms on one core: it ends at 12 ms > its deadline 11 ms.
    assert rec["tau3", 0].start == 2 * MS
    assert rec["tau3", 0].finish == 12 * MS
    assert rec["tau3", 0].deadline == 11 * MS and rec["tau3", 0].deadline_met is False


def test_partitioned_edf_meets_every_deadline_of_the_same_set():
    # core 0: tau1 + tau2 (u = 0.4 <= 1), core 1: tau3 alone (u = 0.909 <= 1): EDF meets all on each core.
    # One hyperperiod: lcm(10, 11) = 110 ms.
    k = _dhall("partitioned", 110 * MS + 1)
    rec = _records(k)
    done = [r for r in k.job_records if r.finish is not None]
    assert len(done) == 11 + 11 + 10  # 110/10 jobs of tau1 and tau2, 110/11 of tau3 (all finished by 110 ms)
    assert all(r.deadline_met for r in done)
    # first jobs: core 0 runs tau1 [0, 2], tau2 [2, 4]; core 1 runs tau3 [0, 10] (deadline 11)
    assert (rec["tau1", 0].finish, rec["tau2", 0].finish, rec["tau3", 0].finish) == (2 * MS, 4 * MS, 10 * MS)
    cores = {(iv[0], iv[4]) for iv in k.schedule if iv[1] == "running"}
    assert cores == {("tau1", 0), ("tau2", 0), ("tau3", 1)}


def test_a_job_resumed_on_another_core_pays_the_migration_cost():
    # Global FP on 2 cores, migration cost 1 ms, no context switch cost.
    #   B (prio 2, 4 ms) and C (prio 3, 10 ms) released at 0: B takes core 0, C core 1.
    #   A (prio 1, 5 ms) released at 1 ms: no idle core, it preempts the least urgent, C (1 ms done, 9 left),
    #     and runs on core 1 [1, 6].
    #   B ends at 4 ms: core 0 idles, C resumes there (it last ran on core 1): 1 ms migration, then 9 ms:
    #     C finishes at 4 + 1 + 9 = 14 ms with cpu time 1 + 1 + 9 = 11 ms (13 ms without the cost).
    env = SimEnv()
    k = Kernel(env, "cpu", policy="fp", cores=2, migration_cost=1 * MS)
    k.create_task("A", _exec(5 * MS), period=100 * MS, offset=1 * MS, priority=1)
    k.create_task("B", _exec(4 * MS), period=100 * MS, priority=2)
    k.create_task("C", _exec(10 * MS), period=100 * MS, priority=3)
    env.run(20 * MS)
    rec = _records(k)
    assert (rec["A", 0].start, rec["A", 0].finish) == (1 * MS, 6 * MS)
    assert rec["B", 0].finish == 4 * MS
    assert rec["C", 0].finish == 14 * MS
    assert rec["C", 0].cpu_time == 11 * MS and rec["C", 0].preemptions == 1
    assert k.migrations == 1 and k.switch_time == 1 * MS
    runs = [iv for iv in k.schedule if iv[0] == "C" and iv[1] == "running"]
    assert runs == [("C", "running", 0, 1 * MS, 1), ("C", "running", 4 * MS, 14 * MS, 0)]


def test_partitioned_fixed_priority_gives_each_core_its_own_response_times():
    # core 0: hi (prio 1, C = 2, T = 5 ms), lo (prio 2, C = 4, T = 10 ms); core 1: solo (prio 3, C = 3, T = 5 ms).
    # lo by response-time analysis on core 0: R = 4 + ceil(R/5)*2: 4 -> 6 -> 8 -> 8, so R = 8 ms
    #   (hi [0, 2], lo [2, 5], hi [5, 7], lo [7, 8]: one preemption).
    # solo is the least urgent task of the node but alone on core 1: R = 3 ms.
    env = SimEnv()
    k = Kernel(env, "cpu", policy="fp", cores=2, multicore="partitioned")
    for name, c, t, prio, core in (("hi", 2, 5, 1, 0), ("lo", 4, 10, 2, 0), ("solo", 3, 5, 3, 1)):
        k.add_task(TaskSpec(name, period=t * MS, priority=prio), _exec(c * MS))
        k.assign_core(name, core)
    env.run(10 * MS)
    rec = _records(k)
    assert rec["lo", 0].finish == 8 * MS and rec["lo", 0].preemptions == 1
    assert rec["solo", 0].finish == 3 * MS and rec["solo", 1].finish == 8 * MS
    assert {(iv[0], iv[4]) for iv in k.schedule if iv[1] == "running"} == {("hi", 0), ("lo", 0), ("solo", 1)}


def test_one_core_with_speed_one_gives_the_records_of_the_one_core_kernel():
    # the multicore dispatcher with m = 1 at speed 1 must reproduce the fast one-core dispatcher, here with
    # context switches, a handler, preemptions and a non-preemptible task
    def run(**kw):
        env = SimEnv()
        k = Kernel(env, "cpu", policy="fp", context_switch=50_000, **kw)
        k.create_handler("isr", _exec(200_000), priority=0, latency=30_000)
        k.create_timer("tick", "isr", period=3 * MS, start=1 * MS)
        k.create_task("a", _exec(1 * MS), period=4 * MS, priority=1)
        k.create_task("b", _exec(2 * MS), period=6 * MS, priority=2, preemptible=False)
        k.create_task("c", _exec(3 * MS), period=12 * MS, priority=3)
        env.run(48 * MS)
        return k
    fast, generic = run(), run(speed=1.0)
    assert type(fast) is Kernel and type(generic) is MulticoreKernel
    assert generic.job_records == fast.job_records
    assert generic.schedule == fast.schedule
    assert (generic.switches, generic.switch_time) == (fast.switches, fast.switch_time)


@pytest.mark.parametrize("kwargs, core, match", [
    ({"cores": 2, "multicore": "partitioned"}, 2, r"core.*0\.\.1.*got 2"),
    ({"cores": 2}, 0, r"only used with partitioned"),
])
def test_a_bad_task_core_is_refused_with_the_task_and_field_named(kwargs, core, match):
    k = Kernel(SimEnv(), "cpu", policy="fp", **kwargs)
    k.create_task("t", _exec(1), period=MS, priority=1)
    with pytest.raises(BuildError, match=match) as info:
        k.assign_core("t", core)
    assert info.value.field == "core"


def test_a_partitioned_task_without_a_core_is_refused_when_the_run_starts():
    env = SimEnv()
    k = Kernel(env, "cpu", policy="fp", cores=2, multicore="partitioned")
    k.create_task("t", _exec(1), period=MS, priority=1)
    with pytest.raises(BuildError, match=r"task 't'.*core.*required under multicore: partitioned"):
        env.run(1)


def test_bad_core_counts_and_modes_and_periodic_loads_are_refused():
    with pytest.raises(BuildError, match="cores must be a whole number"):
        Kernel(SimEnv(), "cpu", cores=0)
    with pytest.raises(BuildError, match="multicore must be 'global' or 'partitioned'"):
        Kernel(SimEnv(), "cpu", cores=2, multicore="clustered")
    k = Kernel(SimEnv(), "cpu", cores=2)
    with pytest.raises(BuildError, match="periodic load is not available"):
        k.create_periodic_load("tick", period=MS, execution=1000)


def test_a_job_killed_on_another_core_frees_that_core_for_the_next_ready_job():
    # Global FP on 2 cores: A (prio 1) and B (prio 2), 10 ms each, take cores 0 and 1 at 0; C (prio 3, 2 ms)
    # waits. At 3 ms a timer handler (on a core too: it preempts the least urgent, B, for zero time) kills B:
    # B's record is killed with 3 ms of CPU; C takes the freed core at 3 ms and ends at 3 + 2 = 5 ms.
    env = SimEnv()
    k = Kernel(env, "cpu", policy="fp", cores=2)
    jobs = {}

    def keep(c):
        def body(job):
            jobs[job.task_name] = job
            yield job.execute(c)
        return body

    def killer(job):
        yield job.kill(jobs["B"])

    k.create_task("A", keep(10 * MS), period=100 * MS, priority=1)
    k.create_task("B", keep(10 * MS), period=100 * MS, priority=2)
    k.create_task("C", keep(2 * MS), period=100 * MS, priority=3)
    k.create_handler("kill_b", killer)
    k.create_timer("at3", "kill_b", start=3 * MS)
    env.run(20 * MS)
    rec = _records(k)
    assert rec["B", 0].killed and rec["B", 0].finish == 3 * MS and rec["B", 0].cpu_time == 3 * MS
    assert (rec["C", 0].start, rec["C", 0].finish) == (3 * MS, 5 * MS)
    assert rec["A", 0].finish == 10 * MS and rec["A", 0].preemptions == 0
