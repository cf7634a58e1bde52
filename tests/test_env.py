"""The simulation environment: named random streams and the signal recorder."""

import numpy as np
import simpy.events

from netsim.env import SimEnv


def test_same_seed_and_name_give_the_same_stream():
    a = SimEnv(seed=5).rng("noise.y").normal(size=5)
    b = SimEnv(seed=5).rng("noise.y").normal(size=5)
    np.testing.assert_array_equal(a, b)


def test_streams_do_not_depend_on_creation_order():
    env1 = SimEnv(seed=3)
    x1 = env1.rng("a").random(4)
    y1 = env1.rng("b").random(4)
    env2 = SimEnv(seed=3)
    y2 = env2.rng("b").random(4)  # created first this time
    env2.rng("c").random(100)  # an extra source in between
    x2 = env2.rng("a").random(4)
    np.testing.assert_array_equal(x1, x2)
    np.testing.assert_array_equal(y1, y2)


def test_different_names_and_seeds_give_different_streams():
    env = SimEnv(seed=1)
    assert not np.array_equal(env.rng("a").random(8), env.rng("b").random(8))
    assert not np.array_equal(SimEnv(seed=1).rng("a").random(8), SimEnv(seed=2).rng("a").random(8))


def test_rng_returns_the_same_generator_object_per_name():
    env = SimEnv(seed=0)
    assert env.rng("x") is env.rng("x")


def test_run_includes_events_at_the_end_time_and_calls_finalizers():
    env = SimEnv()
    seen: list[int] = []
    ended: list[int] = []

    def proc():
        while True:
            seen.append(env.now)
            yield env.timeout(10)

    env.process(proc())
    env.at_end(ended.append)
    env.run(30)
    assert seen == [0, 10, 20, 30]
    assert ended == [30]


def test_recorder_splits_vectors_and_honours_selection():
    env = SimEnv(record={"y", "x"})
    env.record("y", 1.5, t_ns=0)
    env.record("x", [1.0, 2.0], t_ns=5)
    env.record("ignored", 3.0, t_ns=5)
    rec = env.recorder
    assert rec.names() == ["y", "x[0]", "x[1]"]
    assert rec.times["x[1]"] == [5]
    assert rec.values["x[1]"] == [2.0]


def test_next_id_counts_per_kind_and_per_run():
    env = SimEnv()
    assert [env.next_id("msg"), env.next_id("msg"), env.next_id("job")] == [0, 1, 0]
    assert SimEnv().next_id("msg") == 0


def test_recorder_stores_plain_numbers_and_numpy_scalars_alike():
    env = SimEnv()
    env.record("a", 1.5, t_ns=1)
    env.record("a", 2, t_ns=2)
    env.record("a", np.float64(2.5), t_ns=3)
    env.record("a", np.array(3.0), t_ns=4)
    assert env.recorder.values["a"] == [1.5, 2.0, 2.5, 3.0]
    assert all(type(v) is float for v in env.recorder.values["a"])


def test_call_entries_and_simpy_events_run_in_time_priority_and_id_order():
    from netsim.env import schedule_call

    env = SimEnv(seed=0)
    sim = env.sim
    order = []

    def proc():
        yield sim.timeout(5)
        order.append(("proc", sim.now))

    sim.process(proc())  # a simpy process: its Initialize event is due at 0 (URGENT), its timeout at 5 (NORMAL)
    schedule_call(sim, 5, 1, lambda e: order.append(("b", sim.now, e[1])), "x")  # scheduled after the process
    schedule_call(sim, 5, 0, lambda e: order.append(("a", sim.now, e[1])), "y")  # more urgent at the same time
    schedule_call(sim, 7, 2, lambda e: order.append(("c", sim.now, e[1])), None)
    schedule_call(sim, 9, 1, lambda e: order.append(("late", sim.now)), None)
    env.run(7)
    # (time, priority, id) order. Ids: the process start 0, 'b' 1, 'a' 2, 'c' 3, 'late' 4; the process's timeout
    # gets id 5 when the process starts at t=0. At t=5: 'a' (priority 0), then 'b' (1, id 1), then the timeout (1, id 5).
    assert order[:3] == [("a", 5, "y"), ("b", 5, "x"), ("proc", 5)]
    assert order[3] == ("c", 7, None)
    assert len(order) == 4  # the entry at 9 ns lies beyond the end
    assert sim.now == 8  # as simpy's run(until=7 + 1) leaves the clock


def test_an_exception_in_a_call_entry_propagates_unchanged():
    from netsim.env import run_events, schedule_call

    class Boom(Exception):
        def __init__(self, message, code):  # an extra argument: a copy built from args would fail
            super().__init__(message)
            self.code = code

    env = SimEnv(seed=0)

    def fail(_e):
        raise Boom("boom", 42)

    schedule_call(env.sim, 3, 1, fail)
    try:
        run_events(env.sim, 10)
    except Boom as exc:
        assert exc.code == 42 and env.sim.now == 3
    else:  # pragma: no cover - the loop must raise
        raise AssertionError("the exception did not propagate")


def test_same_instant_table_orders_dispatch_before_arbitration_before_deadline():
    from netsim.env import AIR, ARBITRATE, DEADLINE, DISPATCH, NORMAL, URGENT

    # the order the kernel and the media rely on (netsim.env docstring); URGENT/NORMAL are simpy's own
    assert URGENT < NORMAL < DISPATCH < AIR < ARBITRATE < DEADLINE
    assert (URGENT, NORMAL) == (simpy.events.URGENT, simpy.events.NORMAL)


def test_work_created_at_an_instant_runs_before_the_instants_higher_priorities():
    """A dispatch that releases more work at the same instant: that work (NORMAL, then a new DISPATCH) runs
    before the instant's arbitration, which was scheduled first; the deadline check comes last."""
    from netsim.env import ARBITRATE, DEADLINE, DISPATCH, NORMAL, schedule_call

    env = SimEnv(seed=0)
    sim = env.sim
    order: list[str] = []

    def dispatch(_e):
        order.append("dispatch")
        schedule_call(sim, 0, NORMAL, lambda e: (order.append("release"),
                                                  schedule_call(sim, 0, DISPATCH, lambda e: order.append("dispatch 2"))))

    schedule_call(sim, 4, DEADLINE, lambda e: order.append("deadline"))
    schedule_call(sim, 4, ARBITRATE, lambda e: order.append("arbitrate"))
    schedule_call(sim, 4, DISPATCH, dispatch)
    env.run(10)
    assert order == ["dispatch", "release", "dispatch 2", "arbitrate", "deadline"]
