"""Benchmark: dc_servo_can over 10 s simulated (in process and through the CLI), events per second.

Run with ``pytest -m benchmark -s tests/benchmarks/test_bench_run.py``. Speed is printed, and put as a
ratio against a bare simpy loop of the same number of timeouts measured in the same process.
"""

import subprocess
import sys
import time
from pathlib import Path

import pytest
import simpy

from netsim.runner import run

ROOT = Path(__file__).resolve().parents[2]


def _bare_simpy(n_events: int) -> float:
    env = simpy.Environment()

    def proc():
        for _ in range(n_events):
            yield env.timeout(1)

    env.process(proc())
    t0 = time.perf_counter()
    env.run()
    return time.perf_counter() - t0


@pytest.mark.benchmark
def test_bench_dc_servo_can_10s(tmp_path):
    scenario = ROOT / "scenarios" / "dc_servo_can.yaml"
    run(scenario, write=False, overrides={"duration": "0.1 s"})  # warm-up: imports, registry
    for label, ov in (("no interference", {}), ("interference share 0.5", {"nodes.interference.tasks[0].params.share": 0.5})):
        t0 = time.perf_counter()
        result = run(scenario, out=tmp_path / label.replace(" ", "_"), overrides={"duration": "10 s", **ov})
        wall = time.perf_counter() - t0
        sim_wall = result.meta["wall_time_s"]
        events = int(result.meta["events"])
        bare = _bare_simpy(events)
        print(f"\n[bench] dc_servo_can 10 s simulated, {label}: run() wall {wall:.2f} s "
              f"(build+simulate+collect {sim_wall:.2f} s), {events} simpy events, "
              f"{events / wall:,.0f} events/s; bare simpy loop of the same events {bare:.3f} s "
              f"-> ratio {wall / bare:.1f}x; jobs {len(result.jobs)}, messages {len(result.messages)}, "
              f"signal rows {len(result.signals)}")
        assert result.ok


@pytest.mark.benchmark
def test_bench_cli_run_dc_servo_can_10s(tmp_path):
    cmd = [sys.executable, "-m", "netsim", "run", str(ROOT / "scenarios" / "dc_servo_can.yaml"),
           "--out", str(tmp_path / "cli"), "--set", "duration=10 s"]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    print(f"\n[bench] `netsim run dc_servo_can.yaml` (10 s simulated) wall {wall:.2f} s, exit {proc.returncode}")
    if proc.returncode != 0:
        print(proc.stderr[-2000:])
    assert (tmp_path / "cli" / "signals.csv").exists()
