"""The one reader of the folders netsim writes: a run folder (:class:`RunFolder`) and a sweep folder
(:class:`SweepFolder`).

A *run folder* (``netsim run``, one entry of ``netsim batch``, one point of ``netsim sweep``) holds
``meta.json``, written last, so a folder without it is incomplete (the run was killed, or is still writing);
``metrics.csv``, and, unless the run kept only its metrics, ``scenario.yaml``, ``signals.csv``, ``jobs.csv`` /
``messages.csv`` (or their ``*_summary.csv``) and ``schedule.csv``. A sweep point also holds ``point.json``
(the worker's record) and ``manifest.json`` (the sha256 of every other file, written last): a point folder that
no longer matches its manifest was changed after the sweep wrote it, and is not trusted
(:mod:`netsim.results.manifest`).

A *sweep folder* holds ``sweep.json`` (which sweep, its factors and spec), ``points/<index>-<key>/`` (one run
folder per run) and ``summary.csv`` (one row per run, written by :mod:`netsim.sweep.summary`), read here and
nowhere else (:func:`read_summary`).

Opening a folder with :meth:`RunFolder.open` or :meth:`SweepFolder.open` refuses what cannot be read as one,
with a one-line :class:`FolderRefused` (a :class:`~netsim.errors.ConfigError`) that says what to do; the
table readers give the column types the run had (:func:`netsim.results.files.read_table`).

Examples
--------
>>> import tempfile
>>> from netsim.results import RunResult
>>> path = RunResult(meta={"scenario": "demo", "status": "ok"}).to_csv(tempfile.mkdtemp())
>>> run = RunFolder.open(path)
>>> run.status, run.name, run.jobs() is not None
('ok', 'demo', True)
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple, cast

import numpy as np

from netsim.lazy_import import lazy_module

if TYPE_CHECKING:
    import pandas as pd
else:  # imported at its first use: `netsim run` and `validate` build no DataFrame (issue 29)
    pd = lazy_module("pandas")

from netsim.errors import ConfigError
from netsim.results.manifest import (MANIFEST_NAME, RECORD_NAME, json_object, manifest_digests, read_record,
                                     tampered_reason, verified_record)

__all__ = [
    "RunFolder",
    "SweepFolder",
    "SweepRun",
    "FolderRefused",
    "read_summary",
    "read_record",
    "verified_record",
    "manifest_digests",
    "tampered_reason",
    "run_folders_in",
    "META_NAME",
    "METRICS_NAME",
    "SUMMARY_NAME",
    "SWEEP_MARKER",
    "RECORD_NAME",
    "MANIFEST_NAME",
    "SUMMARY_TEXT_COLUMNS",
]

log = logging.getLogger(__name__)

#: Written last into a run folder: a folder without it is incomplete.
META_NAME = "meta.json"
#: A run's metrics, ``metric,value``.
METRICS_NAME = "metrics.csv"
#: A sweep's table, one row per run.
SUMMARY_NAME = "summary.csv"
#: The file that marks a folder as holding a sweep.
SWEEP_MARKER = "sweep.json"
#: The files a run writes besides ``meta.json``: any of them without ``meta.json`` marks an incomplete folder.
_RUN_FILES = ("scenario.yaml", METRICS_NAME, "jobs.csv", "signals.csv", "messages.csv")
#: Text columns of ``summary.csv`` (:data:`netsim.sweep.summary.TRAILING_COLUMNS` but ``seed``): empty is ``""``.
SUMMARY_TEXT_COLUMNS = ("status", "error", "folder")


class FolderRefused(ConfigError):
    """A folder that cannot be read as a run or sweep folder: missing, incomplete, changed since it was written,
    or not one at all. The message is one line and says what to do."""


# --------------------------------------------------------------------------------------------- run folders
class RunFolder:
    """One run folder, read file by file when asked (each file at most once).

    Build one with ``RunFolder(path)`` to look at a folder that may be incomplete (:attr:`is_complete`), or with
    :meth:`open` to refuse one that is incomplete or changed.

    Parameters
    ----------
    path : str or pathlib.Path
        The run folder.

    Examples
    --------
    >>> import tempfile
    >>> from netsim.results import RunResult
    >>> path = RunResult(metrics=pd.Series({"y.ISE": 0.5})).to_csv(tempfile.mkdtemp())
    >>> RunFolder(path).metrics().to_dict()
    {'y.ISE': 0.5}
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self._meta: dict[str, Any] | None = None
        self._metrics: pd.Series | None = None

    def __repr__(self) -> str:
        return f"RunFolder({str(self.path)!r})"

    @classmethod
    def open(cls, path: str | Path) -> RunFolder:
        """The run folder at ``path``, refused when it cannot be read as one.

        Parameters
        ----------
        path : str or pathlib.Path
            The folder ``netsim run`` (or a batch or sweep) wrote.

        Returns
        -------
        RunFolder
            The folder, its ``meta.json`` read.

        Raises
        ------
        FolderRefused
            One line: the folder is missing, has no ``meta.json`` (a run killed or stopped while writing, or
            still running), an unreadable one, or is a sweep point changed since the sweep wrote it.
        """
        run = cls(path)
        run.refuse_if_unreadable()
        return run

    def refuse_if_unreadable(self) -> None:
        """Raise :class:`FolderRefused` (one line) unless this is a complete, untouched run folder."""
        folder = self.path
        if not folder.is_dir():
            raise FolderRefused(f"'{folder}' is not a folder; give the folder that `netsim run` wrote")
        if not self.is_complete:
            if self.is_incomplete:
                raise FolderRefused(
                    f"'{folder}' is an incomplete run folder (no meta.json: the run was killed or stopped while "
                    "writing, or is still running); wait for a running one to finish, or run it again: "
                    f"netsim run {folder / 'scenario.yaml'} --out NEW_FOLDER")
            raise FolderRefused(f"'{folder}' is not a run folder (no meta.json); give the folder that `netsim run` "
                                "wrote")
        if json_object(folder / META_NAME) is None:
            raise FolderRefused(f"'{folder / META_NAME}' is not a readable JSON object (damaged); run the scenario "
                                "again into a new folder")
        if (folder / MANIFEST_NAME).exists() or (folder / RECORD_NAME).exists():
            why = tampered_reason(folder)
            if why is not None:
                raise FolderRefused(f"sweep point '{folder}' is not what the sweep wrote ({why}); run the sweep "
                                    "again: it re-runs this point")

    # ------------------------------------------------------------------ state
    @property
    def is_complete(self) -> bool:
        """True when ``meta.json`` (written last) is there."""
        return (self.path / META_NAME).is_file()

    @property
    def is_incomplete(self) -> bool:
        """True for run files without the ``meta.json`` that marks the folder complete (a run killed or still
        running: ``scenario.yaml`` is written first)."""
        return not (self.path / META_NAME).exists() and any((self.path / n).exists() for n in _RUN_FILES)

    @property
    def has_results(self) -> bool:
        """True for a complete folder with metrics or jobs to report (a failed ``runs: metrics`` point has
        neither)."""
        return self.is_complete and ((self.path / METRICS_NAME).exists() or (self.path / "jobs.csv").exists())

    # ------------------------------------------------------------------ meta and metrics
    @property
    def meta(self) -> dict[str, Any]:
        """``meta.json`` (seed, scenario name and hash, versions, wall time, ``status``, ``error``); ``{}`` when
        it is missing or unreadable."""
        if self._meta is None:
            self._meta = json_object(self.path / META_NAME) or {}
        return self._meta

    @property
    def status(self) -> str:
        """The run's status (``ok``, ``diverged at t = ... s``, ``error``, ...; :mod:`netsim.status`)."""
        return str(self.meta.get("status", "ok"))

    @property
    def name(self) -> str:
        """The scenario's name from ``meta.json``, else the folder's name."""
        return str(self.meta.get("scenario") or self.path.name)

    @property
    def duration_s(self) -> float:
        """The simulated duration in seconds (``meta.json``), NaN when unknown."""
        for key in ("duration_s", "t_end_s"):
            value = self.meta.get(key)
            if isinstance(value, (int, float)) and not isinstance(value, bool) and value > 0:
                return float(value)
        return float("nan")

    def metrics(self) -> pd.Series:
        """``metrics.csv`` as a float Series, metric name -> value, in file order (empty when absent)."""
        if self._metrics is None:
            path = self.path / METRICS_NAME
            if path.exists():
                frame = pd.read_csv(path, dtype={"metric": str, "value": np.float64}, keep_default_na=False,
                                    na_values={"value": [""]})
                self._metrics = pd.Series(frame["value"].to_numpy(dtype=float), index=list(frame["metric"]),
                                          name="value")
            else:
                self._metrics = pd.Series(dtype=float, name="value")
        return self._metrics.copy()

    def metric_values(self) -> dict[str, float]:
        """The metrics as a plain ``{name: value}`` mapping."""
        return {str(k): float(v) for k, v in self.metrics().items()}

    # ------------------------------------------------------------------ tables
    def signals(self, columns: list[str] | None = None) -> pd.DataFrame:
        """``signals.csv`` as floats (``time_s`` first); ``columns`` reads only those (KeyError-like
        ``ValueError`` from pandas for a name not recorded). A folder without the file gives ``time_s`` only."""
        path = self.path / "signals.csv"
        if not path.exists():
            return pd.DataFrame({c: pd.Series([], dtype=float) for c in (columns or ["time_s"])})
        return pd.read_csv(path, dtype=np.float64, usecols=columns)

    def jobs(self) -> pd.DataFrame | None:
        """``jobs.csv`` with its column types (:data:`netsim.results.files.JOB_TYPES`), None when not written."""
        from netsim.results.files import JOB_TYPES, read_table

        path = self.path / "jobs.csv"
        return read_table(path, JOB_TYPES) if path.exists() else None

    def messages(self) -> pd.DataFrame | None:
        """``messages.csv`` with its column types, None when not written."""
        from netsim.results.files import MESSAGE_TYPES, read_table

        path = self.path / "messages.csv"
        return read_table(path, MESSAGE_TYPES) if path.exists() else None

    def job_summary(self) -> pd.DataFrame | None:
        """``jobs_summary.csv`` (``output.jobs: summary``), None when not written."""
        path = self.path / "jobs_summary.csv"
        return pd.read_csv(path) if path.exists() else None

    def message_summary(self) -> pd.DataFrame | None:
        """``messages_summary.csv`` (``output.messages: summary``), None when not written."""
        path = self.path / "messages_summary.csv"
        return pd.read_csv(path) if path.exists() else None

    def schedule(self) -> pd.DataFrame | None:
        """The schedule table (``node, task, state, start_s, end_s``) from ``schedule.csv``, None when not
        written (``output.schedule: off``, or a folder of a version before it)."""
        from netsim.results.files import read_schedule

        path = self.path / "schedule.csv"
        return read_schedule(path) if path.exists() else None

    def scenario(self) -> dict[str, Any] | None:
        """The resolved ``scenario.yaml`` (read bounded and tag-free: a folder may come from anyone), None when
        not written."""
        path = self.path / "scenario.yaml"
        if not path.exists():
            return None
        from netsim.scenario.loader import read_yaml

        data = read_yaml(path)[0]
        return data if isinstance(data, dict) else None

    @property
    def traces(self) -> dict[str, str]:
        """What the run kept (``output``): ``jobs``/``messages`` ``full``, ``summary`` or ``off``; ``schedule``
        ``on`` or ``off``, from the files present."""
        kept = {"jobs": "full", "messages": "full", "schedule": "on"}
        for name in ("jobs", "messages"):
            if not (self.path / f"{name}.csv").exists():
                kept[name] = "summary" if (self.path / f"{name}_summary.csv").exists() else "off"
        if not (self.path / "schedule.csv").exists():
            kept["schedule"] = "off"
        return kept

    def record(self) -> dict[str, Any] | None:
        """``point.json`` of a sweep point (its worker's record), None elsewhere."""
        return read_record(self.path)


