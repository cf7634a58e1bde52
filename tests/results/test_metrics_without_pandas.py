"""A run's metrics are kept as plain floats until ``result.metrics`` is read (issue 29: `netsim run` imports no
pandas); ``metrics.csv`` and the values must be the ones the pandas Series gives."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from netsim.results import Lazy, RunResult

#: Values of every kind a metric returns: float, int, bool, numpy scalars, None (a metric with no value), NaN, inf,
#: and floats whose shortest repr needs 17 digits.
VALUES = {"y.ISE": 0.1 + 0.2, "y.IAE": 3, "ok.flag": True, "np.f": np.float64(1e-300), "np.i": np.int64(7),
          "none": None, "nan": math.nan, "inf": -math.inf, "tiny": 5e-324, "big": 1.7976931348623157e308}


def _read(folder) -> bytes:
    return (folder / "metrics.csv").read_bytes()


def test_metrics_csv_from_the_plain_values_is_byte_identical_to_the_series(tmp_path):
    plain = RunResult(meta={"scenario": "demo"})
    plain._set_metrics(VALUES)
    assert type(object.__getattribute__(plain, "metrics")) is Lazy  # nothing built before the folder is written
    plain.to_csv(tmp_path / "plain")
    assert type(object.__getattribute__(plain, "metrics")) is Lazy  # ... nor by writing it
    # the reference: the Series the runner used to store, written through the Series
    series = RunResult(meta={"scenario": "demo"}, metrics=pd.Series(VALUES, dtype=float, name="value"))
    series.to_csv(tmp_path / "series")
    assert _read(tmp_path / "plain") == _read(tmp_path / "series")


def test_the_metrics_series_built_on_read_equals_the_one_given_directly():
    plain = RunResult()
    plain._set_metrics(VALUES)
    pd.testing.assert_series_equal(plain.metrics, pd.Series(VALUES, dtype=float, name="value"))
    empty = RunResult()
    empty._set_metrics({})
    pd.testing.assert_series_equal(empty.metrics, pd.Series(dtype=float, name="value"))


def test_metric_values_are_the_series_values_and_follow_a_replaced_series():
    plain = RunResult()
    plain._set_metrics(VALUES)
    got = plain.metric_values()
    want = pd.Series(VALUES, dtype=float, name="value").to_dict()
    assert list(got) == list(want)
    assert all(a == b or (math.isnan(a) and math.isnan(b)) for a, b in zip(got.values(), want.values()))
    plain.metrics = pd.Series({"z.ISE": 2.0})  # a user's own Series wins over the values kept from the run
    assert plain.metric_values() == {"z.ISE": 2.0}


def test_values_a_float_array_cannot_hold_go_to_the_series_at_once():
    odd = RunResult()
    odd._set_metrics({("a", 1): 1.0})  # a non-text name: the Series (and the table writer) handle it
    assert isinstance(object.__getattribute__(odd, "metrics"), pd.Series)
