"""Simple links: delay distributions, queueing at a data rate (M/D/1, M/M/1), loss models, reordering."""

import math

import numpy as np
import pytest

from netsim.env import SimEnv
from netsim.errors import ConfigError
from netsim.network import Message, make_network
from netsim.timebase import MS, US

AB = ["a", "b"]


def _periodic(b, n, every_ns, bits=100, sender="a", receiver="b"):
    env, net = b.env, b.net

    def src():
        for k in range(n):
            net.send(Message(sender, receiver, k, bits))
            yield env.timeout(every_ns)

    env.process(src())


def _delays_ms(b):
    return np.array([r.delay_ns for r in b.net.records if r.delay_ns is not None]) / MS


def test_constant_delay_link_without_bitrate(bench):
    b = bench("link", {"nodes": AB, "delay": "2 ms"})
    b.send_at(1 * MS, "a", "b", 1000, tag="x")
    b.run(10 * MS)
    r = b.record("x")
    assert (r.sent_ns, r.tx_start_ns, r.tx_end_ns, r.delivered_ns) == (1 * MS, 1 * MS, 1 * MS, 3 * MS)


def test_ideal_link_delivers_in_the_same_instant_but_through_an_event(bench):
    b = bench("ideal", {"nodes": AB})
    b.send_at(7 * US, "a", "b", 10, tag="x")
    b.run(1 * MS)
    assert b.deliveries("b") == [(7 * US, "x")]


def test_uniform_delay_has_the_right_range_and_mean(bench):
    b = bench("link", {"nodes": AB, "delay": {"dist": "uniform", "low": "1 ms", "high": "3 ms"},
                       "reorder": True}, seed=3)
    _periodic(b, 4000, 100 * US)
    b.run(1000 * MS)
    d = _delays_ms(b)
    assert len(d) == 4000 and d.min() >= 1.0 and d.max() <= 3.0
    # mean 2 ms; std 2/sqrt(12) = 0.577 ms -> standard error 0.009 ms over 4000 draws
    assert d.mean() == pytest.approx(2.0, abs=0.04)


def test_shifted_exponential_and_gamma_delays_match_their_moments(bench):
    b = bench("link", {"nodes": AB, "reorder": True,
                       "delay": {"dist": "exponential", "mean": "2 ms", "shift": "0.5 ms"}}, seed=5)
    _periodic(b, 4000, 100 * US)
    b.run(2000 * MS)
    d = _delays_ms(b)
    assert d.min() >= 0.5
    assert d.mean() == pytest.approx(2.5, abs=0.12)  # shift + mean; SE = 2 ms / sqrt(4000) = 0.03 ms
    g = bench("link", {"nodes": AB, "reorder": True,
                       "delay": {"dist": "shifted_gamma", "shape": 4.0, "scale": "0.5 ms", "shift": "1 ms"}},
              seed=5)
    _periodic(g, 4000, 100 * US)
    g.run(2000 * MS)
    d = _delays_ms(g)
    # gamma(k=4, theta=0.5 ms): mean 2 ms, variance 1 ms^2; plus the 1 ms shift
    assert d.min() >= 1.0
    assert d.mean() == pytest.approx(3.0, abs=0.06)
    assert d.var() == pytest.approx(1.0, rel=0.1)


def test_empirical_delays_from_a_csv_file(bench, tmp_path):
    f = tmp_path / "measured.csv"
    f.write_text("run,delay_ms\n1,1.0\n2,2.5\n3,4.0\n")
    b = bench("link", {"nodes": AB, "reorder": True,
                       "delay": {"dist": "empirical", "file": str(f), "column": "delay_ms", "unit": "ms"}})
    _periodic(b, 3000, 100 * US)
    b.run(1000 * MS)
    d = _delays_ms(b)
    values, counts = np.unique(d, return_counts=True)
    assert values.tolist() == [1.0, 2.5, 4.0]
    assert np.all(np.abs(counts / 3000 - 1 / 3) < 0.04)  # resampled uniformly


