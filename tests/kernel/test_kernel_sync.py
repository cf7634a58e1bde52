"""Mailboxes, semaphores and events between task jobs."""

from __future__ import annotations

import pytest

from netsim.env import SimEnv
from netsim.errors import ConfigError, SimulationError
from netsim.kernel import Event, Kernel, Mailbox, Semaphore
from netsim.timebase import MS


def test_bounded_mailbox_blocks_producer_when_full_and_hands_items_in_order():
    # capacity 1. Producer (prio 1) posts 1, 2, 3 at t=0; consumer (prio 2) fetches, then executes 1 ms.
    # By hand: post 1 ok, post 2 blocks; consumer fetches 1 at 0 (2 moves in, producer wakes, preempts,
    # post 3 blocks); consumer fetches 2 at 1 ms (3 moves in, producer returns at 1 ms), 3 at 2 ms.
    mb = Mailbox("mb", capacity=1)
    got, post_done = [], []
    env = SimEnv()
    k = Kernel(env, "n")

    def producer(job):
        for item in (1, 2, 3):
            yield job.post(mb, item)
            post_done.append((item, job.now))

    def consumer(job):
        for _ in range(3):
            item = yield job.fetch(mb)
            got.append((item, job.now))
            yield job.execute(1 * MS)

    k.create_task("producer", producer, priority=1)
    k.create_task("consumer", consumer, priority=2)
    k.create_job("producer")
    k.create_job("consumer")
    env.run(10 * MS)
    assert got == [(1, 0), (2, 1 * MS), (3, 2 * MS)]
    assert post_done == [(1, 0), (2, 0), (3, 1 * MS)]
    assert {r.task: r.finish for r in k.job_records} == {"producer": 1 * MS, "consumer": 3 * MS}


def test_fetch_blocks_until_a_post_and_blocked_interval_is_traced():
    mb = Mailbox("mb")
    got = []
    env = SimEnv()
    k = Kernel(env, "n")

    def consumer(job):
        item = yield job.fetch(mb)
        got.append((item, job.now))

    def producer(job):
        yield job.sleep(5 * MS)
        yield job.post(mb, "x")

    k.create_task("consumer", consumer, priority=1)
    k.create_task("producer", producer, priority=2)
    k.create_job("consumer")
    k.create_job("producer")
    env.run(10 * MS)
    assert got == [("x", 5 * MS)]
    assert ("consumer", "blocked", 0, 5 * MS) in k.schedule


def test_try_variants_never_block():
    mb = Mailbox("mb", capacity=2)
    out = []
    env = SimEnv()
    k = Kernel(env, "n")

    def body(job):
        out.append((yield job.try_fetch(mb)))
        for i in range(3):
            out.append((yield job.try_post(mb, i)))
        out.append((yield job.try_fetch(mb)))
        out.append(len(mb))

    k.create_task("t", body, priority=1)
    k.create_job("t")
    env.run(1 * MS)
    assert out == [None, True, True, False, 0, 1]
    assert k.job_records[0].finish == 0


def test_semaphore_mutual_exclusion_blocks_higher_priority_until_give():
    # L takes at 0 and holds for 2 ms; H (released at 1 ms) blocks on take, gets it at 2 ms, ends at 4 ms.
    sem = Semaphore("mutex", count=1)
    env = SimEnv()
    k = Kernel(env, "n")

    def critical(job):
        yield job.take(sem)
        yield job.execute(2 * MS)
        yield job.give(sem)

    k.create_task("L", critical, period=20 * MS, priority=2)
    k.create_task("H", critical, period=20 * MS, offset=1 * MS, priority=1)
    env.run(10 * MS)
    rec = {r.task: r for r in k.job_records}
    assert rec["L"].finish == 2 * MS
    assert rec["H"].start == 1 * MS and rec["H"].finish == 4 * MS
    assert sem.count == 1


def test_counting_semaphore_admits_count_jobs():
    sem = Semaphore("pool", count=2)
    env = SimEnv()
    k = Kernel(env, "n")
    entered = []

    def user(job):
        yield job.take(sem)
        entered.append((job.task_name, job.now))
        yield job.sleep(3 * MS)
        yield job.give(sem)

    for i in range(3):
        k.create_task(f"u{i}", user, priority=i)
        k.create_job(f"u{i}")
    env.run(10 * MS)
    assert entered == [("u0", 0), ("u1", 0), ("u2", 3 * MS)]


def test_event_notify_wakes_one_notify_all_wakes_rest_and_unheard_notify_is_lost():
    ev = Event("go")
    woke = []
    env = SimEnv()
    k = Kernel(env, "n")

    def waiter(job):
        yield job.wait(ev)
        woke.append((job.task_name, job.now))

    def notifier(job):
        yield job.sleep(1 * MS)
        yield job.notify(ev)
        yield job.sleep(1 * MS)
        yield job.notify(ev, all=True)
        yield job.sleep(1 * MS)
        yield job.notify(ev)  # nobody waits: lost

    for name, prio in (("w1", 1), ("w2", 2), ("w3", 3)):
        k.create_task(name, waiter, priority=prio)
        k.create_job(name)
    k.create_task("n", notifier, priority=9)
    k.create_job("n")

    def late(job):
        yield job.sleep(4 * MS)
        yield job.wait(ev)
        woke.append(("late", job.now))

    k.create_task("late", late, priority=5)
    k.create_job("late")
    env.run(10 * MS)
    assert woke == [("w1", 1 * MS), ("w2", 2 * MS), ("w3", 2 * MS)]
    late_rec = next(r for r in k.job_records if r.task == "late")
    assert late_rec.finish is None  # still waiting at the end of the run


def test_sync_objects_reject_bad_arguments():
    with pytest.raises(ConfigError, match="capacity"):
        Mailbox("m", capacity=0)
    with pytest.raises(ConfigError, match="count"):
        Semaphore("s", count=-1)
    env = SimEnv()
    k = Kernel(env, "n")

    def body(job):
        yield job.fetch(Semaphore("s"))

    k.create_task("t", body, priority=1)
    k.create_job("t")
    with pytest.raises(SimulationError, match="fetch\\(\\) needs a Mailbox"):
        env.run(1 * MS)
