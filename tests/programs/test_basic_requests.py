"""The basic programs yield requests built once per program, not one per job (issue 29, calls per period)."""

from __future__ import annotations

from typing import Any

from netsim.env import SimEnv
from netsim.kernel import Kernel
from netsim.kernel.requests import ANALOG_IN, EXECUTE, RECEIVE_NEWEST
from netsim.network.message import Message
from netsim.programs.basic import Actuator, ProgramContext, Sampler
from netsim.timebase import MS, US


def _recorded(program: Any, seen: list[list[Any]]) -> Any:
    """A body that runs ``program`` and keeps, per job, the requests it yields."""
    def body(job: Any) -> Any:
        mine: list[Any] = []
        seen.append(mine)
        gen = program(job)
        value = None
        while True:
            try:
                req = gen.send(value)
            except StopIteration:
                return
            mine.append(req)
            value = yield req
    return body


def test_actuator_yields_the_same_receive_and_execute_requests_at_every_job():
    env = SimEnv()
    k = Kernel(env, "act")
    writes: list[tuple[int, float]] = []
    k.attach_analog_out("u", lambda t, v: writes.append((t, v)))
    k.bind_receive("can", "actuate")
    ctx = ProgramContext(env=env, kernel=k, node="act", task="actuate", execution=10 * US)
    seen: list[list[Any]] = []
    k.create_task("actuate", _recorded(Actuator(ctx, Actuator.Params(network="can", channel="u")), seen), priority=1)

    def arrive():
        for i in range(2):
            yield env.timeout(1 * MS)
            k.deliver("can", Message("c", "act", float(i + 1), 8))

    env.process(arrive())
    env.run(3 * MS)
    # each job: receive the newest, execute 10 us, write the DAC (by hand: values 1.0 and 2.0 at 1 and 2 ms + 10 us)
    assert writes == [(1 * MS + 10 * US, 1.0), (2 * MS + 10 * US, 2.0)]
    first, second = seen
    assert [r.op for r in first[:2]] == [RECEIVE_NEWEST, EXECUTE]
    assert first[0] is second[0] and first[1] is second[1]


def test_sampler_yields_the_same_analog_in_request_at_every_job():
    env = SimEnv()
    k = Kernel(env, "s")
    k.attach_analog_in("y", lambda t: t / MS)
    ctx = ProgramContext(env=env, kernel=k, node="s", task="sample", execution=None, period=1 * MS)
    seen: list[list[Any]] = []
    program = Sampler(ctx, Sampler.Params(channel="y", to=None))
    k.create_task("sample", _recorded(program, seen), period=1 * MS, priority=1)
    env.run(2 * MS + 1)
    # jobs at 0, 1 and 2 ms store y = t / ms in shared['y'] (the last: 2.0)
    assert k.shared["y"] == 2.0
    assert len(seen) == 3 and all(len(s) == 1 and s[0].op == ANALOG_IN for s in seen)
    assert seen[0][0] is seen[1][0] is seen[2][0]
