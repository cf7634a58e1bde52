"""End-to-end scenarios: TrueTime's DC servo examples run through the whole stack (YAML -> run folder)."""

import numpy as np
import pandas as pd
import pytest

from netsim.runner import run

MS = 1e-3


def _chains(jobs: pd.DataFrame, messages: pd.DataFrame):
    """Sample-to-actuation chains rebuilt directly from the tables (independently of the latency metric)."""
    sens = jobs[(jobs.node == "sensor") & (jobs.task == "sample")]
    ctrl = jobs[(jobs.node == "controller") & (jobs.task == "control")]
    act = jobs[(jobs.node == "actuator") & (jobs.task == "actuate")]
    y_msgs = messages[(messages.sender == "sensor") & (messages.receiver == "controller")]
    u_msgs = messages[(messages.sender == "controller") & (messages.receiver == "actuator")]
    out = []
    for _, m1 in y_msgs.iterrows():
        s = sens[(sens.start_s <= m1.sent_s) & (sens.finish_s >= m1.sent_s)].iloc[0]
        c = ctrl[np.isclose(ctrl.release_s, m1.delivered_s)].iloc[0]
        m2 = u_msgs[(u_msgs.sent_s >= c.start_s) & (u_msgs.sent_s <= c.finish_s)].iloc[0]
        a = act[np.isclose(act.release_s, m2.delivered_s)]
        if a.empty or pd.isna(a.iloc[0].finish_s):
            continue  # chain cut by the end of the run
        a = a.iloc[0]
        out.append(dict(sample=s.start_s, sent_y=m1.sent_s, recv_y=m1.delivered_s, ctrl_start=c.start_s,
                        sent_u=m2.sent_s, recv_u=m2.delivered_s, act_finish=a.finish_s))
    return pd.DataFrame(out)


@pytest.mark.parametrize("scenario", ["scenarios/dc_servo_can.yaml", "scenarios/dc_servo_csma.yaml"])
def test_networked_servo_sample_to_actuation_latency_is_3_5_ms(scenario, tmp_path):
    result = run(scenario, out=tmp_path / "run", overrides={"duration": "0.5 s"}, plot=True)
    assert result.ok
    ch = _chains(result.jobs, result.messages)
    assert len(ch) == 50  # one chain per 10 ms sample in 0.5 s
    # TrueTime example arithmetic: sensor 0.5 ms, 80 bits at 80 kbit/s = 1 ms, controller 0.5 ms, 1 ms, actuator 0.5 ms
    np.testing.assert_allclose(ch.sent_y - ch["sample"], 0.5 * MS, atol=1e-12)
    np.testing.assert_allclose(ch.recv_y - ch.sent_y, 1.0 * MS, atol=1e-12)
    np.testing.assert_allclose(ch.ctrl_start - ch.recv_y, 0.0, atol=1e-12)
    np.testing.assert_allclose(ch.sent_u - ch.ctrl_start, 0.5 * MS, atol=1e-12)
    np.testing.assert_allclose(ch.recv_u - ch.sent_u, 1.0 * MS, atol=1e-12)
    np.testing.assert_allclose(ch.act_finish - ch["sample"], 3.5 * MS, atol=1e-12)
    # the registered latency metric agrees
    assert result.metrics["latency.mean_s"] == pytest.approx(3.5 * MS, abs=1e-12)
    assert result.metrics["latency.max_s"] == pytest.approx(3.5 * MS, abs=1e-12)
    assert {p.name for p in (tmp_path / "run").glob("*.png")} == {"responses.png", "schedule.png", "network.png"}


def test_servo_on_an_802154_radio_has_latency_within_the_csma_ca_bounds(tmp_path):
    result = run("scenarios/dc_servo_zigbee.yaml", out=tmp_path / "run", overrides={"duration": "1 s"})
    assert result.ok
    ch = _chains(result.jobs, result.messages)
    assert len(ch) == 100
    # per hop (802.15.4 defaults): backoff 0..7 x 320 us, CCA 128 us, turnaround 192 us, then 192 us of PHY
    # overhead + (80 payload + 88 MAC) bits at 250 kbit/s = 864 us on the air
    hop_min = (128 + 192 + 864) * 1e-6
    hop_max = hop_min + 7 * 320e-6
    for hop in (ch.recv_y - ch.sent_y, ch.recv_u - ch.sent_u):
        assert hop.min() >= hop_min - 1e-12 and hop.max() <= hop_max + 1e-12
        # the backoff slots are whole multiples of 320 us
        slots = np.round((hop - hop_min) / 320e-6)
        np.testing.assert_allclose(hop, hop_min + slots * 320e-6, atol=1e-12)
        assert slots.nunique() > 1  # random backoffs: the latency varies, unlike on CAN
    # sensor 0.5 ms, controller 0.5 ms, actuator 0.5 ms around the two hops
    lat = ch.act_finish - ch["sample"]
    assert lat.min() >= 1.5 * MS + 2 * hop_min - 1e-12 and lat.max() <= 1.5 * MS + 2 * hop_max + 1e-12
    assert result.metrics["net.bus.dropped"] == 0 and result.metrics["net.bus.retransmissions"] == 0


