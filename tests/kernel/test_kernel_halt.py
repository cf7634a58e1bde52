"""Kernel.halt: a node that stops for good (its battery ran out, issue 20)."""

from __future__ import annotations

from netsim.env import SimEnv
from netsim.kernel import Kernel
from netsim.network.message import Message
from netsim.timebase import MS

from tests.kernel.conftest import exec_body


def test_halt_kills_the_running_job_and_stops_periodic_releases():
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_task("T", exec_body(4 * MS), period=10 * MS, priority=1)
    env.sim.call_at(12 * MS, k.halt)
    env.run(50 * MS)
    rec = k.job_records
    # job 0 runs 0..4 ms; job 1 (released at 10 ms) is cut at 12 ms; no job after the halt
    assert [(r.job_id, r.finish, r.killed) for r in rec] == [(0, 4 * MS, False), (1, 12 * MS, True)]
    assert k.cpu_time["T"] == 4 * MS + 2 * MS
    assert k.halted


def test_a_halted_node_ignores_messages_and_triggers_and_kills_created_jobs():
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_task("T", exec_body(1 * MS), priority=1)
    k.create_handler("H", exec_body(1 * MS), priority=0)
    k.create_trigger("ext", "H")
    k.halt()
    assert k.trigger("ext") is False
    k.deliver("bus", Message("a", "n", None, 8))
    assert len(k.inbox("bus")) == 0
    job = k.create_job("T")
    env.run(5 * MS)
    assert job.killed and k.cpu_time["T"] == 0 and k.cpu_time["H"] == 0
