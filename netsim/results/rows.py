"""The jobs and messages tables as columns taken straight from the engine's records (issue 19: no DataFrame).

:class:`Rows` holds one table's columns in table order (sorted as the table is), as Python lists. The run folder's
``jobs.csv`` / ``messages.csv`` are written from them (:meth:`Rows.csv_chunks`) and the ``task.*`` / ``net.*``
metrics and the run warnings read them (:meth:`Rows.array`); the pandas DataFrame a user reads as
``result.jobs`` / ``result.messages`` is built from them only when asked for (:meth:`Rows.frame`).

A column has a *kind* that says how its values are turned into a DataFrame column and into CSV text:

``str``
    text (``None`` allowed: an empty cell);
``int``
    whole numbers;
``bool``
    ``True``/``False``;
``nbool``
    ``True``/``False`` or ``None`` (pandas' nullable ``boolean``: an empty cell);
``time``
    integer nanoseconds or ``None``, shown in seconds (``ns / 1e9``; ``None`` is NaN, an empty cell).

The text written is the text pandas writes for the DataFrame (:func:`netsim.results.files.write_csv`), byte for
byte. A column holding anything its kind does not expect (``None`` among whole numbers, a text with a comma, a
number among texts) makes :meth:`Rows.csv_chunks` return None, and the table is written from its DataFrame.
Adding a column (for instance an optional job field) is one :class:`Column` entry in the table's field list.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from netsim.timebase import S

__all__ = ["JOB_FIELDS", "MESSAGE_FIELDS", "Column", "Rows", "job_rows", "message_rows"]


@dataclass(frozen=True)
class Column:
    """One column of a table made from records.

    Attributes
    ----------
    name
        The table's column name.
    attr
        The record attribute (or dict key) it comes from.
    kind
        ``str``, ``int``, ``bool``, ``nbool`` or ``time`` (see the module docstring).
    default
        The value of a record that lacks the attribute.
    """

    name: str
    attr: str
    kind: str
    default: Any = None


#: The jobs table's columns from :class:`netsim.kernel.records.JobRecord` (``outcome`` is derived, last).
JOB_FIELDS: tuple[Column, ...] = (
    Column("node", "node", "str"),
    Column("task", "task", "str"),
    Column("job_id", "job_id", "int"),
    Column("release_s", "release", "time"),
    Column("start_s", "start", "time"),
    Column("finish_s", "finish", "time"),
    Column("response_s", "response", "time"),
    Column("deadline_s", "deadline", "time"),
    Column("deadline_met", "deadline_met", "nbool"),
    Column("preemptions", "preemptions", "int", 0),
    Column("cpu_time_s", "cpu_time", "time", 0),
    Column("killed", "killed", "bool", False),
)

#: The messages table's columns from :class:`netsim.network.records.MessageRecord`.
MESSAGE_FIELDS: tuple[Column, ...] = (
    Column("msg_id", "msg_id", "int"),
    Column("network", "network", "str"),
    Column("sender", "sender", "str"),
    Column("receiver", "receiver", "str"),
    Column("tag", "tag", "str", ""),
    Column("bits", "bits", "int"),
    Column("priority", "priority", "int"),
    Column("sent_s", "sent_ns", "time"),
    Column("tx_start_s", "tx_start_ns", "time"),
    Column("delivered_s", "delivered_ns", "time"),
    Column("dropped", "dropped", "bool", False),
    Column("drop_reason", "drop_reason", "str", ""),
    Column("delay_s", "delay_ns", "time"),
    Column("tx_end_s", "tx_end_ns", "time"),
)

_QUOTED = (",", '"', "\n", "\r")


class Rows:
    """One table's columns in table order (see the module docstring).

    Parameters
    ----------
    columns
        ``(Column, values)`` pairs in the table's column order; every ``values`` list has the same length.
    empty_columns
        The column names of the table when it has no rows (the DataFrame of an empty table has every column).
    """

    __slots__ = ("_arrays", "data", "kinds", "names")

    def __init__(self, columns: Sequence[tuple[Column, list[Any]]], empty_columns: Sequence[str] | None = None) -> None:
        self.names: list[str] = [c.name for c, _ in columns] if columns else list(empty_columns or [])
        self.kinds: dict[str, str] = {c.name: c.kind for c, _ in columns}
        self.data: dict[str, list[Any]] = {c.name: values for c, values in columns}
        self._arrays: dict[str, np.ndarray] = {}

    def __len__(self) -> int:
        return len(next(iter(self.data.values()))) if self.data else 0

    def __getitem__(self, name: str) -> np.ndarray:
        """A column as a numpy array (:meth:`array`), so code written for a DataFrame's ``table[col]`` reads it."""
        return self.array(name)

    def __contains__(self, name: object) -> bool:
        return name in self.data

    @property
    def columns(self) -> list[str]:
        """The column names in table order."""
        return list(self.names)

    def array(self, name: str) -> np.ndarray:
        """Column ``name`` as a numpy array: seconds (float, NaN for None) for a time column, int64 for whole
        numbers, bool, else an object array of the values."""
        got = self._arrays.get(name)
        if got is not None:
            return got
        if name not in self.data:
            raise KeyError(name)
        values, kind = self.data[name], self.kinds[name]
        if kind == "time":
            got = np.array([np.nan if v is None else v for v in values], dtype=float) / S
        elif kind == "bool":
            got = np.array([bool(v) for v in values], dtype=bool)
        elif kind == "int" and all(type(v) is int for v in values):
            got = np.array(values, dtype=np.int64)
        else:
            got = np.empty(len(values), dtype=object)
            got[:] = values
        self._arrays[name] = got
        return got

    def frame(self) -> Any:
        """The table as a pandas DataFrame: the same values and column types as building it record by record."""
        import pandas as pd

        if not self.data or len(self) == 0:
            return pd.DataFrame(columns=self.names)
        data: dict[str, Any] = {}
        for name in self.names:
            kind, values = self.kinds[name], self.data[name]
            if kind == "time":
                data[name] = self.array(name)
            elif kind == "nbool":
                data[name] = pd.array(values, dtype="boolean")
            elif kind == "bool":
                data[name] = [bool(v) for v in values]
            else:
                data[name] = values
        return pd.DataFrame(data, columns=self.names)

    def csv_chunks(self, chunk_rows: int = 8192) -> Iterator[str] | None:
        """The CSV text pandas writes for :meth:`frame` (header, then rows in chunks), or None when a column holds
        a value its kind does not expect (the caller then writes the DataFrame)."""
        if not self.data or len(self) == 0:
            return iter([",".join(self.names) + "\n"]) if self.names and all(
                not any(ch in n for ch in _QUOTED) for n in self.names) else None
        if any(any(ch in n for ch in _QUOTED) or not n for n in self.names):
            return None
        texts = []
        for name in self.names:
            cells = _cells(self.kinds[name], self.data[name], self.array(name) if self.kinds[name] == "time" else None)
            if cells is None:
                return None
            texts.append(cells)
        return _chunks(self.names, texts, len(self), chunk_rows)


