"""CPU accounting of jobs the run ends in the middle of."""

from netsim.env import SimEnv
from netsim.kernel import Kernel
from netsim.timebase import MS, US


def test_a_job_still_running_at_the_end_is_charged_only_the_time_it_ran():
    # released and dispatched at 1 ms (the run's end), it has run for 0 ns; released at 0.4 ms with 1 ms of work,
    # the other job has run 0.6 ms by the end. env.run(T) leaves the simpy clock at T + 1 ns: not CPU time.
    env = SimEnv()
    k = Kernel(env, "n")

    def body(job):
        yield job.execute(1 * MS)

    k.create_task("late", body, priority=1)
    k.create_task("early", body, priority=2)
    env.sim.process(_release_at(env, k, "early", 400 * US))
    env.sim.process(_release_at(env, k, "late", 1 * MS))
    env.run(1 * MS)
    cpu = {r.task: r.cpu_time for r in k.job_records}
    assert all(r.finish is None for r in k.job_records)
    assert cpu == {"late": 0, "early": 600 * US}


def _release_at(env, kernel, task, t):
    yield env.timeout(t)
    kernel.create_job(task)
