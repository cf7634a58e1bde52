"""The signals CSV formatted in chunks with C-level repr (issue 19) gives the bytes of the per-value rule."""

from __future__ import annotations

import numpy as np
import pandas as pd

from netsim.results import files


def _per_value(frame: pd.DataFrame) -> str:
    """The rule of write_csv, one value at a time: time_s as _time_text, other values repr, NaN empty."""
    lines = [",".join(frame.columns)]
    for row in frame.to_numpy().tolist():
        lines.append(",".join([files._time_text(row[0])] + ["" if v != v else repr(v) for v in row[1:]]))
    return "\n".join(lines) + "\n"


def test_chunked_signals_text_equals_the_per_value_rule(monkeypatch) -> None:
    monkeypatch.setattr(files, "CHUNK_ROWS", 7)  # several chunks, a short last one
    rng = np.random.default_rng(0)
    for _ in range(200):
        n, k = int(rng.integers(0, 40)), int(rng.integers(0, 4))
        special = [0.0, 1.0, 2.5, 1e-9, 3.0, 1e15, 1e16, 123456.000000001, -0.0, -2.0]
        t = np.sort(rng.choice(special, n) if rng.random() < 0.5 else rng.random(n) * 10)
        data = {"time_s": t}
        for j in range(k):
            v = rng.normal(size=n) * 10.0 ** rng.integers(-300, 300)
            if rng.random() < 0.5:  # held values: runs of repeats, as in the signals table
                v = np.resize(np.repeat(v[: max(1, n // 4)], 4), n)
            for value, share in ((np.nan, 0.2), (np.inf, 0.05), (-np.inf, 0.05), (-0.0, 0.05)):
                v[rng.random(n) < share] = value
            data[f"c{j}"] = v
        frame = pd.DataFrame(data)
        assert "".join(files._float_csv(frame)) == _per_value(frame)


def test_held_cells_that_compare_equal_but_print_differently() -> None:
    # 0.0 == -0.0 but their texts differ; NaN != NaN but both are empty cells; inf repeats
    values = [0.0, -0.0, -0.0, 0.0, np.nan, np.nan, 1.0, np.inf, np.inf, -np.inf]
    frame = pd.DataFrame({"time_s": np.arange(len(values)) * 0.5, "x": values})
    assert "".join(files._float_csv(frame)) == _per_value(frame)
    assert "".join(files._float_csv(frame)).splitlines()[1:5] == ["0,0.0", "0.5,-0.0", "1,-0.0", "1.5,0.0"]