def _chunks(names: list[str], texts: list[list[str]], n: int, chunk_rows: int) -> Iterator[str]:
    yield ",".join(names) + "\n"
    for a in range(0, n, chunk_rows):
        rows = zip(*(t[a:a + chunk_rows] for t in texts))
        yield "\n".join([",".join(r) for r in rows]) + "\n"


def _cells(kind: str, values: list[Any], seconds: np.ndarray | None) -> list[str] | None:
    """The CSV cells of one column (as pandas writes them), or None when a value does not fit ``kind``."""
    if kind == "time":
        assert seconds is not None
        return _time_cells(seconds)
    if kind == "str":
        if not all(type(v) is str or v is None for v in values):
            return None
        out = ["" if v is None else v for v in values]
        if any(ch in v for v in set(out) for ch in _QUOTED):
            return None
        return out
    if kind == "int":
        if not all(type(v) is int for v in values):
            return None
        return [str(v) for v in values]
    if kind == "bool":
        return ["True" if v else "False" for v in values]
    if kind == "nbool":
        out = []
        for v in values:
            if v is None:
                out.append("")
            elif v is True or v is False or type(v) is np.bool_:
                out.append("True" if v else "False")
            else:
                return None
        return out
    raise ValueError(f"unknown column kind '{kind}'")


def _time_cells(seconds: np.ndarray) -> list[str]:
    """Times in seconds as :func:`netsim.results.files._time_text` writes them: whole seconds as integers, other
    values as ``repr`` (one C call for the column), NaN as an empty cell."""
    values = seconds.tolist()
    cells = str(values)[1:-1].split(", ") if values else []
    whole = np.flatnonzero((seconds == np.floor(seconds)) & (np.abs(seconds) < 1e15))
    for i in whole.tolist():
        cells[i] = "%d" % values[i]  # noqa: UP031 - the text _time_text writes
    for i in np.flatnonzero(np.isnan(seconds)).tolist():
        cells[i] = ""
    return cells


