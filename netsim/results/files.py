"""The run folder's CSV files: written with a fixed format and read back with the same values and types.

:func:`write_csv` writes every float as the shortest text that reads back as the same float (times as exact
decimals of their nanoseconds), so the same run gives byte-identical files; :func:`read_table` reads a jobs or
messages file back with the column types the run had.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterable, Iterator

import numpy as np

from netsim.lazy_import import lazy_module

if TYPE_CHECKING:
    import pandas as pd
else:  # imported at its first use: `netsim run` and `validate` build no DataFrame (issue 29)
    pd = lazy_module("pandas")

__all__ = ["FLOAT_FORMAT", "TIME_COLUMNS", "write_csv", "read_table", "float_block_text", "JOB_TYPES", "MESSAGE_TYPES"]

#: Float format of the run folder's CSVs: None is Python's shortest round-trip text (``repr``), so a value read
#: back is the same float (issue 21: ``%.12g`` moved values by ~5e-12 and wrote ``1.0`` as ``1``, read back as an
#: integer). Every value is written as pandas' ``to_csv`` writes it without a ``float_format``.
FLOAT_FORMAT: str | None = None


def write_csv(frame: pd.DataFrame, path: Path) -> None:
    """Write ``frame`` atomically with the run folder's fixed float format and ``\\n`` line ends.

    Values use :data:`FLOAT_FORMAT` (the shortest text that reads back as the same float); the time columns
    (:data:`TIME_COLUMNS`, all integer nanoseconds divided by 1e9) write whole seconds as integers and other
    times as their shortest round-trip text, the exact decimal of the nanosecond count for any time below about
    10^6 s (``100000.0000005``). The file is written under a temporary name and renamed
    (:func:`netsim.safe_write.write_atomic`): never half a file, never through a planted symlink.
    """
    text: Any = _float_csv(frame)
    if text is None:
        times = [c for c in frame.columns if c in TIME_COLUMNS and frame[c].dtype == np.float64]
        if times:
            frame = frame.copy()
            for c in times:
                frame[c] = [_time_text(v) for v in frame[c].tolist()]
        text = frame.to_csv(index=False, float_format=FLOAT_FORMAT, lineterminator="\n")
    from netsim.safe_write import write_atomic

    write_atomic(path, text)


def metrics_text(names: list[str], values: list[float]) -> str | None:
    """``metrics.csv`` (``metric,value``) as pandas writes the two-column table, or None when a name needs
    quoting or is empty (then write the table with :func:`write_csv`)."""
    if any(not n or any(ch in n for ch in (",", '"', "\n", "\r")) for n in names):
        return None
    cells = _reprs([float(v) for v in values])  # repr of each value, in one C call
    lines = [f"{n},{'' if c == 'nan' else c}\n" for n, c in zip(names, cells)]
    return "metric,value\n" + "".join(lines)


#: Columns that hold times (integer ns / 1e9): written with full precision (see :func:`write_csv`).
TIME_COLUMNS = frozenset({
    "time_s", "release_s", "start_s", "finish_s", "response_s", "deadline_s", "cpu_time_s", "sent_s",
    "tx_start_s", "delivered_s", "delay_s", "tx_end_s", "end_s", "arrival_s", "release_jitter_s",
    "response_from_arrival_s",
})


def _time_text(v: float) -> str:
    """A time in seconds as the shortest text that reads back as the same float (empty for NaN)."""
    if v != v:
        return ""
    if v == int(v) and abs(v) < 1e15:
        return "%d" % v
    return repr(v)


#: Rows formatted per chunk of :func:`_float_csv` (the text of a long table is never held whole: flat memory).
CHUNK_ROWS = 8192


def _float_csv(frame: pd.DataFrame) -> Iterator[str] | None:
    """The CSV text pandas writes for an all-float64 frame with plain column names, in chunks of
    :data:`CHUNK_ROWS` rows; None for other frames.

    The signals table (thousands of rows) is all floats; formatting it here is ~10x faster than
    ``DataFrame.to_csv`` and gives the same bytes: every value as ``repr`` (``FLOAT_FORMAT`` None), NaN as an
    empty field, no quoting (names with a comma, quote or line break go through pandas).
    """
    names = [str(c) for c in frame.columns]
    if not names or any(t != np.float64 for t in frame.dtypes):
        return None
    if any(ch in n for n in names for ch in (",", '"', "\n", "\r")) or any(not n for n in names):
        return None
    return _float_chunks(frame, names)


def _float_chunks(frame: pd.DataFrame, names: list[str]) -> Iterator[str]:
    yield ",".join(names) + "\n"
    columns = [frame[c].to_numpy(dtype=np.float64) for c in frame.columns]
    timed = [n in TIME_COLUMNS for n in names]
    for a in range(0, len(frame), CHUNK_ROWS):
        yield float_block_text(np.column_stack([c[a:a + CHUNK_ROWS] for c in columns]), timed)


def float_block_text(block: np.ndarray, timed: list[bool]) -> str:
    """The CSV lines (each ending in ``\n``) of a 2-D float array's rows, as pandas writes them: every value as
    ``repr``, NaN as an empty cell, a time column (``timed``) with whole seconds as integers."""
    if len(block) == 0:
        return ""
    t = block[:, 0]
    if timed[0] and not any(timed[1:]) and not np.isnan(t).any():  # the signals table: time_s first, then values
        heads = _reprs(t.tolist())
        whole = np.flatnonzero((t == np.floor(t)) & (np.abs(t) < 1e15))
        for i in whole.tolist():  # whole seconds as integers (_time_text)
            heads[i] = "%d" % t[i]
        if block.shape[1] == 1:
            lines = heads
        else:
            rest = _rows_text(block[:, 1:])
            lines = [h + "," + r for h, r in zip(heads, rest)]
    elif not any(timed):
        lines = [",".join(["" if v != v else repr(v) for v in row]) for row in block.tolist()]
    else:
        def value(v: float) -> str:
            return "" if v != v else repr(v)

        cells = [_time_text if tm else value for tm in timed]
        lines = [",".join([f(v) for f, v in zip(cells, row)]) for row in block.tolist()]
    return "\n".join(lines) + "\n"


def _reprs(values: list[float]) -> list[str]:
    """``repr`` of each float, formatted in one C call (``str`` of a list uses each float's ``repr``)."""
    return str(values)[1:-1].split(", ") if values else []


def _rows_text(block: np.ndarray) -> list[str]:
    """Each row of a 2-D float array as CSV cells: ``repr`` of each value, NaN as an empty cell.

    The signals table holds each signal between its samples, so most cells repeat the cell above: each column's
    text is made only where its bits change (the same bits give the same ``repr``, and ``-0.0`` and ``0.0``
    differ in bits), formatted in one C call (:func:`_reprs`), then spread down the column."""
    n, k = block.shape
    if n == 0:
        return []
    cells = np.empty((n, k), dtype=object)
    change = np.empty(n, dtype=bool)
    for j in range(k):
        column = np.ascontiguousarray(block[:, j])
        bits = column.view(np.int64)
        change[0] = True
        np.not_equal(bits[1:], bits[:-1], out=change[1:])
        texts = ["" if t == "nan" else t for t in _reprs(column[change].tolist())]
        cells[:, j] = np.asarray(texts, dtype=object)[np.cumsum(change) - 1]
    return [",".join(row) for row in cells.tolist()]


#: Column types of the jobs and messages tables (the columns :func:`jobs_table` and :func:`messages_table` make).
JOB_TYPES: dict[str, str] = {
    "node": "str", "task": "str", "deadline_met": "boolean", "killed": "bool", "outcome": "str",
    **dict.fromkeys(("release_s", "start_s", "finish_s", "response_s", "deadline_s", "cpu_time_s", "arrival_s",
                     "release_jitter_s", "response_from_arrival_s"), "float64"),
}
MESSAGE_TYPES: dict[str, str] = {
    "network": "str", "sender": "str", "receiver": "str", "tag": "str", "dropped": "bool", "drop_reason": "str",
    **dict.fromkeys(("sent_s", "tx_start_s", "delivered_s", "delay_s", "tx_end_s"), "float64"),
}


def read_table(path: Path, types: dict[str, str]) -> pd.DataFrame:
    """A jobs or messages CSV with its column types: empty cells are NaN/NA in number and boolean columns and
    ``""`` in text columns."""
    import csv

    with open(path, newline="", encoding="utf-8") as fh:
        header = next(csv.reader(fh), [])
    present = {c: t for c, t in types.items() if c in header}
    empty_is_na = {c: [""] for c in header if present.get(c) != "str"}
    return pd.read_csv(path, dtype=present, keep_default_na=False, na_values=empty_is_na)


#: Header of ``schedule.csv``: the kernels' schedule trace, one row per interval, times in integer nanoseconds.
SCHEDULE_HEADER = "node,task,state,start_ns,end_ns"


def schedule_csv_chunks(kernels: Iterable[tuple[str, Iterable[Any]]], chunk_rows: int = 20_000) -> Iterator[str]:
    """``schedule.csv`` as text chunks from each kernel's trace ``(task, state, t0_ns, t1_ns)``: the node, then the
    interval, times as integers (exact, compact; the table's ``start_s``/``end_s`` are these over 1e9)."""
    import csv
    import io

    kernels = list(kernels)
    # a multicore kernel's intervals carry their core (netsim.kernel.multicore): then a 'core' column, empty
    # where there is none; without one the file is as it always was
    cores = any(intervals and len(intervals[0]) > 4 for _, intervals in kernels)  # type: ignore[index]
    yield SCHEDULE_HEADER + (",core\n" if cores else "\n")
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    n = 0
    for node, intervals in kernels:
        for iv in intervals:
            task, state, t0, t1 = iv[:4]
            if cores:
                core = iv[4] if len(iv) > 4 else None
                writer.writerow((node, task, state, int(t0), int(t1), "" if core is None else int(core)))
            else:
                writer.writerow((node, task, state, int(t0), int(t1)))
            n += 1
            if n % chunk_rows == 0:
                yield buf.getvalue()
                buf.seek(0)
                buf.truncate()
    if buf.tell():
        yield buf.getvalue()


def schedule_intervals(frame: pd.DataFrame) -> list[tuple[str, list[tuple[str, str, int, int]]]]:
    """The per-node intervals of a schedule table (seconds back to the integer ns they were made from)."""
    out: dict[str, list[tuple[str, str, int, int]]] = {}
    for node, task, state, a, b in zip(frame["node"], frame["task"], frame["state"], frame["start_s"], frame["end_s"]):
        out.setdefault(str(node), []).append((str(task), str(state), round(float(a) * 1e9), round(float(b) * 1e9)))
    return list(out.items())


def read_schedule(path: Path) -> pd.DataFrame:
    """The schedule table (``node, task, state, start_s, end_s``) from a ``schedule.csv``."""
    from netsim.results.tables import SCHEDULE_COLUMNS, _ns_column

    frame = pd.read_csv(path, dtype={"node": "str", "task": "str", "state": "str", "start_ns": "int64",
                                     "end_ns": "int64"}, keep_default_na=False)
    if frame.empty:
        return pd.DataFrame(columns=SCHEDULE_COLUMNS)
    out = pd.DataFrame({"node": frame["node"], "task": frame["task"], "state": frame["state"],
                        "start_s": _ns_column(frame["start_ns"].tolist()), "end_s": _ns_column(frame["end_ns"].tolist())},
                       columns=SCHEDULE_COLUMNS)
    if "core" in frame.columns:  # a multicore node's running intervals say which core ran them
        out["core"] = pd.to_numeric(frame["core"].replace("", None)).astype("Int64")
    return out
