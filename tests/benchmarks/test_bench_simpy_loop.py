"""netsim against a networked control loop written by hand in plain simpy (issue 29, second row).

Opt in: ``pytest -m benchmark -s tests/benchmarks/test_bench_simpy_loop.py``.

The loop, the same in both: a sensor task samples the DC servo ``1000 / (s (s + 1))`` every 1 ms and sends the
reading over a link of constant 0.1 ms delay to an event-driven PD controller (K = 1, Td = 0.04 s, N = 100,
h = 1 ms, square reference of amplitude 1 and period 1 s), which sends its output over the same link to an
event-driven actuator that writes it to the plant's input; the plant is propagated exactly (zero-order hold,
matrix exponential) between the instants it is read or written; 10 s simulated, no execution times.

The plain simpy model (:func:`_plain_simpy_loop`) is written here, as a user of simpy would write it: one
process per node, a store per inbox, a link as a timeout whose callback puts the message in the receiver's
store; the ZOH matrices of each step length are computed on first use (two lengths: 0.8 ms and 0.2 ms). netsim
runs the equivalent scenario (:func:`_scenario`, built here, not shipped).

Printed, as CPU-time medians of interleaved rounds in one process (the machine is shared; the load average is
printed): netsim's build + event loop, and its event loop alone, each over the plain simpy model (set-up + run);
heap entries and Python calls (cProfile's count, builtins included) per period of both. Asserted: the two loops
give the same plant trajectory, every sensor reading and every applied input equal to 1e-9 of the signal's
scale, so the ratio compares the same work.
"""

from __future__ import annotations

import cProfile
import os
import pstats
import statistics
import time
from typing import Any

import numpy as np
import pytest
import scipy.linalg
import simpy

from netsim.scenario import build, load_scenario

MS = 1_000_000
PERIOD = 1 * MS
DELAY = MS // 10
SECONDS = 10
T_END = SECONDS * 1_000_000_000
GAIN, POLE = 1000.0, 1.0
K, TD, N = 1.0, 0.04, 100.0


def _scenario() -> dict[str, Any]:
    """The loop as a netsim scenario (three one-task nodes on an ideal-rate link of 0.1 ms delay)."""
    def task(name: str, program: str, params: dict[str, Any], **timing: Any) -> dict[str, Any]:
        return {"tasks": [{"name": name, "program": program, "priority": 1, "params": params, **timing}]}

    return {
        "name": "bench_simpy_loop", "seed": 1, "duration": f"{SECONDS} s",
        "plant": {"model": "dc_servo", "params": {"gain": GAIN, "a": POLE}},
        "io": {"y": {"type": "adc", "output": 0}, "u": {"type": "dac", "input": 0}},
        "signals": {"r": {"type": "square", "amplitude": 1.0, "period": "1 s"}},
        "nodes": {
            "sensor": task("sample", "sampler", {"channel": "y", "network": "net", "to": "controller",
                                                 "record_as": "ys"}, period="1 ms"),
            "controller": task("control", "controller", {"network": "net", "to": "actuator", "reference": "r",
                                                          "K": K, "Td": TD, "N": N, "h": "1 ms"},
                               release="on_message:net"),
            "actuator": task("actuate", "actuator", {"network": "net", "channel": "u", "record_as": "ua"},
                             release="on_message:net"),
        },
        "networks": {"net": {"type": "link", "nodes": ["sensor", "controller", "actuator"], "delay": "0.1 ms"}},
        "record": ["ys", "ua"],
    }


