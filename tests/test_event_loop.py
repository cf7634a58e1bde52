"""The event loop on simpy's extension points (netsim.env.EventLoop): simpy's own run(), plain simpy processes
beside kernels and networks, failures, cancellable calls, and no private simpy attribute outside netsim.env."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest
import simpy

from netsim.env import ARBITRATE, DEADLINE, DISPATCH, NORMAL, EventLoop, SimEnv, schedule_call
from netsim.kernel import Kernel
from netsim.network import Message, make_network
from netsim.results import jobs_table, messages_table, signals_table
from netsim.build.builder import build
from netsim.scenario.loader import load_scenario
from netsim.timebase import MS, S, US

ROOT = Path(__file__).resolve().parents[1]


def test_the_environment_is_a_simpy_environment_with_an_integer_clock():
    env = SimEnv()
    assert isinstance(env.sim, simpy.Environment) and isinstance(env.sim, EventLoop)
    env.sim.run(until=5)
    assert env.sim.now == 5 and env.now == 5


# ------------------------------------------------------------------ simpy's own run() on a shipped scenario
def _tables(sim) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    jobs = pd.concat([jobs_table(k.job_records, name) for name, k in sim.kernels.items()], ignore_index=True)
    msgs = messages_table([r for net in sim.networks.values() for r in net.records])
    rec = sim.env.recorder
    return jobs, msgs, signals_table(rec.times, rec.values, order=sim.scenario.record)


@pytest.mark.parametrize("name", ["dc_servo_can", "dc_servo_zigbee", "three_servos_edf"])
def test_simpys_own_run_gives_the_tables_of_the_netsim_loop(name):
    """Kernels, a network (CAN; a radio; none) and a plant, run by netsim's loop and by simpy's run()."""
    t_end = S // 5
    ours = build(load_scenario(ROOT / "scenarios" / f"{name}.yaml"))
    ours.run(until=t_end)
    theirs = build(load_scenario(ROOT / "scenarios" / f"{name}.yaml"))
    theirs.env.sim.run(until=t_end + 1)  # simpy stops before `until`: events at t_end are processed
    theirs.finish(t_end)
    jobs, msgs, signals = _tables(ours)
    assert len(jobs) > 0 and len(signals) > 0 and (len(msgs) > 0) == bool(ours.networks)
    for a, b in zip((jobs, msgs, signals), _tables(theirs)):
        pd.testing.assert_frame_equal(a, b)


# ------------------------------------------------------------------ a plain simpy process in a netsim run
def _loop_with_a_simpy_machine(run_with_simpy: bool) -> dict[str, list]:
    """TrueTime's networked loop (sensor -> controller -> actuator on CAN, 80 kbit/s, 80-bit frames: 1 ms per
    frame, 0.5 ms of CPU per node, period 10 ms) with plain simpy beside it: the actuator's output feeds a
    simpy.Store read by a machine process holding a simpy.Resource for 2 ms per part; an inspector process
    wants the machine at 4 ms; a traffic source sends one urgent CAN frame at 10.5 ms to a sink whose
    deliveries go into another Store."""
    env = SimEnv(seed=0)
    sim = env.sim
    nodes = ["sensor", "controller", "actuator", "source", "sink"]
    net = make_network(env, "can", "can", {"nodes": nodes, "bitrate": "80 kbit/s", "min_frame_bits": 80})
    kernels = {n: Kernel(env, n, policy="fp") for n in nodes[:3]}
    for n, k in kernels.items():
        k.attach_network(net)
        net.attach(n, k)
    parts, inbox = simpy.Store(sim), simpy.Store(sim)
    machine = simpy.Resource(sim, capacity=1)
    log: dict[str, list] = {"part": [], "busy": [], "idle": [], "inspect": [], "sink": []}

    class Sink:  # a network receiver that is not a kernel: it hands the message to simpy
        def deliver(self, network: str, msg: Message) -> None:
            inbox.put(msg)

    net.attach("sink", Sink())
    kernels["sensor"].attach_analog_in("y", lambda t: float(t))
    kernels["actuator"].attach_analog_out("u", lambda t, v: parts.put(v))  # a netsim callback feeds simpy

    def sensor(job):
        y = yield job.analog_in("y")
        yield job.execute(500 * US)
        yield job.send("can", "controller", y, 80, priority=2)

    def controller(job):
        msg = yield job.receive("can")
        yield job.execute(500 * US)
        yield job.send("can", "actuator", msg.payload, 80, priority=1)

    def actuator(job):
        msg = yield job.receive("can")
        yield job.execute(500 * US)
        yield job.analog_out("u", msg.payload)

    kernels["sensor"].create_task("sample", sensor, period=10 * MS, priority=1)
    kernels["controller"].create_task("control", controller, priority=1)
    kernels["actuator"].create_task("actuate", actuator, priority=1)
    kernels["controller"].bind_receive("can", "control")
    kernels["actuator"].bind_receive("can", "actuate")

    def machine_proc():
        while True:
            value = yield parts.get()
            log["part"].append((sim.now, value))
            with machine.request() as req:
                yield req
                log["busy"].append(sim.now)
                yield sim.timeout(2 * MS)
            log["idle"].append(sim.now)

    def inspector():
        yield sim.timeout(4 * MS)
        with machine.request() as req:
            yield req
            log["inspect"].append(sim.now)
            yield sim.timeout(1 * MS)

    def source():
        yield sim.timeout(10 * MS + 500 * US)  # the instant the sensor of the second period sends
        net.send(Message("source", "sink", "urgent", 80, 0, tag="urgent"))

    def sink_reader():
        while True:
            msg = yield inbox.get()
            log["sink"].append((sim.now, msg.payload))

    for gen in (machine_proc(), inspector(), source(), sink_reader()):
        sim.process(gen)
    t_end = 35 * MS
    if run_with_simpy:
        sim.run(until=t_end + 1)
        env.finish(t_end)
    else:
        env.run(t_end)
    return log


@pytest.mark.parametrize("run_with_simpy", [False, True], ids=["netsim loop", "simpy run"])
def test_plain_simpy_processes_interleave_with_kernels_and_networks(run_with_simpy):
    log = _loop_with_a_simpy_machine(run_with_simpy)
    # By hand. Period k (release 10k ms): sample, 0.5 ms CPU, 1 ms frame, 0.5 ms, 1 ms frame, 0.5 ms: the
    # actuator writes the sample time at 10k + 3.5 ms, and the machine (a simpy process waiting on the Store)
    # gets the part at that very instant.
    # Period 1: the source's frame (priority 0) is sent at 10.5 ms, the instant the sensor sends its own
    # (priority 2): a simpy timeout is NORMAL, before the bus arbitrates (ARBITRATE), so both compete and the
    # source's goes first (10.5 -> 11.5 ms, then into the sink's Store at 11.5 ms); the sensor's frame waits
    # 1 ms: the loop delay of that period is 4.5 ms.
    assert log["sink"] == [(11_500 * US, "urgent")]
    assert log["part"] == [(3_500 * US, 0.0), (14_500 * US, float(10 * MS)), (23_500 * US, float(20 * MS)),
                           (33_500 * US, float(30 * MS))]
    # the machine (capacity 1) is held 2 ms per part; the inspector asks at 4 ms and gets it when the first
    # part is done, at 3.5 + 2 = 5.5 ms; the last part (33.5 ms) is still on it at the end (35 ms)
    assert log["busy"] == [3_500 * US, 14_500 * US, 23_500 * US, 33_500 * US]
    assert log["idle"] == [5_500 * US, 16_500 * US, 25_500 * US]
    assert log["inspect"] == [5_500 * US]


# ------------------------------------------------------------------ failures
class Boom(Exception):
    def __init__(self, message: str, code: int) -> None:  # an extra argument: a copy built from args fails
        super().__init__(message)
        self.code = code


def test_a_failed_process_is_handed_to_the_process_waiting_for_it():
    env = SimEnv()
    sim = env.sim
    caught = []

    def worker():
        yield sim.timeout(3)
        raise ValueError("worn out")  # simpy throws a copy into the waiting process: one built from args

    def supervisor():
        try:
            yield sim.process(worker())
        except ValueError as exc:
            caught.append((sim.now, str(exc)))
        yield sim.timeout(2)
        caught.append((sim.now, "after"))

    sim.process(supervisor())
    env.run(10)  # simpy semantics: the supervisor handles the failure, the run goes on
    assert caught == [(3, "worn out"), (5, "after")]


@pytest.mark.parametrize("run_with_simpy", [False, True], ids=["netsim loop", "simpy run"])
def test_an_unhandled_failure_raises_the_original_exception(run_with_simpy):
    env = SimEnv()
    sim = env.sim

    def worker():
        yield sim.timeout(3)
        raise Boom("worn out", 7)

    sim.process(worker())
    with pytest.raises(Boom) as info:
        sim.run(until=11) if run_with_simpy else env.run(10)
    assert info.value.code == 7 and sim.now == 3


# ------------------------------------------------------------------ calls and priorities
def test_call_at_runs_at_its_time_and_priority_and_cancel_drops_it():
    env = SimEnv()
    sim = env.sim
    order = []
    sim.call_at(5, order.append, "deadline", priority=DEADLINE)
    sim.call_at(5, order.append, "dispatch", priority=DISPATCH)
    dropped = sim.call_at(5, order.append, "cancelled", priority=NORMAL)
    sim.call_later(5, lambda a, b: order.append(a + b), "norm", "al")  # NORMAL by default
    sim.call_at(3, dropped.cancel)
    env.run(10)
    assert order == ["normal", "dispatch", "deadline"]
    with pytest.raises(ValueError, match="before now"):
        sim.call_at(2, order.append, "past")
    with pytest.raises(ValueError, match="negative delay"):
        sim.call_later(-1, order.append, "past")


def test_event_at_resumes_a_process_at_its_row_of_the_same_instant_table():
    env = SimEnv()
    sim = env.sim
    order = []

    def proc():
        yield sim.event_at(4, ARBITRATE)
        order.append(("arbitrate", sim.now))

    sim.process(proc())
    schedule_call(sim, 4, DEADLINE, lambda item: order.append(("deadline", sim.now)))
    schedule_call(sim, 4, DISPATCH, lambda item: order.append(("dispatch", sim.now)))
    env.run(4)
    assert order == [("dispatch", 4), ("arbitrate", 4), ("deadline", 4)]


def test_simpys_step_runs_one_entry_at_a_time():
    env = SimEnv()
    sim = env.sim
    order = []
    schedule_call(sim, 2, NORMAL, lambda item: order.append(item[1]), "b")
    schedule_call(sim, 1, NORMAL, lambda item: order.append(item[1]), "a")
    sim.step()
    assert order == ["a"] and sim.now == 1
    sim.step()
    assert order == ["a", "b"] and sim.now == 2
    with pytest.raises(simpy.core.EmptySchedule):
        sim.step()
    assert sim.events_scheduled() == 2


# ------------------------------------------------------------------ no private simpy attribute elsewhere
# simpy's private attributes: the clock, the heap, the id counter, the active process, an event's state
_PRIVATE = re.compile(r"\b(?:sim|_sim)\._(?:now|queue|eid|active_proc)\b|\._(?:ok|defused)\b"
                      r"|getattr\([^)]*\bsim\b[^)]*['\"]_(?:now|queue|eid|active_proc)['\"]")
_NOT_YET: set[str] = set()  # every module outside netsim/env.py uses the public API


def test_no_private_simpy_attribute_outside_the_env_module():
    hits = []
    for path in sorted([*(ROOT / "netsim").rglob("*.py"), *(ROOT / "models").rglob("*.py")]):
        rel = path.relative_to(ROOT).as_posix()
        if rel == "netsim/env.py" or rel in _NOT_YET:
            continue
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if _PRIVATE.search(line):
                hits.append(f"{rel}:{n}: {line.strip()}")
    assert hits == []


# ------------------------------------------------------------------ the README's example
def test_the_readmes_simpy_process_example_prints_what_the_readme_says(capsys, monkeypatch):
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text[text.index("### A plain simpy process in a netsim run"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    claimed = re.search(r"It prints `([^`]*)`", section).group(1)
    monkeypatch.chdir(ROOT)  # the example names the scenario relative to the repository
    exec(compile(code, "README.md", "exec"), {"__name__": "readme_example"})
    assert capsys.readouterr().out.strip() == claimed
    # the claim itself, by hand: an 80-bit frame at 80 kbit/s takes 1 ms; the sensor's frame, sent at the
    # instant of the burst, waits for it: 1 ms + 1 ms
    assert claimed == "100 bursts; sensor frame delay 2000000 to 2000000 ns"
