"""et_control with a time-triggered run that tracks exactly (ISE = 0): no division by zero (issue 14 B).

``hdd_case6`` with ``signals.r.value: 0`` made the TTS baseline's ISE exactly 0; NE = ISEP/ISE then stopped the
run with an error after it had simulated (and a plain division would give inf and a RuntimeWarning).
"""

from __future__ import annotations

import logging
import warnings
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from netsim.errors import ConfigError
from netsim.metrics.et import et_control, sampling_efficiency


def _result(y: list[float], r: float = 0.0) -> SimpleNamespace:
    t = np.arange(len(y), dtype=float)  # one sample per period T = 1 s
    sig = pd.DataFrame({"time_s": t, "r": np.full(len(y), r), "y": y})
    msgs = pd.DataFrame({"tag": ["y", "u"], "sent_s": [0.1, 0.2], "dropped": [False, False]})
    return SimpleNamespace(signals=sig, messages=msgs, meta={"duration_s": float(len(y))})


def test_ne_is_zero_when_both_runs_track_exactly_and_undefined_otherwise():
    assert sampling_efficiency(0.0, 0.0) == 0.0  # the ETS output equals a TTS output that tracks exactly
    with pytest.raises(ConfigError, match="use a reference the time-triggered loop does not track exactly"):
        sampling_efficiency(0.1, 0.0)


def test_et_control_leaves_ne_and_gpi_out_with_a_warning_when_the_tts_run_tracks_exactly(caplog):
    baseline = _result([0.0, 0.0, 0.0, 0.0])  # zero reference, output stays at 0: ISE = 0
    run = _result([0.0, 0.3, 0.4, 0.0])  # the event-triggered run deviates: ISEP = 0.5
    with warnings.catch_warnings(), caplog.at_level(logging.WARNING, logger="netsim.metrics.et"):
        warnings.simplefilter("error")  # a RuntimeWarning (division by zero) fails the test
        m = et_control(run, {"period": "1 s"}, baseline)
    assert m["et.ISE"] == 0.0 and m["et.ISEP"] == pytest.approx(0.5)  # sqrt(0.3^2 + 0.4^2)
    assert "et.NE" not in m and "et.GPI" not in m
    assert all(np.isfinite(v) for v in m.values())
    assert "et.NE and et.GPI are left out" in caplog.text and "nonzero step" in caplog.text


def test_et_control_gives_ne_zero_when_both_runs_track_exactly():
    m = et_control(_result([0.0, 0.0, 0.0]), {"period": "1 s"}, _result([0.0, 0.0, 0.0]))
    assert m["et.NE"] == 0.0
    assert m["et.GPI"] == pytest.approx(0.45 * m["et.Uc"] + 0.45 * m["et.Ua"])  # eq (29) with NE = 0
