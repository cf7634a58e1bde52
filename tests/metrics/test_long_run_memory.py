"""A long run with summary output keeps flat memory (issue 31 fault 6), the latency metric included.

The loop: dc_servo_can made a 1 ms loop (sensor every 1 ms, 0.1 ms + 0.05 ms after sending; controller 0.2 ms and
actuator 0.1 ms on message; CAN at 1 Mbit/s, no interference node), ``record: []`` and the latency metric over
sensor -> controller -> actuator, with ``output: {jobs: summary, messages: summary, schedule: off}``. Its latency is
the same in every period, 0.56 ms by hand: sensor 0.1 ms, an 80-bit frame at 1 Mbit/s 0.08 ms, controller
0.2 ms, a frame 0.08 ms, actuator 0.1 ms; so the mean of a long run must equal the short run's exactly.

Peak RSS is measured for the ``netsim`` child process alone (``os.wait4``'s resource usage of that child).
The default-suite test compares a 1 s and a 6 s run with small stream windows (so they are full after 0.3 s);
the slow test the 10 s and the 1000 s runs with the shipped windows (full after about 8 s).
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from typing import Any

import pytest
import yaml

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "dc_servo_can.yaml"
ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MPLBACKEND": "Agg"}


def loop_scenario(duration: str, mode: str = "summary") -> dict[str, Any]:
    """The 1 ms loop (module docstring) for ``duration``, its traces kept as ``mode``."""
    raw = yaml.safe_load(SCENARIO.read_text())
    raw["name"] = "long_loop"
    raw["duration"] = duration
    del raw["nodes"]["interference"]
    raw["networks"]["can"]["nodes"].remove("interference")
    raw["networks"]["can"]["bitrate"] = "1 Mbit/s"
    sensor = raw["nodes"]["sensor"]["tasks"][0]
    sensor.update(period="1 ms", execution="0.1 ms")
    sensor["params"]["after_send"] = "0.05 ms"
    control = raw["nodes"]["controller"]["tasks"][0]
    control.update(execution="0.2 ms", deadline="1 ms")
    control["params"]["h"] = "1 ms"
    raw["nodes"]["actuator"]["tasks"][0].update(execution="0.1 ms", deadline="1 ms")
    raw["record"] = []
    raw["metrics"] = [{"type": "latency", "params": {"chain": ["sensor.sample", "controller.control",
                                                               "actuator.actuate"]}}]
    raw["output"] = {"jobs": mode, "messages": mode, "schedule": "off" if mode != "full" else "on"}
    return raw


def peak_rss(folder: Path, duration: str, mode: str = "summary", windows: tuple[int, int] | None = None
             ) -> tuple[float, float, dict[str, float], float]:
    """Run the loop for ``duration`` in a child process; its peak RSS (MiB), wall time (s), latency metrics and CPU
    time (s).
    ``windows`` = (KEEP, BATCH) of the latency stream, set in the child before the run."""
    name = f"{mode}_{duration.replace(' ', '')}"
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(loop_scenario(duration, mode), sort_keys=False))
    keep, batch = windows or (None, None)
    code = textwrap.dedent(f"""
        import netsim, netsim.metrics.chain as chain
        if {keep!r} is not None:
            chain.KEEP, chain.BATCH = {keep!r}, {batch!r}
        result = netsim.run({str(path)!r}, write=False)
        for key, value in result.metrics.items():
            if key.startswith("latency."):
                print(key, repr(float(value)))
    """)
    out, err = folder / f"{name}.out", folder / f"{name}.err"
    t0 = time.monotonic()
    with out.open("w") as fo, err.open("w") as fe:
        proc = subprocess.Popen([sys.executable, "-c", code], env=ENV, stdout=fo, stderr=fe)
        _, status, usage = os.wait4(proc.pid, 0)  # this child's own peak, not the test process's other children
    proc.returncode = os.waitstatus_to_exitcode(status)
    wall = time.monotonic() - t0
    assert proc.returncode == 0, err.read_text()
    lines = out.read_text().splitlines()
    metrics = {line.split()[0]: float(line.split()[1]) for line in lines if line.startswith("latency.")}
    return usage.ru_maxrss / 1024, wall, metrics, usage.ru_utime + usage.ru_stime  # Linux: ru_maxrss in KiB


def test_summary_output_keeps_flat_memory_and_the_latency_of_a_short_run(tmp_path: Path) -> None:
    """Default suite: 1 s against 6 s with stream windows of 256 records (full after 0.3 s of this loop).
    Kept in full, the 5000 more periods would add about 15 MiB (5 rows a period, about 600 B a row:
    netsim.scenario.memory.ROW_BYTES), over the 10 % allowed here."""
    short_rss, _, short, _ = peak_rss(tmp_path, "1 s", windows=(256, 128))
    long_rss, _, long, _ = peak_rss(tmp_path, "6 s", windows=(256, 128))
    assert short["latency.count"] == 1000 and long["latency.count"] == 6000  # one chain per period
    assert long["latency.mean_s"] == short["latency.mean_s"] == pytest.approx(0.00056, abs=1e-12)
    assert long_rss <= 1.10 * short_rss, (short_rss, long_rss)


@pytest.mark.slow
def test_a_1000_s_run_of_a_1_ms_loop_stays_within_10_percent_of_the_10_s_run(tmp_path: Path) -> None:
    """Issue 31 fault 6, as stated: 1000 s simulated against 10 s, summary output, the latency metric on.
    Prints the figures for the note (pytest -s)."""
    short_rss, short_wall, short, short_cpu = peak_rss(tmp_path, "10 s")
    long_rss, long_wall, long, long_cpu = peak_rss(tmp_path, "1000 s")
    print(f"\nlong run: peak RSS {short_rss:.1f} MiB (10 s, {short_wall:.0f} s wall, {short_cpu:.0f} s CPU) -> "
          f"{long_rss:.1f} MiB (1000 s, {long_wall:.0f} s wall, {long_cpu:.0f} s CPU), latency count "
          f"{long['latency.count']:.0f}, mean "
          f"{long['latency.mean_s'] * 1e3:.3f} ms")
    assert long["latency.count"] == 1_000_000 and long["latency.mean_s"] == short["latency.mean_s"]
    assert long_rss <= 1.10 * short_rss, (short_rss, long_rss)