def run_folders_in(folder: Path) -> list[RunFolder]:
    """The run folders with results directly inside ``folder`` (a batch folder), sorted by name; incomplete
    ones are skipped with a warning."""
    subs = sorted(p for p in Path(folder).iterdir() if p.is_dir())
    for sub in subs:
        if RunFolder(sub).is_incomplete:
            log.warning("skipping incomplete run folder %s (no meta.json: stopped while writing)", sub)
    return [RunFolder(p) for p in subs if RunFolder(p).has_results]


# --------------------------------------------------------------------------------------------- sweep folders
def _floats(column: pd.Series) -> pd.Series | None:
    """``column`` as float64 when every non-empty cell is a number (``nan``/``inf`` spelled so), else None."""
    try:  # float() of each cell: reads nan and inf, which pandas' number parser leaves as text
        return column.astype(np.float64)
    except (TypeError, ValueError):  # a text column (a factor's text values): kept as text
        return None


def read_summary(path: str | Path) -> pd.DataFrame:
    """The one parse of a sweep's ``summary.csv`` (:mod:`netsim.sweep.summary` writes it).

    ``index`` and ``replicate`` are integers; ``status``, ``error`` and ``folder`` are text with ``""`` for an
    empty cell; every other column that holds only numbers (empty cells, ``nan``, ``inf`` included) is float or
    integer, and a column of text (a factor's text values, ``True``/``False``) keeps its text.

    Parameters
    ----------
    path : str or pathlib.Path
        The ``summary.csv`` file.

    Returns
    -------
    pandas.DataFrame
        One row per run, in file order (sorted by ``index``).
    """
    frame = pd.read_csv(path, keep_default_na=False, na_values=[""])
    for name in frame.columns:
        column = frame[name]
        if name in SUMMARY_TEXT_COLUMNS:
            frame[name] = column.astype(object).fillna("").astype(str)
        elif not pd.api.types.is_numeric_dtype(column) and not pd.api.types.is_bool_dtype(column):
            floats = _floats(column)
            if floats is not None:
                frame[name] = floats
    return frame