def test_interference_delays_and_eventually_starves_the_loop():
    share = {"nodes.interference.tasks[0].params.share": 0.5, "duration": "1 s"}
    half = run("scenarios/dc_servo_can.yaml", write=False, overrides=share)
    # interference frames are more urgent on CAN: control frames wait, latency rises above 3.5 ms
    assert half.metrics["latency.max_s"] > 3.5 * MS + 0.5 * MS
    full = run("scenarios/dc_servo_can.yaml", write=False,
               overrides={**share, "nodes.interference.tasks[0].params.share": 1.0})
    # an 80-bit frame every 1 ms fills the 80 kbit/s bus: no control frame ever wins arbitration
    assert full.metrics["latency.count"] == 0
    assert full.metrics["net.can.utilization"] > 0.99


def test_same_seed_gives_byte_identical_csvs(tmp_path):
    ov = {"nodes.interference.tasks[0].params.share": 0.5, "duration": "0.3 s"}
    a = run("scenarios/dc_servo_can.yaml", out=tmp_path / "a", overrides=ov)
    b = run("scenarios/dc_servo_can.yaml", out=tmp_path / "b", overrides=ov)
    c = run("scenarios/dc_servo_can.yaml", out=tmp_path / "c", overrides=ov, seed=a.meta["seed"] + 1)
    for name in ["signals.csv", "jobs.csv", "messages.csv", "metrics.csv", "scenario.yaml"]:
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name
    # the comparison can fail: the interference draws depend on the seed
    assert (tmp_path / "a" / "messages.csv").read_bytes() != (tmp_path / "c" / "messages.csv").read_bytes()


def test_ideal_servo_pid_follows_the_square_wave():
    result = run("scenarios/dc_servo_ideal.yaml", write=False)
    s = result.signals
    # first control value written at the end of the first job (2 ms): u = K*(b*r - y) = 0.96*0.5*1 (y = 0, I = D = 0)
    first_u = s.loc[s["u"].first_valid_index()]
    assert first_u.time_s == pytest.approx(2 * MS)
    assert first_u.u == pytest.approx(0.48)
    # settled within 2 % of the reference in the last 100 ms before every reference switch (every 0.5 s)
    for t0 in np.arange(0.0, 2.0, 0.5):
        win = s[(s.time_s >= t0 + 0.4) & (s.time_s < t0 + 0.5)]
        assert (win.r - win.y).abs().max() < 0.02
    assert result.metrics["task.computer.pid.deadline_misses"] == 0


def _late_window_errors(s: pd.DataFrame, y: str, duration: float):
    """max |r - y| in the last 100 ms before each reference switch (the square wave switches every 0.5 s)."""
    return [float((s.r - s[y])[(s.time_s >= t + 0.4) & (s.time_s < t + 0.5)].abs().max())
            for t in np.arange(0.0, duration, 0.5)]


def test_three_servos_under_dm_lowest_priority_misses_every_deadline_and_goes_unstable():
    result = run("scenarios/three_servos_dm.yaml", write=False)
    jobs = result.jobs[result.jobs.task == "pid1"]
    # the 4 ms and 5 ms tasks take 2/4 + 2/5 = 0.9 of the CPU; pid1 needs 2/6 more: every job after the
    # first (which finishes exactly at its deadline, 6 ms) is late or still unfinished past its deadline
    t_end = result.meta["t_end_s"]
    later = jobs[(jobs.release_s > 0) & (jobs.deadline_s <= t_end)]  # jobs whose deadline has come
    late = (later.deadline_met.astype(str) == "False") | (later.finish_s.isna() & (later.deadline_s < t_end))
    assert len(later) > 100 and late.all()
    for other in ("pid2", "pid3"):
        assert result.metrics[f"task.cpu.{other}.deadline_misses"] == 0
    # the loop of pid1 is unstable: its error grows by orders of magnitude window after window until the
    # plant state passes the divergence bound
    assert result.status.startswith("diverged at t = ")
    s = result.signals
    peaks = [float((s.r - s.y1)[(s.time_s >= t) & (s.time_s < t + 0.25)].abs().max()) for t in (0.25, 0.5, 0.75, 1.0)]
    assert all(b > 10 * a for a, b in zip(peaks, peaks[1:]))
    # the two higher-priority loops are fine
    for y in ("y2", "y3"):
        assert max(_late_window_errors(s[s.time_s < 1.0], y, 1.0)) < 0.05


def test_three_servos_under_edf_all_loops_stay_acceptable():
    edf = run("scenarios/three_servos_edf.yaml", write=False)
    assert edf.ok
    ideal = run("scenarios/dc_servo_ideal.yaml", write=False)
    # Acceptable means (1) no divergence, (2) each output settles to within 0.1 (5 % of the 2-unit reference
    # step) in the last 100 ms before every switch of the square wave, and (3) each loop's IAE is at most
    # twice that of the same PID running alone on its own CPU (dc_servo_ideal, T = 6 ms, C = 2 ms).
    for i in (1, 2, 3):
        assert max(_late_window_errors(edf.signals, f"y{i}", 2.0)) < 0.1
        assert edf.metrics[f"y{i}.IAE"] < 2.0 * ideal.metrics["y.IAE"]
    # ... even though, after the initial transient, every task misses its deadlines (TrueTime's README)
    for i in (1, 2, 3):
        assert edf.metrics[f"task.cpu.pid{i}.deadline_misses"] > 0.9 * edf.metrics[f"task.cpu.pid{i}.jobs"]
