"""JMAP reconstruction and the sigma_u / Ev metrics."""

import logging
import math

import numpy as np
import pytest

from netsim.models.cart.jmap import interval_bounds, reconstruct
from netsim.models.cart.metrics import cart_metrics, stationary_mask

H = 1e-3
T = np.arange(0.0, 1.5, H)
P = 0.5 * T + 0.02 * np.sin(3 * T)  # a known smooth trajectory
V = 0.5 + 0.06 * np.cos(3 * T)


@pytest.mark.parametrize("delta", [5e-5, 3.2e-3])
def test_jmap_recovers_smooth_trajectory_within_the_quantization_step(delta):
    counts = np.floor(P / delta + 0.5)
    rec = reconstruct(counts, H, delta, slack=0)
    assert rec.status == "Solved"
    # every sample's interval holds the truth and the estimate: |error| < delta
    assert np.max(np.abs(rec.p - P)) < delta
    # velocity: a smooth path through the intervals; away from the free ends the error stays below one
    # step per 10 ms (delta / 0.01 s), far below the 0.5 m/s speed
    inner = slice(100, -100)
    assert np.max(np.abs(rec.v[inner] - V[inner])) < delta / 0.01


def test_jmap_timing_relaxation_widens_the_tube_by_one_sample_of_motion():
    delta = 5e-5
    counts = np.floor(P / delta + 0.5)
    lo, hi = interval_bounds(counts, slack=1)
    # at 0.44..0.56 m/s one sample moves 8.8..11.2 steps (+-1 from quantization): the hull grows by that
    # on each side of the 1-step interval
    width = hi - lo
    assert np.all(width[1:-1] >= 1 + 2 * 7.8) and np.all(width <= 1 + 2 * 12.2)
    rec = reconstruct(counts, H, delta, slack=1)
    assert np.max(np.abs(rec.p - P)) < delta * (1 + 12)


def test_stationary_window_is_the_last_07_m():
    p = np.linspace(0, 1.2, 121)
    m = stationary_mask(p)
    assert p[m].min() == pytest.approx(0.3) and p[m].max() == pytest.approx(1.0)


def test_sigma_u_and_ev_by_hand():
    t = np.arange(0, 2.0, 1e-3)
    p = 0.8 * t
    v = np.full_like(t, 0.8)
    v[::2] = 0.808  # +1 % on every other sample -> RMS(v/vref - 1) = 0.01 / sqrt(2)
    u = np.where(np.arange(len(t)) % 2 == 0, 3.0, 1.0)  # mean 2, std 1 -> sigma_u = 0.5
    edges = np.arange(0, 2.0, 0.004)  # 250 events/s; Tfilter 8 ms -> 2 events per Tfilter
    m = cart_metrics(t, p, v, u, 0.8, edge_times=edges, tfilter=0.008, jmap=False)
    assert m["sigma_u"] == pytest.approx(0.5, rel=1e-3)
    assert m["Ev"] == pytest.approx(0.01 / math.sqrt(2), rel=1e-2)
    assert m["events_per_tfilter"] == pytest.approx(2.0, rel=0.01)
    assert m["reached"] == 1.0 and m["t_reach"] == pytest.approx(1.25)


def test_vref_zero_says_sigma_u_is_undefined(caplog):
    t = np.arange(0, 1.0, 1e-3)
    with caplog.at_level(logging.WARNING):
        m = cart_metrics(t, np.zeros_like(t), np.zeros_like(t), np.ones_like(t), 0.0)
    assert m["defined"] == 0.0 and math.isnan(m["sigma_u"]) and math.isnan(m["Ev"])
    assert "undefined" in caplog.text


def test_cart_that_never_reaches_1m_gives_nan_metrics(caplog):
    t = np.arange(0, 1.0, 1e-3)
    with caplog.at_level(logging.WARNING):
        m = cart_metrics(t, 0.5 * t, np.full_like(t, 0.5), np.ones_like(t), 0.8)
    assert m["reached"] == 0.0 and math.isnan(m["sigma_u"])
    assert "reached only 0.499 m" in caplog.text  # max of 0.5 t over t < 1 s