class SweepRun(NamedTuple):
    """One run of a sweep: its row of ``summary.csv`` and its folder."""

    index: int  # type: ignore[assignment]  # a field named like tuple.index, which it shadows (an API name)
    replicate: int
    #: Factor name -> value (as ``summary.csv`` holds it).
    values: dict[str, Any]
    folder: RunFolder
    row: dict[str, Any]


@dataclass
class SweepFolder:
    """One sweep folder: ``sweep.json``, ``summary.csv`` and the point folders.

    Parameters
    ----------
    path : pathlib.Path
        The folder ``netsim sweep`` wrote.
    info : dict
        ``sweep.json``: ``sweep`` (name), ``file``, ``base``, ``factors`` (name -> YAML paths), ``runs``,
        ``spec`` (the sweep file as validated: :class:`netsim.sweep.spec.SweepSpec` reads it back).
    """

    path: Path
    info: dict[str, Any]
    _summary: pd.DataFrame | None = field(default=None, repr=False)

    @staticmethod
    def holds_sweep(path: str | Path) -> bool:
        """True when ``path`` has a ``sweep.json`` and a ``summary.csv``."""
        return (Path(path) / SWEEP_MARKER).is_file() and (Path(path) / SUMMARY_NAME).is_file()

    @staticmethod
    def read_info(path: str | Path) -> dict[str, Any] | None:
        """``sweep.json`` of the folder at ``path``, None when it is missing or unreadable."""
        return json_object(Path(path) / SWEEP_MARKER)

    @classmethod
    def open(cls, path: str | Path) -> SweepFolder:
        """The sweep folder at ``path``, refused when it cannot be read as one.

        Raises
        ------
        FolderRefused
            One line: no or an unreadable ``sweep.json``, or no ``summary.csv`` (the sweep never got to the
            end; run it again, it resumes).
        """
        folder = Path(path)
        if not (folder / SWEEP_MARKER).is_file():
            raise FolderRefused(f"'{folder}' is not a sweep folder (no {SWEEP_MARKER}); give the folder that "
                                "`netsim sweep` wrote")
        info = json_object(folder / SWEEP_MARKER)
        if info is None:
            raise FolderRefused(f"'{folder / SWEEP_MARKER}' is not a readable JSON object (damaged); run the sweep "
                                "again with --overwrite")
        if not (folder / SUMMARY_NAME).is_file():
            raise FolderRefused(f"sweep folder '{folder}' has no {SUMMARY_NAME} (the sweep stopped before its end); "
                                "run the sweep again: it resumes")
        return cls(folder, info)

    @property
    def name(self) -> str:
        """The sweep's name (``sweep.json``), else the folder's."""
        return str(self.info.get("sweep") or self.path.name)

    @property
    def factors(self) -> list[str]:
        """The factor names, in the sweep file's order (the factor columns of ``summary.csv``)."""
        factors = self.info.get("factors") or {}
        return [str(f) for f in factors]

    @property
    def spec_data(self) -> dict[str, Any] | None:
        """The validated sweep file as JSON data (``SweepSpec.model_validate`` reads it), None when absent."""
        spec = self.info.get("spec")
        return spec if isinstance(spec, dict) else None

    @property
    def summary_path(self) -> Path:
        """``<folder>/summary.csv``."""
        return self.path / SUMMARY_NAME

    def summary(self) -> pd.DataFrame:
        """``summary.csv`` (:func:`read_summary`; read once, a copy each call)."""
        if self._summary is None:
            self._summary = read_summary(self.summary_path)
        return self._summary.copy()

    def runs(self, *, with_results: bool = True) -> list[SweepRun]:
        """The runs of ``summary.csv`` in its order.

        Parameters
        ----------
        with_results : bool, default True
            Only runs whose folder is complete and holds metrics or jobs (a pending or failed ``runs: metrics``
            point has none).
        """
        factors = self.factors
        out = []
        for row in self.summary().to_dict("records"):
            run = RunFolder(self.path / str(row["folder"]))
            if with_results and not run.has_results:
                continue
            out.append(SweepRun(int(row["index"]), int(row["replicate"]), {f: row[f] for f in factors if f in row},
                                run, cast(dict[str, Any], row)))  # summary.csv's columns are text
        return out

    def verify(self) -> None:
        """Raise :class:`FolderRefused` (one line) for the first run folder with results that was changed since
        the sweep wrote it (it no longer matches its ``manifest.json``)."""
        for run in self.runs():
            if (run.folder.path / MANIFEST_NAME).exists() or (run.folder.path / RECORD_NAME).exists():
                run.folder.refuse_if_unreadable()
