"""Network send/receive and analog I/O requests."""

from __future__ import annotations

import pytest

from netsim.env import SimEnv
from netsim.errors import SimulationError
from netsim.kernel import Kernel
from netsim.network.message import Message
from netsim.timebase import MS, US


class FakeNetwork:
    def __init__(self, name: str) -> None:
        self.name = name
        self.sent: list[tuple[int, Message]] = []
        self.env: SimEnv | None = None

    def send(self, msg: Message) -> None:
        assert self.env is not None
        self.sent.append((self.env.now, msg))


def test_send_hands_a_filled_message_to_the_network_at_segment_time():
    env = SimEnv()
    k = Kernel(env, "sensor")
    net = FakeNetwork("can")
    net.env = env
    k.attach_network(net)

    def body(job):
        yield job.execute(200 * US)
        yield job.send("can", "controller", 1.5, 64, priority=3)
        yield job.send("can", None, "all", 8, tag="hello")

    k.create_task("sample", body, period=1 * MS, priority=1)
    env.run(500 * US)
    assert len(net.sent) == 2
    (t0, m0), (t1, m1) = net.sent
    assert t0 == t1 == 200 * US
    assert (m0.sender, m0.receiver, m0.payload, m0.bits, m0.priority, m0.tag) == (
        "sensor", "controller", 1.5, 64, 3, "sample")
    assert (m1.receiver, m1.tag, m1.priority) == (None, "hello", 0)


def test_send_on_unattached_network_names_task_and_network():
    env = SimEnv()
    k = Kernel(env, "n")
    k.attach_network(FakeNetwork("can"))

    def body(job):
        yield job.send("cna", "x", 0, 8)

    k.create_task("t", body, priority=1)
    k.create_job("t")
    with pytest.raises(SimulationError, match=r"task 't'.*'cna'.*did you mean 'can'"):
        env.run(1 * MS)


def test_deliver_with_bound_task_releases_job_that_reads_the_message():
    env = SimEnv()
    k = Kernel(env, "actuator")
    k.bind_receive("can", "act")
    seen = []

    def act(job):
        msg = yield job.receive("can")
        seen.append((job.now, job.data is msg, msg.payload))
        yield job.execute(100 * US)
        again = yield job.receive("can")
        seen.append(again)

    k.create_task("act", act, priority=1)

    def arrive():
        yield env.timeout(2 * MS)
        k.deliver("can", Message("controller", "actuator", 4.2, 64))

    env.process(arrive())
    env.run(5 * MS)
    assert seen == [(2 * MS, True, 4.2), None]
    rec = k.job_records[0]
    assert rec.release == 2 * MS and rec.finish == 2 * MS + 100 * US


def test_deliver_with_bound_handler_invokes_it_and_unbound_network_only_queues():
    env = SimEnv()
    k = Kernel(env, "ctrl")
    k.bind_receive("can", "rx")
    seen = []

    def rx(job):
        msg = yield job.receive("can")
        seen.append((job.now, msg.payload, job.invoker))
        yield job.execute(10 * US)

    k.create_handler("rx", rx)

    def arrive():
        yield env.timeout(1 * MS)
        k.deliver("can", Message("s", "ctrl", "a", 8))
        k.deliver("can", Message("s", "ctrl", "b", 8))
        k.deliver("other", Message("s", "ctrl", "c", 8))

    env.process(arrive())
    env.run(2 * MS)
    assert seen == [(1 * MS, "a", "network:can"), (1 * MS + 10 * US, "b", "network:can")]
    assert [m.payload for m in k.inbox("other")] == ["c"]


def test_analog_in_and_out_call_the_attached_channels_at_request_time():
    env = SimEnv()
    k = Kernel(env, "n")
    writes = []
    k.attach_analog_in("y", lambda t: t / MS)
    k.attach_analog_out("u", lambda t, v: writes.append((t, v)))

    def body(job):
        y = yield job.analog_in("y")
        yield job.execute(300 * US)
        yield job.analog_out("u", -2 * y)

    k.create_task("ctl", body, period=1 * MS, offset=1 * MS, priority=1)
    env.run(2500 * US)
    assert writes == [(1300 * US, -2.0), (2300 * US, -4.0)]


def test_unknown_analog_channel_is_reported_with_suggestion():
    env = SimEnv()
    k = Kernel(env, "n")
    k.attach_analog_in("theta", lambda t: 0.0)

    def body(job):
        yield job.analog_in("tehta")

    k.create_task("t", body, priority=1)
    k.create_job("t")
    with pytest.raises(SimulationError, match="did you mean 'theta'"):
        env.run(1 * MS)


