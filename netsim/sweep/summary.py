"""``summary.csv`` of a sweep: one row per run, byte-identical whatever executed the runs.

Columns: ``index, replicate``, then one column per factor (in the sweep file's order), then every metric
(in order of first appearance, scanning rows by index), then ``status, seed, error, folder``. Rows are
sorted by ``index``. Floats are written with Python's shortest round-trip ``repr`` (exact and stable across
processes and machines); a metric a run did not produce is an empty cell; non-scalar factor values are
written as compact JSON. ``status`` is the run's own (``ok``, ``diverged at t = ...``, ``unstable at t = ...``,
``error``, ``pending``: :mod:`netsim.status`); ``error`` is the one-line form of the run's error or of why it is
not ok (:func:`one_line`: one row is one line of the file); the full text is in the run's ``point.json``.

This module writes the file; :func:`netsim.results.folder.read_summary` is the one place that reads it back
(:class:`netsim.results.folder.SweepFolder`).
"""

from __future__ import annotations

import csv
import io
import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterable, Mapping, Sequence

from netsim.sweep.spec import canonical_json

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["format_value", "one_line", "require_results", "summary_text", "write_summary", "TRAILING_COLUMNS"]

#: Columns after the metrics (the reader keeps ``status``, ``error`` and ``folder`` as text:
#: :data:`netsim.results.folder.SUMMARY_TEXT_COLUMNS`).
TRAILING_COLUMNS = ("status", "seed", "error", "folder")


def format_value(value: Any) -> str:
    """One CSV cell: floats via ``repr`` (``nan``/``inf`` spelled so), bools ``True``/``False``, None empty."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        return repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return value
    if hasattr(value, "item"):  # numpy scalar
        return format_value(value.item())
    return canonical_json(value)


def one_line(text: str) -> str:
    """``text`` on one line: its lines stripped and joined with `` | `` (with a space after a line ending in
    ``:``), empty lines dropped. ``"2 problems:\n  a\n  b"`` becomes ``"2 problems: a | b"``."""
    lines = [line.strip() for line in str(text).splitlines()]
    out = ""
    for line in (x for x in lines if x):
        out += line if not out else (" " if out.endswith(":") else " | ") + line
    return out


def summary_text(factors: Sequence[str], rows: Iterable[Mapping[str, Any]]) -> str:
    """The CSV text of the summary for ``rows`` (records with index, replicate, values, metrics, ...)."""
    ordered = sorted(rows, key=lambda r: int(r["index"]))
    metrics: dict[str, None] = {}
    for r in ordered:
        for name in r.get("metrics") or {}:
            metrics.setdefault(name, None)
    header = ["index", "replicate", *factors, *metrics, *TRAILING_COLUMNS]
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(header)
    for r in ordered:
        values = r.get("values") or {}
        got = r.get("metrics") or {}
        cells = [r["index"], r["replicate"], *(values.get(f) for f in factors)]
        cells += [got.get(m) for m in metrics]
        cells += [r.get("status", ""), r.get("seed"), one_line(r.get("error") or ""), r.get("folder", "")]
        writer.writerow([format_value(c) for c in cells])
    return buf.getvalue()


def write_summary(path: Path, factors: Sequence[str], rows: Iterable[Mapping[str, Any]]) -> Path:
    """Write :func:`summary_text` to ``path`` atomically; return ``path``."""
    text = summary_text(factors, rows)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text, encoding="utf-8", newline="")
    os.replace(tmp, path)
    return path


def require_results(summary: pd.DataFrame, name: str) -> pd.DataFrame:
    """``summary`` (a sweep's summary table) when every run gave a result: ``ok``, ``diverged`` or ``unstable``.

    A report that counts a diverged or unstable run as a lost loop must not count a run that gave no result
    (``error``, ``interrupted``, ``pending``) as one, nor drop it silently.

    Parameters
    ----------
    summary : pandas.DataFrame
        The sweep's ``summary.csv`` as a table, with a ``status`` column.
    name : str
        The sweep's name, for the message.

    Returns
    -------
    pandas.DataFrame
        ``summary`` itself.

    Raises
    ------
    NetsimError
        Naming the first run without a result and its error.
    """
    from netsim.errors import NetsimError
    from netsim.status import DIVERGED, OK, UNSTABLE, kind_of

    bad = summary[~summary["status"].map(kind_of).isin([OK, DIVERGED, UNSTABLE])]
    if len(bad):
        first = bad.iloc[0]
        why = str(first.get("error", "") or "").strip()
        raise NetsimError(f"sweep {name}: {len(bad)} of {len(summary)} runs gave no result (run "
                          f"{first.get('index', '?')}: {first['status']}{': ' + why if why else ''}); fix the cause "
                          "and run the report again (finished runs are resumed)")
    return summary
