"""The signals table in row chunks, straight from the recorder's samples (issue 19: flat memory in run length).

A :class:`SignalSource` holds each recorded signal's samples (sorted, one per instant) and gives the wide signals
table (``time_s`` first, each signal held between its samples, empty before its first) window by window
(:meth:`SignalSource.chunks`): the run folder's ``signals.csv``, the ``control_error`` metric and the divergence
check read it so, without the whole table in memory. :meth:`SignalSource.table` builds the whole table
(:func:`netsim.results.tables.signals_table`) when a user reads ``result.signals``. The chunks, put one under the
other, are that table, value for value.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from netsim.timebase import S

__all__ = ["SignalSource", "ordered_names"]

#: Samples per signal taken into one window of :meth:`SignalSource.chunks`.
WINDOW = 8192


def ordered_names(names: Sequence[str], order: Iterable[str] | None) -> list[str]:
    """The table's column order: the ``order`` names (or base names whose ``name[i]`` columns follow), then the
    remaining names sorted."""
    ordered: list[str] = []
    if order is not None:
        for want in order:
            group = [n for n in names if n not in ordered and (n == want or n.split("[", 1)[0] == want)]
            ordered += sorted(group, key=lambda n: (len(n), n))
    ordered += sorted(n for n in names if n not in ordered)
    return ordered


def _as_array(samples: Any, dtype: Any) -> np.ndarray:
    """A sample container as a numpy array, without a copy for a typed array (:class:`netsim.env.Samples`)."""
    try:
        got = np.frombuffer(samples, dtype=dtype)
        if len(got) == len(samples):
            return got
    except (TypeError, ValueError, BufferError):  # not a typed array of that type (a list): copied below
        pass
    return np.asarray(samples, dtype=dtype)


class SignalSource:
    """Recorded samples per signal, read as the signals table in windows of rows.

    Parameters
    ----------
    times, values
        Sample instants (int ns) and values per signal name (as in :class:`netsim.env.Recorder`); not copied
        when they are typed arrays, already in time order with one sample per instant, and hold no NaN.
    order
        Preferred column order (:func:`ordered_names`).
    """

    def __init__(self, times: Mapping[str, Any], values: Mapping[str, Any], order: Iterable[str] | None = None) -> None:
        self._times = times
        self._values = values
        self._order = list(order) if order is not None else None
        self.names: list[str] = ordered_names(list(times), self._order)
        self._series: dict[str, tuple[np.ndarray, np.ndarray]] | None = None

    def table(self) -> Any:
        """The whole signals table (a pandas DataFrame; :func:`netsim.results.tables.signals_table`)."""
        from netsim.results.tables import signals_table

        return signals_table(self._times, self._values, order=self._order)

    def series(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """``(t_ns, held_values)`` of one signal: its samples in time order (the last of an instant is the one the
        table shows), a NaN sample replaced by the last value before it (what the table shows at that row)."""
        if self._series is None:
            self._series = {}
        got = self._series.get(name)
        if got is not None:
            return got
        t = _as_array(self._times[name], np.int64)
        v = _as_array(self._values[name], np.float64)
        if len(t) != len(v):  # a run interrupted (Ctrl-C, SIGTERM) between a sample's time and its value
            n = min(len(t), len(v))
            t, v = t[:n], v[:n]
        missing = np.isnan(v)
        ordered = len(t) < 2 or bool(np.all(t[1:] >= t[:-1]))
        if not ordered or (missing.any() and not bool(np.all(t[1:] > t[:-1]))):  # rare: sort, one per instant
            order = np.argsort(t, kind="stable")
            t, v = t[order], v[order]
            last = np.append(t[1:] != t[:-1], True)  # the last sample of each instant counts
            t, v = t[last], v[last]
            missing = np.isnan(v)
        # else repeated instants in time order are kept (no copy): the windows read the last sample at or before
        # each row, which is the last of its instant
        if missing.any():  # each NaN sample holds the last value before it (the table's forward fill)
            idx = np.where(missing, 0, np.arange(len(v)))
            np.maximum.accumulate(idx, out=idx)
            v = v[idx]
        self._series[name] = (t, v)
        return t, v

    def chunks(self, names: Sequence[str] | None = None) -> Iterator[tuple[np.ndarray, list[np.ndarray]]]:
        """The table's rows in windows: ``(t_ns, [column, ...])`` per window, the columns of ``names`` (default:
        every signal, in table order) held at the window's instants (NaN before a signal's first sample).

        The rows are the instants at which any signal (of all of them, not only ``names``) was sampled, as in the
        whole table. A window takes at most :data:`WINDOW` samples of each signal.
        """
        every = [self.series(n) for n in self.names]
        wanted = [self.series(n) for n in (self.names if names is None else names)]
        pos = [0] * len(every)
        while True:
            ends = [t[p + WINDOW - 1] for (t, _), p in zip(every, pos) if p + WINDOW - 1 < len(t)]
            cut = min(ends) if ends else None
            pieces = []
            for i, (t, _) in enumerate(every):
                q = len(t) if cut is None else int(np.searchsorted(t, cut, side="right"))
                if q > pos[i]:
                    pieces.append(t[pos[i]:q])
                pos[i] = q
            if not pieces:
                return
            at = np.unique(np.concatenate(pieces)) if len(pieces) > 1 else pieces[0].copy()
            cols = []
            for t, v in wanted:
                k = np.searchsorted(t, at, side="right") - 1
                cols.append(np.where(k >= 0, v[np.clip(k, 0, None)], np.nan) if len(t) else np.full(len(at), np.nan))
            yield at, cols
            if cut is None:
                return

    def csv_chunks(self) -> Iterator[str]:
        """``signals.csv``: the text :func:`netsim.results.files.write_csv` writes for :meth:`table`, window by
        window."""
        from netsim.results.files import TIME_COLUMNS, float_block_text

        names = ["time_s", *self.names]
        timed = [n in TIME_COLUMNS for n in names]  # as write_csv decides it from the names
        yield ",".join(names) + "\n"
        for at, cols in self.chunks():
            yield float_block_text(np.column_stack([at / S, *cols]), timed)

    def csv_plain(self) -> bool:
        """True when the column names need no quoting (else the table goes through pandas' writer)."""
        return all(n and not any(ch in n for ch in (",", '"', "\n", "\r")) for n in self.names)