def test_empirical_delay_file_problems_are_config_errors(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("delay\n0.001\n-0.002\n")
    cases = [
        ({"dist": "empirical", "file": str(tmp_path / "nope.csv")}, "does not exist"),
        ({"dist": "empirical", "file": str(bad), "column": "d"}, "no column 'd'"),
        ({"dist": "empirical", "file": str(bad), "column": "delay"}, "line 3: time -0.002 must be"),
        ({"dist": "empirical"}, "exactly one of"),
    ]
    for spec, match in cases:
        with pytest.raises(ConfigError, match=match):
            make_network(SimEnv(), "l", "link", {"nodes": AB, "delay": spec})


def _poisson_queue(service, n, seed):
    """Poisson arrivals (rate 0.8 / ms) into a 1 Mbit/s link; mean service 1 ms (1000 bits)."""
    env = SimEnv(seed=seed)
    net = make_network(env, "q", "link", {"nodes": AB, "bitrate": 1_000_000, "queue_limit": 100_000})
    net.attach("b", type("R", (), {"deliver": lambda self, nw, m: None})())
    arrivals, sizes = env.rng("test.arrivals"), env.rng("test.sizes")

    def src():
        for _ in range(n):
            yield env.timeout(int(round(arrivals.exponential(1.25 * MS))))
            bits = 1000 if service == "deterministic" else max(1, int(round(sizes.exponential(1000))))
            net.send(Message("a", "b", None, bits))

    env.process(src())
    env.run(int(n * 1.25 * MS * 1.2))
    waits = np.array([r.tx_start_ns - r.sent_ns for r in net.records]) / MS
    return waits.mean(), {**net.metrics(env.now), "t_end_ns": env.now}


def test_md1_mean_waiting_time_at_load_08():
    # M/D/1 (Pollaczek-Khinchine): Wq = rho / (2 mu (1 - rho)); rho = 0.8, 1/mu = 1 ms -> 2.0 ms.
    # Across seeds the 40 000-message estimate scatters by about 4 % (1 sigma): tolerance 12 %.
    rho, service_ms = 0.8, 1.0
    expected = rho * service_ms / (2 * (1 - rho))
    w, m = _poisson_queue("deterministic", 40_000, seed=11)
    assert w == pytest.approx(expected, rel=0.12)
    # every frame kept the link busy for exactly 1 ms
    assert m["utilization"] * m["t_end_ns"] == pytest.approx(40_000 * MS)


def test_mm1_mean_waiting_time_with_exponential_service():
    # M/M/1: Wq = rho / (mu (1 - rho)) = 0.8 * 1 ms / 0.2 = 4.0 ms (sizes exponential, mean 1000 bits)
    rho, service_ms = 0.8, 1.0
    expected = rho * service_ms / (1 - rho)
    w, _ = _poisson_queue("exponential", 40_000, seed=12)
    assert w == pytest.approx(expected, rel=0.12)


def test_gilbert_elliott_long_run_loss_rate_and_burst_length(bench):
    p_gb, p_bg = 0.05, 0.25
    b = bench("ideal", {"nodes": AB, "loss": {"model": "gilbert_elliott", "p_good_to_bad": p_gb,
                                              "p_bad_to_good": p_bg}}, seed=4)
    _periodic(b, 60_000, 10 * US)
    b.run(1000 * MS)
    lost = np.array([r.dropped for r in b.net.records])
    # stationary chain: pi_bad = p_gb / (p_gb + p_bg) = 1/6 is the loss rate (loss_bad = 1, loss_good = 0)
    assert lost.mean() == pytest.approx(p_gb / (p_gb + p_bg), abs=0.015)
    # a burst is a stay in the bad state: geometric with mean 1 / p_bg = 4 copies
    edges = np.diff(np.concatenate([[0], lost.astype(int), [0]]))
    bursts = np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)
    assert bursts.mean() == pytest.approx(1 / p_bg, abs=0.3)
    assert b.net.metrics(1000 * MS)["dropped.lost"] == lost.sum()


def test_bernoulli_loss_rate(bench):
    b = bench("ideal", {"nodes": AB, "loss": {"model": "bernoulli", "p": 0.2}}, seed=2)
    _periodic(b, 20_000, 10 * US)
    b.run(1000 * MS)
    lost = np.array([r.dropped for r in b.net.records])
    assert lost.mean() == pytest.approx(0.2, abs=3 * math.sqrt(0.2 * 0.8 / 20_000) + 0.002)


def test_without_reordering_copies_keep_their_order(bench):
    b = bench("link", {"nodes": AB, "delay": {"dist": "uniform", "low": "0 ms", "high": "5 ms"}}, seed=1)
    _periodic(b, 500, 1 * MS)
    b.run(1000 * MS)
    seqs = [m.seq for _, m in b.rx["b"].got]
    assert seqs == list(range(500))


def test_reordering_with_stale_drop_delivers_only_fresh_messages(bench):
    spec = {"dist": "uniform", "low": "0 ms", "high": "5 ms"}
    b = bench("link", {"nodes": AB, "delay": spec, "reorder": True}, seed=1)
    _periodic(b, 500, 1 * MS)
    b.run(1000 * MS)
    seqs = [m.seq for _, m in b.rx["b"].got]
    assert sorted(seqs) == list(range(500)) and seqs != sorted(seqs)  # out of order arrivals happen
    s = bench("link", {"nodes": AB, "delay": spec, "reorder": True, "drop_stale": True}, seed=1)
    _periodic(s, 500, 1 * MS)
    s.run(1000 * MS)
    fresh = [m.seq for _, m in s.rx["b"].got]
    assert all(x < y for x, y in zip(fresh, fresh[1:]))
    stale = [r for r in s.net.records if r.drop_reason == "stale"]
    assert len(stale) + len(fresh) == 500 and len(stale) > 0
    # same seed: the same arrival order, so exactly the copies that arrived late are dropped
    late = sum(1 for i, x in enumerate(seqs) if x < max(seqs[:i], default=-1))
    assert len(stale) == late
