"""Bad input is reported at build time naming task and field; livelocks are detected, not hung on."""

from __future__ import annotations

import pytest

from netsim.env import SimEnv
from netsim.errors import BuildError, ConfigError, LivelockError, SimulationError
from netsim.kernel import ExecTime, Kernel, Mailbox
from netsim.timebase import MS


def good(job):
    yield job.execute(1 * MS)


@pytest.fixture
def k():
    return Kernel(SimEnv(), "ctrl", policy="fp")


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"period": 0, "priority": 1}, "period"),
        ({"period": -5 * MS, "priority": 1}, "period"),
        ({"period": 1.5, "priority": 1}, "period"),
        ({"period": 10 * MS, "offset": -1, "priority": 1}, "offset"),
        ({"offset": 1 * MS, "priority": 1}, "offset"),
        ({"period": 10 * MS, "deadline": 0, "priority": 1}, "deadline"),
        ({"period": 10 * MS}, "priority"),
        ({"period": 10 * MS, "priority": "high"}, "priority"),
        ({"period": 10 * MS, "priority": 1, "wcet": -1}, "wcet"),
        ({"period": 10 * MS, "priority": 1, "wcet_handler": "h"}, "wcet_handler"),
        ({"priority": 1, "deadline_handler": "h"}, "deadline_handler"),
    ],
)
def test_invalid_task_parameters_raise_build_error_naming_task_and_field(k, kwargs, field):
    with pytest.raises(BuildError) as info:
        k.create_task("speed_loop", good, **kwargs)
    msg = str(info.value)
    assert "speed_loop" in msg and f"'{field}'" in msg
    assert info.value.task == "speed_loop" and info.value.field == field


def test_deadline_after_period_rejected_by_rm_and_dm_but_allowed_by_fp_and_edf():
    for policy in ("rm", "dm"):
        k = Kernel(SimEnv(), "n", policy=policy)
        with pytest.raises(BuildError, match=r"task 'a', field 'deadline'.*exceeds the period"):
            k.create_task("a", good, period=5 * MS, deadline=8 * MS)
    for policy in ("fp", "edf"):
        k = Kernel(SimEnv(), "n", policy=policy)
        k.create_task("a", good, period=5 * MS, deadline=8 * MS, priority=1)


def test_unknown_policy_suggests_the_closest_name():
    with pytest.raises(BuildError, match=r"node 'n'.*unknown policy 'rn'; did you mean 'rm'"):
        Kernel(SimEnv(), "n", policy="rn")


def test_body_that_is_not_a_generator_function_is_rejected():
    def not_a_generator(job):
        return 42

    k = Kernel(SimEnv(), "n")
    with pytest.raises(BuildError, match=r"task 'bad', field 'body'.*not a generator function"):
        k.create_task("bad", not_a_generator, priority=1)
    with pytest.raises(BuildError, match=r"field 'body'"):
        k.create_handler("bad_isr", "not callable")


def test_generator_bodies_in_objects_and_partials_are_accepted():
    import functools

    class Program:
        def __call__(self, job):
            yield job.execute(1)

    def with_arg(x, job):
        yield job.execute(x)

    env = SimEnv()
    k = Kernel(env, "n")
    k.create_task("a", Program(), priority=1)
    k.create_task("b", functools.partial(with_arg, 5), priority=1)
    k.create_job("a")
    k.create_job("b")
    env.run(100)
    # both bodies ran as generators: a uses 1 ns of CPU, b 5 ns (the partial's bound argument)
    assert k.cpu_time["a"] == 1
    assert k.cpu_time["b"] == 5


def test_duplicate_names_and_unknown_handler_references():
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_task("a", good, priority=1)
    with pytest.raises(BuildError, match="already used"):
        k.create_handler("a", good)
    k.create_handler("sampler", good)
    k.create_timer("tick", "smapler", period=1 * MS)
    with pytest.raises(BuildError, match=r"task 'tick', field 'handler'.*did you mean 'sampler'"):
        k.validate()
    with pytest.raises(BuildError):
        env.run(1 * MS)  # validated before anything runs


def test_negative_execution_times_are_rejected():
    with pytest.raises(ConfigError, match="negative"):
        ExecTime.constant(-1)
    with pytest.raises(ConfigError, match="negative"):
        ExecTime.from_spec("-0.5 ms")
    with pytest.raises(ConfigError, match="negative"):
        ExecTime.uniform(-5, 10)
    env = SimEnv()
    k = Kernel(env, "n")

    def body(job):
        yield job.execute(-5)

    k.create_task("neg", body, priority=1)
    k.create_job("neg")
    with pytest.raises(SimulationError, match=r"task 'neg': execute\(-5\) is negative"):
        env.run(1 * MS)


def test_context_switch_must_not_be_negative():
    with pytest.raises(BuildError, match="context_switch"):
        Kernel(SimEnv(), "n", context_switch=-1)


def test_yielding_something_else_than_a_request_is_reported():
    env = SimEnv()
    k = Kernel(env, "n")

    def body(job):
        yield 1000

    k.create_task("t", body, priority=1)
    k.create_job("t")
    with pytest.raises(SimulationError, match=r"task 't' yielded 1000"):
        env.run(1 * MS)


def test_zero_time_handler_loop_raises_livelock_naming_the_handler():
    env = SimEnv()
    k = Kernel(env, "n")

    def again(job):
        job.kernel.invoke_handler("again")
        yield job.execute(0)

    k.create_handler("again", again)
    k.create_timer("start", "again", start=1 * MS)
    with pytest.raises(LivelockError) as info:
        env.run(2 * MS)
    assert info.value.involved == ["again"]
    assert env.now == 1 * MS


def test_zero_time_ping_pong_between_tasks_raises_livelock_naming_both():
    env = SimEnv()
    k = Kernel(env, "n", livelock_limit=5_000)
    ping, pong = Mailbox("ping"), Mailbox("pong")

    def a(job):
        while True:
            yield job.post(ping, 1)
            yield job.fetch(pong)

    def b(job):
        while True:
            yield job.fetch(ping)
            yield job.post(pong, 1)

    k.create_task("a", a, priority=1)
    k.create_task("b", b, priority=2)
    k.create_job("a")
    k.create_job("b")
    with pytest.raises(LivelockError) as info:
        env.run(1 * MS)
    assert info.value.involved == ["a", "b"]


def test_body_looping_on_zero_time_requests_raises_livelock():
    env = SimEnv()
    k = Kernel(env, "n")
    k.attach_analog_in("y", lambda t: 0.0)

    def spin(job):
        while True:
            yield job.analog_in("y")

    k.create_task("spin", spin, priority=1)
    k.create_job("spin")
    with pytest.raises(LivelockError, match="'spin'"):
        env.run(1 * MS)


def test_bind_receive_to_unknown_target_is_reported_before_the_run():
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_task("actuate", good, priority=1)
    k.bind_receive("can", "actuat")
    with pytest.raises(BuildError, match=r"bind_receive\('can', 'actuat'\).*did you mean 'actuate'"):
        env.run(1 * MS)
    with pytest.raises(BuildError, match="already bound"):
        k.bind_receive("can", "actuate")