def _gather(records: Iterable[Any], fields: Sequence[Column], fill: dict[str, Any] | None = None
            ) -> dict[str, list[Any]]:
    """Per column, the values of ``records`` (objects or dicts); ``fill`` replaces a ``None`` of a column."""
    recs = records if isinstance(records, list) else list(records)
    as_dict = any(isinstance(r, dict) for r in recs)
    out: dict[str, list[Any]] = {}
    for c in fields:
        if as_dict:
            vals = [r.get(c.attr, c.default) if isinstance(r, dict) else getattr(r, c.attr, c.default) for r in recs]
        else:
            vals = [getattr(r, c.attr, c.default) for r in recs]
        if fill and c.name in fill:
            vals = [fill[c.name] if v is None else v for v in vals]
        out[c.name] = vals
    return out


def _ordered(fields: Sequence[Column], parts: list[dict[str, list[Any]]], key: Any) -> dict[str, list[Any]]:
    """The parts' columns concatenated and stably sorted by ``key(columns) -> list of sort keys``."""
    cols = {c.name: [v for p in parts for v in p[c.name]] for c in fields}
    keys = key(cols)
    if keys is not None:
        order = sorted(range(len(keys)), key=keys.__getitem__)
        if order != list(range(len(order))):
            cols = {name: [vals[i] for i in order] for name, vals in cols.items()}
    return cols


def _missing_last(v: Any) -> tuple[bool, Any]:
    """A sort key that puts None and NaN after every value (pandas' ``na_position='last'``)."""
    return (True, 0) if v is None or v != v else (False, v)  # noqa: PLR0124 - NaN is not equal to itself


def job_rows(kernels: Iterable[tuple[str, Iterable[Any]]], extra: Sequence[Column] = ()) -> Rows:
    """The jobs table of the kernels ``(name, records)``: sorted by release time, node, task and job id (stable,
    kernels in the given order), with the derived ``outcome`` column last.

    ``extra`` columns (optional job fields, e.g. release jitter's) come after ``killed`` and before ``outcome``.
    """
    from netsim.kernel.records import (
        job_outcome,  # here: importing netsim.kernel loads simpy
    )

    fields = tuple(JOB_FIELDS) + tuple(extra)
    parts = [_gather(recs, fields, fill={"node": name}) for name, recs in kernels]
    parts = [p for p in parts if p["node"]]

    def key(cols: dict[str, list[Any]]) -> list[Any]:
        rel = [v / S if v is not None else None for v in cols["release_s"]]  # sorted on the seconds, as the table
        return [(_missing_last(r), _missing_last(n), _missing_last(t), _missing_last(j))
                for r, n, t, j in zip(rel, cols["node"], cols["task"], cols["job_id"])]

    if not parts:
        return Rows([], empty_columns=[c.name for c in fields] + ["outcome"])
    cols = _ordered(fields, parts, key)
    outcome = Column("outcome", "outcome", "str")
    cols["outcome"] = [job_outcome(d, bool(k), m) for d, k, m in zip(cols["deadline_s"], cols["killed"],
                                                                      cols["deadline_met"])]
    return Rows([(c, cols[c.name]) for c in (*fields, outcome)])


def message_rows(networks: Iterable[Iterable[Any]]) -> Rows:
    """The messages table of the networks' records: sorted by message id, network and receiver (stable)."""
    parts = [_gather(recs, MESSAGE_FIELDS) for recs in networks]
    parts = [p for p in parts if p["msg_id"]]
    if not parts:
        return Rows([], empty_columns=[c.name for c in MESSAGE_FIELDS])
    for p in parts:
        p["drop_reason"] = [v or "" for v in p["drop_reason"]]
        p["dropped"] = [bool(v) for v in p["dropped"]]
        p["delay_s"] = [int(d) - int(s) if (y is None and d is not None) else y
                        for y, d, s in zip(p["delay_s"], p["delivered_s"], p["sent_s"])]

    def key(cols: dict[str, list[Any]]) -> list[Any]:
        return [(_missing_last(m), _missing_last(n), _missing_last(r))
                for m, n, r in zip(cols["msg_id"], cols["network"], cols["receiver"])]

    cols = _ordered(MESSAGE_FIELDS, parts, key)
    return Rows([(c, cols[c.name]) for c in MESSAGE_FIELDS])