def test_deliver_leaves_the_bound_task_for_after_the_media_callback():
    # a medium may act after deliver within the same callback (the pipeline delivers every copy of a frame in
    # one loop; CAN requests arbitration after delivering), so the receiver's zero-time code must not run inside
    # deliver: it runs at the instant's DISPATCH entry, after the callback returned. (Dispatching inside deliver
    # saves calls per period, but a zero-time reply would then run before the medium's own remaining actions.)
    env = SimEnv()
    k = Kernel(env, "actuator")
    k.bind_receive("can", "act")
    seen = []

    def act(job):
        msg = yield job.receive("can")
        seen.append((job.now, msg.payload))
        yield job.execute(100 * US)

    k.create_task("act", act, priority=1)
    after_deliver = []

    def arrive():
        yield env.timeout(2 * MS)
        k.deliver("can", Message("controller", "actuator", 4.2, 64))
        after_deliver.append((list(seen), k.running))

    env.process(arrive())
    env.run(5 * MS)
    assert after_deliver == [([], None)]  # nothing of the receiver ran inside deliver
    assert seen == [(2 * MS, 4.2)]  # it read the message at the same instant, afterwards
    assert k.job_records[0].finish == 2 * MS + 100 * US


def test_deliver_waits_for_a_release_due_at_the_same_instant():
    # releases come before dispatch at an instant: a periodic release queued at the arrival's instant is
    # processed first, so the more urgent periodic task starts before the message's task reads its inbox
    env = SimEnv()
    k = Kernel(env, "n")
    k.bind_receive("can", "act")
    starts = []

    def act(job):
        starts.append(("act", job.now))
        yield job.receive_newest("can")
        yield job.execute(10 * US)

    def hi(job):
        starts.append(("hi", job.now))
        yield job.execute(50 * US)

    k.create_task("act", act, priority=2)
    k.create_task("hi", hi, period=1 * MS, offset=1 * MS, priority=1)

    def arrive():
        yield env.timeout(2 * MS)  # queued at t = 0, before the release at 2 ms (queued at 1 ms)
        k.deliver("can", Message("s", "n", 1.0, 8))

    env.process(arrive())
    env.run(2 * MS + 500 * US)
    assert starts == [("hi", 1 * MS), ("hi", 2 * MS), ("act", 2 * MS + 50 * US)]


def test_receive_newest_empties_the_inbox_in_one_request_and_returns_its_last_message():
    # three messages queued at one instant: the one request returns the third and leaves the inbox empty; an
    # empty inbox gives None
    env = SimEnv()
    k = Kernel(env, "ctrl")
    got = []
    yields = []

    def body(job):
        for _ in range(2):
            req = job.receive_newest("can")
            yields.append(req)
            got.append((yield req))
            got.append(len(k.inbox("can")))

    k.create_task("t", body, priority=1)

    def arrive():
        yield env.timeout(1 * MS)
        for payload in "abc":
            k.deliver("can", Message("s", "ctrl", payload, 8))
        k.create_job("t")

    env.process(arrive())
    env.run(2 * MS)
    assert [m.payload if m is not None else None for m in got[::2]] == ["c", None]
    assert got[1::2] == [0, 0]  # the inbox is empty after each single request


class _CountingDict(dict):
    """A dict that counts its ``get`` calls (how often deliver looks a target up)."""

    gets = 0

    def get(self, *args):
        type(self).gets += 1
        return super().get(*args)


def test_deliver_looks_its_target_up_once_per_network_and_again_after_a_new_binding():
    env = SimEnv()
    k = Kernel(env, "n")
    k.handlers = _CountingDict(k.handlers)
    seen = []

    def rx(job):
        msg = yield job.receive("can")
        seen.append((job.now, msg.payload, job.invoker))

    k.create_handler("rx", rx)

    def arrive():
        yield env.timeout(1 * MS)
        k.deliver("can", Message("s", "n", "unbound", 8))  # only queued
        k.bind_receive("can", "rx")
        for payload in "abc":
            yield env.timeout(1 * MS)
            k.deliver("can", Message("s", "n", payload, 8))

    env.process(arrive())
    env.run(5 * MS)
    # the binding made after the first message counts from the next one; rx reads the inbox in order, so the
    # first job reads the unbound message (queued at 1 ms), each later job the one before its own
    assert seen == [(2 * MS, "unbound", "network:can"), (3 * MS, "a", "network:can"), (4 * MS, "b", "network:can")]
    # one handler look-up for the three bound deliveries (before: one per delivery)
    assert _CountingDict.gets == 1
