"""The signals table read window by window (issue 19, flat memory): the same rows, CSV bytes, control_error numbers
and divergence verdict as the whole table."""

from __future__ import annotations

from array import array
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import netsim.results.signals as signals_module
from netsim.divergence import find_divergence
from netsim.metrics.held import held_integrals_chunked, pairwise_sum
from netsim.metrics.runtime import held_integrals
from netsim.results import Lazy, RunResult, signals_table, write_csv
from netsim.results.divergence import find_divergence_chunked
from netsim.results.signals import SignalSource


def _samples(seed: int) -> tuple[dict[str, object], dict[str, object]]:
    """Three signals on different grids: typed arrays, a plain list with NaN samples, repeated and unordered
    instants (the last sample of an instant counts)."""
    rng = np.random.default_rng(seed)
    times: dict[str, object] = {}
    values: dict[str, object] = {}
    t = np.arange(0, 5000, 1) * 1_000_000  # 1 ms grid
    times["y"] = array("q", t.tolist())
    values["y"] = array("d", np.cumsum(rng.standard_normal(len(t))).tolist())
    tu = np.sort(rng.choice(np.arange(3, 5_000_000_000, 7_000), size=700, replace=False))
    u = rng.standard_normal(len(tu))
    u[rng.random(len(u)) < 0.1] = np.nan  # a NaN sample holds the value before it
    times["u"], values["u"] = tu.tolist(), u.tolist()
    tr = [0, 2_000_000_000, 1_000_000_000, 1_000_000_000, 4_500_000_000]
    times["r"], values["r"] = tr, [1.0, -1.0, 0.5, 0.25, 2.0]
    td = [0, 0, 1_500_000_000, 1_500_000_000, 1_500_000_000, 3_000_000_000]  # in order, repeated instants
    times["d"], values["d"] = array("q", td), array("d", [4.0, 5.0, 6.0, -7.0, 8.0, 9.0])
    times["dn"], values["dn"] = list(td), [4.0, np.nan, 6.0, 7.0, np.nan, 9.0]  # a NaN last of its instant
    return times, values


