"""The cart report's verdicts: break-point logic, stop-phase criterion, measures, and numbers quoted = run data."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from netsim.models.cart.claims import (
    EVENT,
    LTI,
    OSC_THRESHOLD,
    break_point,
    claims,
    describe_break,
    fmt,
    headline,
    pool_sigma,
    pooling_difference,
)
from netsim.models.cart.metrics import STOP_WINDOW, cart_metrics, stop_rms

REPORT = Path(__file__).resolve().parents[3] / "reports" / "cart"
WCS = (5, 10, 20, 40, 80)


# ------------------------------------------------------------------------------------------ break point
def test_break_below_the_first_wc_tested_is_not_reported_as_between_5_and_10():
    # event-based already below LTI at wc = 5: the break is at or below 5, the data cannot place it
    assert break_point(WCS, [1, 2, 3, 4, 5], [0.5, 1, 1, 1, 1]) == (None, 5)
    assert "at or below wc = 5" in describe_break(None, 5)


def test_break_between_two_tested_wcs_and_never():
    assert break_point(WCS, [1, 2, 3, 4, 5], [2, 1, 1, 1, 1]) == (5, 10)
    assert describe_break(5, 10) == "between wc = 5 and 10"
    assert break_point(WCS, [1, 1, 1, 1, 1], [2, 2, 2, 2, 2]) == (80, None)
    assert "above wc = 80" in describe_break(80, None)
    # order of the input does not matter
    assert break_point((80, 5, 10, 40, 20), [5, 1, 2, 4, 3], [1, 2, 1, 1, 1]) == (5, 10)
    with pytest.raises(ValueError):
        break_point(WCS, [1, 2], [1, 2, 3])


# ------------------------------------------------------------------------------------------ synthetic runs
def _synthetic(rng: np.random.Generator, *, break_at: int = 10, unstable: tuple[str, ...] = EVENT[:2]) -> pd.DataFrame:
    """A Fig. 2 run table with known values: event sigma_u below LTI from ``break_at`` on, the controllers
    in ``unstable`` oscillating at wc = 80, Full Event tracking best by JMAP Ev but Position Prediction best
    by the true velocity."""
    rows = []
    for c in LTI + EVENT:
        for w in WCS:
            for s in (1, 2, 3):
                lti = c in LTI
                sig = (0.1 * w) if lti else (0.2 * w if w < break_at else 0.01 * w)
                mean_u = 2.0 + 0.1 * rng.standard_normal()
                evj = 0.01 * (0.5 if c == "full_event" else 1.0) * (1 + 0.1 * rng.random())
                ev = 0.01 * (0.3 if c == "position_prediction" else 1.0) * (1 + 0.1 * rng.random())
                stop = 0.25 if (c in unstable and w == 80) else (0.04 if (lti and w == 80) else 0.0)
                rows.append(dict(controller=c, wc=w, q=6, vref=0.8, seed=s, mean_u=mean_u,
                                 std_u=sig * 2.0 * (1 + 0.05 * rng.random()), sigma_u=math.nan, Ev=ev, Ev_jmap=evj,
                                 Ev_jmap0=evj, events_per_tfilter=250 / (3 * w), reached=1.0,
                                 v_rms_stop=stop * 0.8, Ev_half1=0.01, Ev_half2=0.012))
    df = pd.DataFrame(rows)
    df["sigma_u"] = df.std_u / df.mean_u
    return pool_sigma(df)


def _claim(rows, start: str) -> dict[str, str]:
    return next(r for r in rows if r["claim"].startswith(start))


def test_pooled_sigma_is_std_over_the_mean_of_all_runs_with_the_same_vref():
    df = pd.DataFrame(dict(vref=[0.8, 0.8, 0.4], mean_u=[1.0, 3.0, 5.0], std_u=[1.0, 1.0, 1.0],
                           sigma_u=[1.0, 1 / 3, 0.2]))
    got = pool_sigma(df)
    # means by vref: 2.0 (0.8), 5.0 (0.4)
    assert got.sigma_u_pooled.tolist() == pytest.approx([0.5, 0.5, 0.2])
    # per-run / pooled - 1: 1.0, -1/3, 0 -> largest 1.0
    assert pooling_difference(got) == pytest.approx(1.0)


def test_quoted_effort_and_break_numbers_are_the_run_means():
    df = _synthetic(np.random.default_rng(1), break_at=10)
    rows = claims(df)
    eff = _claim(rows, "Event-based sigma_u")
    m = df.groupby(["controller", "wc"]).sigma_u_pooled.mean()
    for w in (80, 40):
        lti = min(m[("pure_pi", w)], m[("observer_pi", w)])
        ev = max(m[(c, w)] for c in EVENT)
        assert f"wc={w}: best LTI {fmt(lti)} vs worst event {fmt(ev)}" in eff["numbers"]
    brk = _claim(rows, "Break point")
    assert brk["verdict"] == "partly reproduced" and "between wc = 5 and 10" in brk["numbers"]
    assert f"wc=10: {fmt(m[('pure_pi', 10)])} / {fmt(m[('basic_event', 10)])}" in brk["numbers"]
    # 0.8 m/s / 3.2 mm = 250 events/s; Tfilter = 1/(3 wc): 250/15 = 16.7 at wc = 5
    assert "250 events/s" in brk["why"] and "16.7 events per Tfilter" in brk["why"]


def test_break_below_5_gives_not_reproduced():
    rows = claims(_synthetic(np.random.default_rng(2), break_at=5))
    brk = _claim(rows, "Break point")
    assert brk["verdict"] == "not reproduced"
    assert "at or below wc = 5" in brk["numbers"]


def test_instability_is_judged_on_the_stop_phase():
    rows = claims(_synthetic(np.random.default_rng(3)))
    inst = _claim(rows, "Basic Event and Position Prediction")
    assert inst["verdict"] == "reproduced"
    assert "basic_event at wc=80: 100 % of 3 runs oscillate" in inst["numbers"]
    # 4 of the 5 wc are <= 40: 5 controllers x 4 wc x 3 seeds + Full Event at 80 x 3 seeds = 63 runs
    assert "all at wc <= 40: 0 % of 63 runs oscillate" in inst["numbers"]
    # the LTI controllers' small motion at 80 (0.04 vref) is below the threshold and quoted
    assert 0.04 < OSC_THRESHOLD and "pure_pi 0.04" in inst["numbers"]
    rows = claims(_synthetic(np.random.default_rng(3), unstable=()))
    assert _claim(rows, "Basic Event and Position Prediction")["verdict"] == "not reproduced"


def test_tracking_verdict_uses_the_jmap_ev_and_says_what_the_true_velocity_gives():
    rows = claims(_synthetic(np.random.default_rng(4)))
    trk = _claim(rows, "Full Event controller has the best tracking")
    assert trk["verdict"] == "reproduced"  # best by Ev_jmap
    assert "best by true Ev position_prediction" in trk["numbers"]
    assert "gives a different one" in trk["why"]


def test_headline_ratios_are_the_ratios_of_run_means():
    df = _synthetic(np.random.default_rng(5))
    h = headline(df)
    m = df.groupby(["controller", "wc"]).mean(numeric_only=True)
    assert h["pi_over_full_40"] == pytest.approx(m.sigma_u_pooled[("pure_pi", 40)] / m.sigma_u_pooled[("full_event", 40)])
    assert h["evj_full_over_pi_80"] == pytest.approx(m.Ev_jmap[("full_event", 80)] / m.Ev_jmap[("pure_pi", 80)])
    assert h["osc_simplified_80"] == 1.0 and h["osc_others"] == 0.0
    assert h["half2_over_half1_20"] == pytest.approx(1.2)


# ------------------------------------------------------------------------------------------ metrics
def test_stop_rms_covers_only_the_window_after_reaching_the_end():
    t = np.arange(0.0, 4.0, 1e-3)
    v = np.where(t >= 1.0 + STOP_WINDOW[0], 0.3, 0.0)  # moves only from the window's start on
    assert stop_rms(t, v, 1.0) == pytest.approx(0.3)
    assert stop_rms(t, np.where(t < 1.0 + STOP_WINDOW[0], 0.3, 0.0), 1.0) == 0.0
    assert math.isnan(stop_rms(t, v, 2.5))  # the run ends before the window does
    assert math.isnan(stop_rms(t, v, math.nan))


def test_half_window_ev_of_a_synthetic_run():
    t = np.arange(0.0, 3.0, 1e-3)
    p = np.minimum(0.8 * t, 1.2)
    v = np.where(p < 0.65, 0.8 * 1.01, 0.8 * 0.98)  # 1 % error in the first half, 2 % in the second
    m = cart_metrics(t, p, v, np.full_like(t, 2.0), 0.8, jmap=False)
    assert m["Ev_half1"] == pytest.approx(0.01) and m["Ev_half2"] == pytest.approx(0.02)


# ------------------------------------------------------------------------------------------ the committed report
def _md_table(text: str, header_start: str) -> list[list[str]]:
    lines = text.splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith(header_start))
    rows = []
    for ln in lines[i + 2:]:
        if not ln.startswith("|"):
            break
        rows.append([c.strip().strip("*") for c in ln.strip().strip("|").split("|")])
    return rows


@pytest.mark.skipif(not (REPORT / "README.md").exists(), reason="no committed cart report")
def test_committed_report_quotes_the_numbers_of_its_runs():
    text = (REPORT / "README.md").read_text(encoding="utf-8")
    f2 = pd.read_csv(REPORT / "fig2.csv")
    fq = pd.read_csv(REPORT / "quant.csv")
    inst = pd.read_csv(REPORT / "instability.csv") if (REPORT / "instability.csv").exists() else None
    # the verdicts recomputed from the run tables are the ones the README and claims.csv quote
    rows = claims(f2, fq, inst)
    table = _md_table(text, "| claim | verdict")
    assert [r[:3] for r in table] == [[c["claim"], c["verdict"], c["numbers"]] for c in rows]
    csv = pd.read_csv(REPORT / "claims.csv", keep_default_na=False)
    assert csv.numbers.tolist() == [c["numbers"] for c in rows]
    # the Fig. 2 table: means of the per-run rows, computed here
    g = f2.groupby(["controller", "wc"]).mean(numeric_only=True)
    for r in _md_table(text, "| controller | wc |"):
        c, w = r[0], int(r[1])
        assert r[2] == fmt(g.sigma_u_pooled[(c, w)]) and r[3] == fmt(g.sigma_u[(c, w)])
        assert r[4] == fmt(g.Ev_jmap[(c, w)]) and r[5] == fmt(g.Ev[(c, w)])
    # the sigma_u per-run vs pooled difference quoted in the text
    diff = (f2.sigma_u / f2.sigma_u_pooled - 1).abs().max()
    assert f"differs from it by up to {fmt(100 * diff, 2)} % in the Fig. 2 runs" in text
    # the sensitivity table against its runs
    if (REPORT / "sensitivity_runs.csv").exists():
        sr = pd.read_csv(REPORT / "sensitivity_runs.csv")
        both = pd.concat([f2[f2.wc.isin([20, 40, 80])], sr], ignore_index=True)
        for r in _md_table(text, "| friction | runs"):
            h = headline(both[both.friction == r[0]])
            assert r[2] == fmt(h["pi_over_full_40"]) and r[7] == fmt(h["evj_full_over_pi_80"])
            assert r[10] == fmt(h["half2_over_half1_20"])


@pytest.mark.slow
def test_tiny_report_regenerates_consistent_tables(tmp_path):
    from netsim.models.cart.report import cart_report

    calls = []
    tables = cart_report(tmp_path, plots=False, quant=False, sensitivity=False, seeds=(1,), workers=2,
                         progress=lambda d, n, what: calls.append((d, n)))
    assert calls[-1] == (25, 25)
    f2 = pd.read_csv(tmp_path / "fig2.csv")
    assert [c["numbers"] for c in claims(f2)] == tables["claims"].numbers.tolist()
    text = (tmp_path / "README.md").read_text(encoding="utf-8")
    for c in tables["claims"].itertuples():
        assert c.numbers in text
