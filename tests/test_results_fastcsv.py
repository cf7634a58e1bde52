"""write_csv formats all-float tables itself: the bytes must equal pandas' ``to_csv`` with the same options."""

import numpy as np
import pandas as pd

from netsim.results import FLOAT_FORMAT, TIME_COLUMNS, write_csv

EDGE = [0.0, -0.0, 1.0, -1.5, np.nan, np.inf, -np.inf, 1e-300, 5e-324, 1.7976931348623157e308,
        123456789012345.0, 0.1, 2.0 / 3, 1e21, -1e-7]


def _time_cell(v: float) -> str:
    # the rule for time columns: integers as integers (as %.12g writes them), others as Python's shortest
    # round-trip repr, NaN empty
    return "" if v != v else ("%d" % v if float(v).is_integer() else repr(float(v)))


def _both(frame: pd.DataFrame, tmp_path) -> tuple[bytes, bytes]:
    ref = frame.copy()
    for c in ref.columns:
        if c in TIME_COLUMNS and ref[c].dtype == np.float64:
            ref[c] = [_time_cell(v) for v in ref[c]]
    ref.to_csv(tmp_path / "pandas.csv", index=False, float_format=FLOAT_FORMAT, lineterminator="\n")
    write_csv(frame, tmp_path / "ours.csv")
    return (tmp_path / "pandas.csv").read_bytes(), (tmp_path / "ours.csv").read_bytes()


def test_float_table_bytes_equal_pandas_including_nan_inf_and_negative_zero(tmp_path):
    rng = np.random.default_rng(3)
    frame = pd.DataFrame({"time_s": np.arange(300) / 7.0,
                          "y[0]": rng.standard_normal(300) * 10.0 ** rng.integers(-30, 30, 300),
                          "u": np.resize(EDGE, 300)})
    ours, theirs = _both(frame, tmp_path)
    assert ours == theirs


def test_empty_and_non_float_tables_still_match_pandas(tmp_path):
    assert _both(pd.DataFrame({"time_s": pd.Series([], dtype=float)}), tmp_path)[0] == \
        _both(pd.DataFrame({"time_s": pd.Series([], dtype=float)}), tmp_path)[1]
    mixed = pd.DataFrame({"metric": ["a", "b,c"], "value": [1.0, np.nan]})  # strings: pandas path, quoting
    p, o = _both(mixed, tmp_path)
    assert p == o and b'"b,c"' in o
    quoted = pd.DataFrame({"a,b": [1.0, 2.0]})  # a name that needs quoting goes through pandas too
    p, o = _both(quoted, tmp_path)
    assert p == o


def test_times_late_in_a_long_run_keep_their_nanoseconds(tmp_path):
    # 100000 s + 0.5 us: %.12g wrote 100000.000001 (0.5 us off); the time column must read back exactly
    ns = [100_000 * 10**9 + 500, 3 * 10**9 + 1, 7]
    frame = pd.DataFrame({"time_s": [n / 1e9 for n in ns], "y": [1.0, 2.0, 3.0]})
    write_csv(frame, tmp_path / "t.csv")
    back = pd.read_csv(tmp_path / "t.csv")
    assert [round(v * 1e9) for v in back["time_s"]] == ns
    assert "100000.0000005" in (tmp_path / "t.csv").read_text()