@pytest.fixture(params=[3, 64, 8192])
def window(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> int:
    monkeypatch.setattr(signals_module, "WINDOW", request.param)
    return request.param


@pytest.mark.parametrize("seed", [0, 1])
def test_windows_put_together_are_the_whole_table(window: int, seed: int) -> None:
    times, values = _samples(seed)
    source = SignalSource(times, values, order=["r", "y"])
    table = signals_table(times, values, order=["r", "y"])
    assert source.names == list(table.columns[1:])
    parts = list(source.chunks())
    at = np.concatenate([t for t, _ in parts])
    assert len(parts) > 1 or window == 8192
    np.testing.assert_array_equal(at / 1e9, table["time_s"].to_numpy())
    for j, name in enumerate(source.names):
        got = np.concatenate([cols[j] for _, cols in parts])
        np.testing.assert_array_equal(got, table[name].to_numpy())  # NaN where the table is empty
    some = list(source.chunks(["u"]))  # a subset of the columns: the same rows
    np.testing.assert_array_equal(np.concatenate([c[0] for _, c in some]), table["u"].to_numpy())


def test_signals_csv_from_the_windows_has_the_bytes_of_the_table(window: int, tmp_path: Path) -> None:
    times, values = _samples(2)
    source = SignalSource(times, values, order=["y"])
    (tmp_path / "a.csv").write_text("".join(source.csv_chunks()), encoding="utf-8")
    write_csv(source.table(), tmp_path / "b.csv")
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()


def test_an_empty_recorder_gives_the_header_only(tmp_path: Path) -> None:
    source = SignalSource({}, {})
    (tmp_path / "a.csv").write_text("".join(source.csv_chunks()), encoding="utf-8")
    write_csv(source.table(), tmp_path / "b.csv")
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes() == b"time_s\n"


@pytest.mark.parametrize("n", [0, 1, 7, 8, 9, 127, 128, 129, 1000, 8193, 65_537, 200_003, 330_001])
def test_pairwise_sum_in_blocks_is_numpys_sum(n: int) -> None:
    rng = np.random.default_rng(n)
    a = rng.standard_normal(n) * np.exp(4 * rng.standard_normal(n))  # magnitudes far apart: order shows
    blocks = [a[i:i + 5003] for i in range(0, n, 5003)]
    assert pairwise_sum(iter(blocks), n, leaf=1 << 10) == float(np.sum(a))
    assert pairwise_sum(iter(blocks), n) == float(np.sum(a))


def test_held_integrals_in_windows_equal_the_whole_arrays() -> None:
    rng = np.random.default_rng(4)
    t = np.cumsum(rng.random(50_000) * 1e-3)
    e = rng.standard_normal(len(t)) * np.exp(3 * rng.standard_normal(len(t)))
    e[rng.random(len(e)) < 0.05] = np.nan
    for t0, t1 in ((0.0, float(t[-1])), (1.0, 20.0), (3.0, float(t[-1]) + 5)):
        def windows() -> object:
            return ((t[i:i + 999], e[i:i + 999]) for i in range(0, len(t), 999))

        assert held_integrals_chunked(windows, t0, t1) == held_integrals(t, e, t0, t1)


def _result(times: dict[str, object], values: dict[str, object]) -> RunResult:
    source = SignalSource(times, values)
    return RunResult(signals=Lazy(source.table), _signal_source=source, meta={"t_end_s": 5.0})


def test_control_error_in_windows_equals_the_table(window: int) -> None:
    from netsim.metrics.runtime import control_error

    times, values = _samples(3)
    for params in ({"reference": "r", "output": "y"}, {"output": "u", "t0": "0.5 s", "t1": "4 s"}):
        chunked = control_error(_result(times, values), params)
        whole = _result(times, values)
        _ = whole.signals  # built: control_error reads the table
        assert chunked == control_error(whole, params)


class _Recorder:
    def __init__(self, times: dict[str, object], values: dict[str, object]) -> None:
        self.times, self.values = times, values


@pytest.mark.parametrize("ratio", [1000.0, 5.0, 0.5])
def test_divergence_in_windows_equals_the_table(window: int, ratio: float) -> None:
    times, values = _samples(5)
    specs = [{"type": "control_error", "params": {"reference": "r", "output": "y", "diverged_above": ratio}},
             {"type": "control_error", "params": {"output": "u", "diverged_above": ratio}}]
    chunked = find_divergence_chunked(_result(times, values), _Recorder(times, values), specs)
    whole = _result(times, values)
    _ = whole.signals
    assert chunked == find_divergence(whole, _Recorder(times, values), specs)
    if ratio == 0.5:
        assert chunked is not None  # the random walk leaves half the reference's scale


def test_a_run_keeps_its_signals_unbuilt_until_read(tmp_path: Path) -> None:
    import netsim

    root = Path(__file__).resolve().parents[1]
    res = netsim.run(root / "scenarios" / "dc_servo_can.yaml", out=tmp_path / "run")
    assert type(object.__getattribute__(res, "signals")) is Lazy  # control_error and the CSV read windows
    table = res.signals
    assert isinstance(table, pd.DataFrame)
    write_csv(table, tmp_path / "s.csv")
    assert (tmp_path / "run" / "signals.csv").read_bytes() == (tmp_path / "s.csv").read_bytes()


def test_metrics_csv_has_the_bytes_pandas_writes(tmp_path: Path) -> None:
    from netsim.results.files import metrics_text

    rng = np.random.default_rng(8)
    values = [float(v) for v in rng.standard_normal(50) * np.exp(20 * rng.standard_normal(50))]
    values += [np.nan, np.inf, -np.inf, -0.0, 0.0, 1.0, 1e16, 1e-5, 123456789.0, 0.1 + 0.2, 5e-324]
    names = [f"m.{i}" for i in range(len(values))]
    res = RunResult(metrics=pd.Series(values, index=names, dtype=float, name="value"))
    write_csv(res.metrics_frame(), tmp_path / "m.csv")
    assert metrics_text(names, values) == (tmp_path / "m.csv").read_text(encoding="utf-8")
    write_csv(RunResult().metrics_frame(), tmp_path / "e.csv")
    assert metrics_text([], []) == (tmp_path / "e.csv").read_text(encoding="utf-8")
    assert metrics_text(["a,b"], [1.0]) is None  # needs quoting: pandas writes it


def test_a_pickled_result_has_its_tables_built_and_leaves_the_samples_behind() -> None:
    import pickle

    import netsim

    root = Path(__file__).resolve().parents[1]
    res = netsim.run(root / "scenarios" / "dc_servo_can.yaml", write=False, overrides={"duration": "0.2 s"})
    back = pickle.loads(pickle.dumps(res))
    assert back._signal_source is None and back._job_rows is None and back._message_rows is None
    assert back.signals.equals(res.signals) and back.jobs.equals(res.jobs) and back.messages.equals(res.messages)
    assert len(back.jobs) > 0 and len(back.signals) > 0


def test_a_sample_cut_in_half_by_an_interrupt_is_left_out_of_windows_and_table() -> None:
    # Ctrl-C / SIGTERM can land between appending a sample's time and its value: one more time than values
    times = {"a": array("q", [0, 10, 20]), "b": array("q", [0, 15])}
    values = {"a": array("d", [1.0, 2.0]), "b": array("d", [5.0, 6.0])}
    table = signals_table(times, values)
    # the rows are the complete samples' instants (0, 10 of a; 0, 15 of b); a's cut sample at 20 is not one
    np.testing.assert_allclose(table["time_s"] * 1e9, [0.0, 10.0, 15.0])
    assert list(table["a"]) == [1.0, 2.0, 2.0]
    rows = [np.column_stack([at, *cols]) for at, cols in SignalSource(times, values).chunks()]
    np.testing.assert_allclose(np.vstack(rows), table[["time_s", "a", "b"]].to_numpy() * [1e9, 1, 1])