def _plain_simpy_loop() -> tuple[simpy.Environment, list[float], list[float]]:
    """The loop in plain simpy: returns the environment, the sensor readings and the applied inputs."""
    A = np.array([[0.0, 1.0], [0.0, -POLE]])
    B = np.array([0.0, GAIN])
    zoh: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    plant = {"x": np.zeros(2), "t": 0, "u": 0.0}

    def advance(t: int) -> None:  # exact ZOH propagation from the last instant to t
        dt = t - plant["t"]
        if dt:
            m = zoh.get(dt)
            if m is None:
                aug = np.zeros((3, 3))
                aug[:2, :2] = A * (dt * 1e-9)
                aug[:2, 2] = B * (dt * 1e-9)
                e = scipy.linalg.expm(aug)
                m = zoh[dt] = (e[:2, :2], e[:2, 2])
            plant["x"] = m[0] @ plant["x"] + m[1] * plant["u"]
            plant["t"] = t

    env = simpy.Environment()
    to_controller, to_actuator = simpy.Store(env), simpy.Store(env)
    readings: list[float] = []
    applied: list[float] = []

    def link(store: simpy.Store, value: float) -> None:  # constant delay, then the receiver's inbox
        env.timeout(DELAY, value).callbacks.append(lambda ev: store.put(ev.value))

    def sensor():
        while True:
            advance(env.now)
            y = float(plant["x"][0])
            readings.append(y)
            link(to_controller, y)
            yield env.timeout(PERIOD)

    ad = TD / (TD + N * PERIOD * 1e-9)
    bd = K * N * ad

    def controller():
        d, y_old = 0.0, None
        while True:
            y = yield to_controller.get()
            r = 1.0 if env.now % 1_000_000_000 < 500_000_000 else -1.0  # square wave, period 1 s
            d = ad * d - bd * (y - (y if y_old is None else y_old))  # PD, derivative filtered, on -y
            y_old = y
            link(to_actuator, K * (r - y) + d)

    def actuator():
        while True:
            u = yield to_actuator.get()
            advance(env.now)
            plant["u"] = u
            applied.append(u)

    for proc in (sensor, controller, actuator):
        env.process(proc())
    env.run(until=T_END + 1)
    return env, readings, applied


def _netsim_loop(scenario: Any) -> tuple[Any, float]:
    """Build and run the netsim loop; returns the simulation and the event loop's CPU time."""
    sim = build(scenario)
    t0 = time.process_time()
    sim.run()
    return sim, time.process_time() - t0


def _cpu(fn: Any) -> float:
    t0 = time.process_time()
    fn()
    return time.process_time() - t0


def _calls(fn: Any) -> int:
    prof = cProfile.Profile()
    prof.enable()
    fn()
    prof.disable()
    return int(pstats.Stats(prof).total_calls)  # type: ignore[attr-defined]


@pytest.mark.benchmark
def test_bench_netsim_against_plain_simpy_loop():
    scenario = load_scenario(_scenario())  # validated once: the figures compare building and running
    sim, _ = _netsim_loop(scenario)  # warm-up (imports, registry) and the trajectory check
    env, readings, applied = _plain_simpy_loop()
    periods = T_END // PERIOD + 1
    ys = np.asarray(sim.env.recorder.values["ys"])
    ua = np.asarray(sim.env.recorder.values["ua"])
    assert len(ys) == len(readings) == periods and len(ua) == len(applied) == periods - 1
    # the same plant trajectory in both loops: every reading and every applied input
    scale_y = max(1.0, float(np.max(np.abs(readings))))
    scale_u = max(1.0, float(np.max(np.abs(applied))))
    dy = float(np.max(np.abs(ys - readings)))
    du = float(np.max(np.abs(ua - applied)))
    assert dy <= 1e-9 * scale_y and du <= 1e-9 * scale_u

    load = os.getloadavg()
    whole, loop, plain = [], [], []
    for _ in range(5):  # interleaved rounds
        plain.append(_cpu(_plain_simpy_loop))
        t0 = time.process_time()
        _, t_loop = _netsim_loop(scenario)
        whole.append(time.process_time() - t0)
        loop.append(t_loop)
    med = statistics.median
    heap_netsim = build(scenario)
    calls_netsim = _calls(heap_netsim.run)
    entries_netsim = heap_netsim.env.sim.events_scheduled()
    calls_plain = _calls(_plain_simpy_loop)
    entries_plain = int(repr(_plain_simpy_loop()[0]._eid)[6:-1])  # itertools.count's repr: "count(n)"
    print(f"\n[bench] networked loop (1 ms period, 0.1 ms link, PD, exact plant, {SECONDS} s = {periods} periods); "
          f"load average {load[0]:.2f} before, {os.getloadavg()[0]:.2f} after; CPU medians of 5 interleaved rounds")
    print(f"[bench]   plain simpy (set-up + run) {med(plain) * 1e3:.0f} ms; netsim build + event loop "
          f"{med(whole) * 1e3:.0f} ms, event loop alone {med(loop) * 1e3:.0f} ms")
    print(f"[bench]   netsim / plain simpy: build + loop {med(whole) / med(plain):.2f}x, event loop alone "
          f"{med(loop) / med(plain):.2f}x (issue 29 target <= 1.5x)")
    print(f"[bench]   per period: netsim {entries_netsim / periods:.1f} heap entries, {calls_netsim / periods:.0f} "
          f"calls (cProfile, event loop); plain simpy {entries_plain / periods:.1f} heap entries, "
          f"{calls_plain / periods:.0f} calls")
    print(f"[bench]   same trajectory: readings within {dy:.1e}, inputs within {du:.1e}")
