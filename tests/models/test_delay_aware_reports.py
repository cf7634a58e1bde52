"""The delay-aware rows of the pendulum and two-wheel cart reports (issue 26 section 5), on constructed sweeps."""

from __future__ import annotations

import math

import pandas as pd


def test_pendulum_delay_aware_margins_bracket_the_first_fallen_run() -> None:
    from netsim.models.pendulum.report_sweeps import delay_aware_margins

    rows = []
    # unaware: all 5 balanced up to 21.1 ms, 4 of 5 at 26.1, 0 at 31.1; told the delay: 5 of 5 everywhere but
    # 46.1 (3 of 5) -- a later all-balanced point (51.1) must not count, it lies beyond the first failure
    for how, table in (("unaware", ((11.1, 5), (21.1, 5), (26.1, 4), (31.1, 0))),
                       ("input_delay", ((11.1, 5), (41.1, 5), (46.1, 3), (51.1, 5)))):
        for total, ok in table:
            rows.append({"estimator": "kalman", "estimation": how, "total_delay_ms": total, "seed_count": 5,
                         "stable_runs": ok})
    m = delay_aware_margins(pd.DataFrame(rows)).set_index("estimation")
    assert (m.loc["unaware", "stable_up_to_ms"], m.loc["unaware", "fails_at_ms"]) == (21.1, 26.1)
    assert m.loc["unaware", "stable_runs_at_fail"] == 4
    assert (m.loc["input_delay", "stable_up_to_ms"], m.loc["input_delay", "fails_at_ms"]) == (41.1, 46.1)
    assert m.loc["input_delay", "stable_runs_at_fail"] == 3


def test_pendulum_delay_aware_margins_say_when_nothing_failed() -> None:
    from netsim.models.pendulum.report_sweeps import delay_aware_margins

    rows = [{"estimator": "luenberger", "estimation": "input_delay", "total_delay_ms": t, "seed_count": 5,
             "stable_runs": 5} for t in (1.1, 31.1, 61.1)]
    m = delay_aware_margins(pd.DataFrame(rows)).iloc[0]
    assert m.stable_up_to_ms == 61.1 and math.isnan(m.fails_at_ms) and m.largest_delay_ms == 61.1


def test_unicycle_delay_aware_frame_names_the_rows_and_shares_the_zero_delay_run() -> None:
    from netsim.models.unicycle.readme_net import delay_aware_frame

    can = pd.DataFrame({"delay": ["0 ms", "100 ms", "100 ms"], "input_delay": [0, 0, 10],
                        "unicycle.track_rms_e1": [1.0, 2.0, 3.0]})
    radio = pd.DataFrame({"sensors": ["accurate", "accurate"], "delay": ["0 ms", "50 ms"], "input_delay": [0, 5],
                          "unicycle.track_rms_e1": [4.0, 5.0]})
    d = delay_aware_frame(can, radio)
    got = sorted(zip(d.network, d.sensors, d._ms, d["filter"], d["unicycle.track_rms_e1"]))
    assert got == sorted([("CAN", "report", 0.0, "told the delay", 1.0), ("CAN", "report", 0.0, "unaware", 1.0),
                          ("CAN", "report", 100.0, "unaware", 2.0), ("CAN", "report", 100.0, "told the delay", 3.0),
                          ("radio", "accurate", 0.0, "told the delay", 4.0),
                          ("radio", "accurate", 0.0, "unaware", 4.0),
                          ("radio", "accurate", 50.0, "told the delay", 5.0)])


def test_pendulum_law_spectral_radius_matches_hand_built_loops() -> None:
    import numpy as np

    from netsim.models.pendulum.analysis import law_spectral_radius
    from netsim.models.pendulum.design import designs

    d = designs()
    A, B, K = d.lin.Ad, d.lin.Bd, d.K_lqr
    # no delay: the state-feedback loop A - B K
    assert abs(law_spectral_radius(d, 0.0) - np.max(np.abs(np.linalg.eigvals(A - B @ K)))) < 1e-12
    # two whole periods: z = [x; u[k-2]; u[k-1]], x+ = A x + B u[k-2], written out by hand
    F = np.zeros((6, 6))
    F[:4, :4], F[:4, 4:5] = A, B
    F[4, 5] = 1.0
    F[5, :4] = -K
    assert abs(law_spectral_radius(d, 2 * d.lin.h) - np.max(np.abs(np.linalg.eigvals(F)))) < 1e-12
