"""The result of one run: tidy tables, metrics and metadata, and the run folder they are written to.

A :class:`RunResult` holds

``signals``
    wide table, ``time_s`` first, then one column per recorded signal; one row per instant at which any
    signal was sampled; each column holds its last value (forward fill) between its own samples and is empty
    before its first sample.
``jobs``
    one row per job: ``node, task, job_id, release_s, start_s, finish_s, response_s, deadline_s,
    deadline_met, preemptions, cpu_time_s, killed, outcome`` (empty cells for jobs unfinished at the end;
    ``response_s`` is empty for killed jobs too). ``deadline_met`` and ``outcome`` follow one rule,
    :func:`netsim.kernel.records.deadline_verdict`: ``outcome`` is ``met``, ``missed`` (finished late, or
    unfinished with its deadline at or before the end), ``killed`` (a miss too), ``pending`` (unfinished and
    not yet due: neither met nor missed) or ``done`` (finished, no deadline).
``messages``
    one row per message copy: ``msg_id, network, sender, receiver, tag, bits, priority, sent_s,
    tx_start_s, delivered_s, dropped, drop_reason, delay_s, tx_end_s``.
``metrics``
    a :class:`pandas.Series` metric name -> value.
``meta``
    seed, scenario name and hash, package versions, wall time, status (``ok``, ``error``,
    ``diverged at t = ... s``) and error text.
``schedule``
    the kernels' schedule traces ``node, task, state, start_s, end_s`` (for Gantt charts), written as
    ``schedule.csv`` (times in integer ns: ``node,task,state,start_ns,end_ns``) and read back by
    :meth:`RunResult.read`; not kept with ``output.schedule: off`` (no file, an empty table).

Run folder layout (see :meth:`RunResult.to_csv`): ``scenario.yaml``, ``signals.csv``, ``jobs.csv``,
``messages.csv``, ``schedule.csv``, ``metrics.csv`` (``metric,value``), ``meta.json``. CSVs use a fixed float format and a
stable column order, so the same scenario and seed give byte-identical files. A scenario's ``output: {jobs:
summary}`` (``messages: summary``) writes ``jobs_summary.csv`` (``messages_summary.csv``) instead of the rows;
``off`` writes neither (:mod:`netsim.results.traces`). Run and sweep folders are read back in one place,
:mod:`netsim.results.folder` (:class:`RunFolder`, :class:`SweepFolder`); :meth:`RunResult.read` reads through it.

Why this module is long: :class:`RunResult` is the public result class, and about half of the module is its
methods' numpydoc docstrings (typed parameters, returns and a runnable example each, issue 27); the code the
tables are built with lives in :mod:`netsim.results.tables`, ``files``, ``rows`` and ``signals``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Mapping, TypeVar, cast

import numpy as np

from netsim.lazy_import import lazy_exports, lazy_module

if TYPE_CHECKING:
    import pandas as pd
else:  # imported at its first use: `netsim run` and `validate` build no DataFrame (issue 29)
    pd = lazy_module("pandas")

from netsim.results.files import (
    FLOAT_FORMAT,
    TIME_COLUMNS,
    schedule_csv_chunks,
    schedule_intervals,
    write_csv,
)
from netsim.results.summary import key_metrics

if TYPE_CHECKING:
    from control import TimeResponseData
    from matplotlib.figure import Figure

    from netsim.results.folder import FolderRefused, RunFolder, SweepFolder, read_summary
from netsim.results.tables import (
    JOB_COLUMNS,
    JOB_SUMMARY_COLUMNS,
    MESSAGE_COLUMNS,
    MESSAGE_SUMMARY_COLUMNS,
    SCHEDULE_COLUMNS,
    check_out_dir,
    jobs_table,
    messages_table,
    schedule_table,
    signals_table,
    summary_table,
)

__all__ = [
    "RunResult",
    "Lazy",
    "JOB_COLUMNS",
    "MESSAGE_COLUMNS",
    "SCHEDULE_COLUMNS",
    "FLOAT_FORMAT",
    "signals_table",
    "jobs_table",
    "messages_table",
    "schedule_table",
    "summary_table",
    "JOB_SUMMARY_COLUMNS",
    "MESSAGE_SUMMARY_COLUMNS",
    "write_csv",
    "check_out_dir",
    "key_metrics",
    "TIME_COLUMNS",
    "RunFolder",
    "SweepFolder",
    "FolderRefused",
    "read_summary",
]


#: The readers of run and sweep folders, imported at first use: a run only writes its folder (issue 29, start-up).
__getattr__, __dir__ = lazy_exports(__name__, {name: "netsim.results.folder" for name in
                                               ("FolderRefused", "RunFolder", "SweepFolder", "read_summary")})


def _json_default(obj: Any) -> Any:
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.floating,)):
        return float(obj)
    if isinstance(obj, Path):
        return str(obj)
    return str(obj)


#: The files :meth:`RunResult.to_csv` writes besides ``metrics.csv`` and ``meta.json``.
_TABLE_FILES = ("scenario.yaml", "signals.csv", "jobs.csv", "messages.csv", "jobs_summary.csv", "messages_summary.csv",
                "schedule.csv")


def _empty_signals() -> pd.DataFrame:
    return pd.DataFrame({"time_s": pd.Series([], dtype=float)})


def _empty_metrics() -> pd.Series:
    return pd.Series(dtype=float, name="value")


_T = TypeVar("_T")


def _unbuilt(build: Callable[[], _T]) -> _T:
    """A :class:`Lazy` for a :class:`RunResult` field, typed as the value it turns into when the field is read."""
    return cast(_T, Lazy(build))


class Lazy:
    """A table built on first access: a :class:`RunResult` field holding one calls ``build()`` when read, and
    keeps the table (issue 19: DataFrames only when asked for; the schedule trace, read only by the Gantt
    chart, is never built in most runs)."""

    __slots__ = ("build",)

    def __init__(self, build: Any) -> None:
        self.build = build


@dataclass
class RunResult:
    """Tables, metrics and metadata of one run (see the module docstring for the columns).

    :func:`netsim.run` returns one; :meth:`read` loads one from a run folder. A table field may hold a
    :class:`Lazy`: it is built when first read.

    Parameters
    ----------
    signals : pandas.DataFrame
        ``time_s``, then one column per recorded signal.
    jobs : pandas.DataFrame
        One row per job (columns :data:`JOB_COLUMNS`).
    messages : pandas.DataFrame
        One row per message copy (columns :data:`MESSAGE_COLUMNS`).
    metrics : pandas.Series
        Metric name -> value.
    meta : dict
        Seed, scenario name and hash, package versions, wall time, ``status``, error text.
    scenario : dict, optional
        The resolved scenario the run was made from.
    schedule : pandas.DataFrame
        The kernels' schedule traces (columns :data:`SCHEDULE_COLUMNS`).
    out_dir : pathlib.Path, optional
        The run folder, when one was written or read.
    traces : dict of str to str
        The scenario's ``output`` settings: ``jobs``/``messages`` ``full``, ``summary`` or ``off``; ``schedule``
        ``on`` or ``off``.
    job_summary : pandas.DataFrame, optional
        Per-task statistics (``output.jobs: summary``).
    message_summary : pandas.DataFrame, optional
        Per-network statistics (``output.messages: summary``).

    Examples
    --------
    >>> empty = RunResult()
    >>> empty.status, list(empty.signals.columns)
    ('ok', ['time_s'])
    >>> result = netsim.run("scenarios/dc_servo_can.yaml")                     # doctest: +SKIP
    >>> result.jobs.groupby("task")["response_s"].max()                         # doctest: +SKIP
    """

    def __getattribute__(self, name: str) -> Any:
        value = object.__getattribute__(self, name)
        if type(value) is Lazy:
            value = value.build()
            object.__setattr__(self, name, value)
        return value

    def __getstate__(self) -> dict[str, Any]:
        """Pickled and copied with every table built (a :class:`Lazy` holds a closure, which does not pickle); the
        records and samples the tables were built from are left behind."""
        state = {name: getattr(self, name) for name in object.__getattribute__(self, "__dict__")}
        state.update(_job_rows=None, _message_rows=None, _signal_source=None, _schedule_source=None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        object.__getattribute__(self, "__dict__").update(state)

    # the empty tables are Lazy too: a run fills them in, and pandas is imported only when one is read (issue 29)
    signals: pd.DataFrame = field(default_factory=lambda: _unbuilt(_empty_signals))
    jobs: pd.DataFrame = field(default_factory=lambda: _unbuilt(lambda: pd.DataFrame(columns=JOB_COLUMNS)))
    messages: pd.DataFrame = field(default_factory=lambda: _unbuilt(lambda: pd.DataFrame(columns=MESSAGE_COLUMNS)))
    metrics: pd.Series = field(default_factory=lambda: _unbuilt(_empty_metrics))
    meta: dict[str, Any] = field(default_factory=dict)
    scenario: dict[str, Any] | None = None
    schedule: pd.DataFrame = field(default_factory=lambda: _unbuilt(lambda: pd.DataFrame(columns=SCHEDULE_COLUMNS)))
    out_dir: Path | None = None
    #: The scenario's trace settings (``output.jobs``, ``messages``, ``schedule``): a table not kept in ``full``
    #: is not written (``jobs.csv`` / ``messages.csv``), its summary is (:mod:`netsim.results.traces`).
    traces: dict[str, str] = field(default_factory=lambda: {"jobs": "full", "messages": "full", "schedule": "on"})
    #: Per-task statistics (``output.jobs: summary``; columns :data:`JOB_SUMMARY_COLUMNS`), else None.
    job_summary: pd.DataFrame | None = None
    #: Per-network statistics (``output.messages: summary``; columns :data:`MESSAGE_SUMMARY_COLUMNS`), else None.
    message_summary: pd.DataFrame | None = None
    #: The jobs table's columns straight from the records (:class:`netsim.results.rows.Rows`; this run's, not one
    #: read back): ``jobs.csv`` and the metrics are made from them, ``jobs`` is built from them when read.
    _job_rows: Any = None
    #: The messages table's columns straight from the records (as :attr:`_job_rows`).
    _message_rows: Any = None
    #: The recorded samples (:class:`netsim.results.signals.SignalSource`): ``signals.csv`` and the metrics read
    #: the table from them window by window, ``signals`` is built from them when read.
    _signal_source: Any = None
    #: The kernels' schedule traces ``[(node, [(task, state, t0_ns, t1_ns), ...]), ...]`` (this run's): ``schedule.csv``
    #: is written from them, ``schedule`` is built from them when read.
    _schedule_source: Any = None
    #: Metrics streamed while the run went, by key (:func:`netsim.results.traces.attach_streams`; this run's).
    _streams: Any = None
    #: The metrics as floats by name while ``metrics`` is unbuilt (:meth:`_set_metrics`): ``metrics.csv`` and the
    #: command line's summary read them, ``metrics`` is built from them when read.
    _metric_values: dict[str, float] | None = None

    def _set_metrics(self, values: Mapping[Any, Any]) -> None:
        """Set :attr:`metrics` from a name -> value mapping: ``pandas.Series(values, dtype=float, name="value")``,
        built when first read (``metrics.csv`` and :meth:`metric_values` need no pandas).

        Parameters
        ----------
        values : Mapping
            Metric name -> value (a number, or None for NaN).

        Examples
        --------
        >>> run = RunResult()
        >>> run._set_metrics({"y.ISE": 0.25, "y.IAE": None})
        >>> run.metric_values()
        {'y.ISE': 0.25, 'y.IAE': nan}
        >>> run.metrics.to_dict()
        {'y.ISE': 0.25, 'y.IAE': nan}
        """
        data = dict(values)

        def series() -> pd.Series:
            return pd.Series(data, dtype=float, name="value")

        try:  # the same float conversion as the Series' (None -> NaN, bool -> 0.0/1.0)
            floats = np.asarray(list(data.values()), dtype=float)
        except (TypeError, ValueError):
            floats = None
        if floats is None or floats.ndim != 1 or not all(isinstance(name, str) for name in data):
            self.metrics, self._metric_values = series(), None  # the Series says what is wrong with the values
            return
        self.metrics = _unbuilt(series)
        self._metric_values = dict(zip(data, floats.tolist()))

    def metric_values(self) -> dict[str, float]:
        """The metrics as a plain dict, name -> value (:attr:`metrics` without building its pandas Series).

        Returns
        -------
        dict of str to float
            In ``metrics.csv`` order.

        Examples
        --------
        >>> RunResult(metrics=pd.Series({"y.ISE": 0.25})).metric_values()
        {'y.ISE': 0.25}
        """
        plain = self._unbuilt_metrics()
        if plain is not None:
            return dict(plain)
        return {str(k): float(v) for k, v in zip(self.metrics.index, self.metrics.to_numpy(dtype=float))}

    def _unbuilt_metrics(self) -> dict[str, float] | None:
        """:attr:`_metric_values` while :attr:`metrics` is unbuilt (nothing can have changed it), else None."""
        if type(object.__getattribute__(self, "metrics")) is not Lazy:
            return None
        return object.__getattribute__(self, "_metric_values")

    def _signal_chunks(self, names: list[str]) -> Any:
        """The signals table's rows in windows, ``(t_ns, [column of each name, ...])`` per window
        (:meth:`netsim.results.signals.SignalSource.chunks`), while ``signals`` has not been built; else None
        (read ``signals``). A name that was not recorded raises ``KeyError``."""
        source = object.__getattribute__(self, "_signal_source")
        if source is None or type(object.__getattribute__(self, "signals")) is not Lazy:
            return None
        missing = [n for n in names if n not in source.names]
        if missing:
            raise KeyError(missing[0])
        return source.chunks(names)

    def _table_rows(self, name: str) -> Any:
        """The :class:`~netsim.results.rows.Rows` of table ``name`` (``"jobs"`` or ``"messages"``) while its
        DataFrame has not been built (nothing can have changed it), else None: read the DataFrame."""
        if type(object.__getattribute__(self, name)) is not Lazy:
            return None
        return object.__getattribute__(self, "_job_rows" if name == "jobs" else "_message_rows")

    @property
    def status(self) -> str:
        """``"ok"``, ``"diverged at t = ... s"``, ``"unstable at t = ... s"`` (the loop left its operating region,
        :mod:`netsim.results.verdict`), ``"error"`` or ``"interrupted at t = ... s"`` (``meta["status"]``, :mod:`netsim.status`).

        Examples
        --------
        >>> RunResult(meta={"status": "diverged at t = 1.5 s"}).status
        'diverged at t = 1.5 s'
        """
        return str(self.meta.get("status", "ok"))

    @property
    def ok(self) -> bool:
        """True when the run finished normally (``status == "ok"``).

        Examples
        --------
        >>> RunResult().ok, RunResult(meta={"status": "error"}).ok
        (True, False)
        """
        return self.status == "ok"

    def signal(self, name: str) -> pd.Series:
        """One recorded signal, indexed by time.

        Parameters
        ----------
        name : str
            The signal's column in ``signals``.

        Returns
        -------
        pandas.Series
            Its values (held between its samples, NaN before the first), indexed by ``time_s``.

        Raises
        ------
        KeyError
            Naming the recorded signals, when ``name`` is not one.

        Examples
        --------
        >>> run = RunResult(signals=pd.DataFrame({"time_s": [0.0, 0.5], "y": [0.0, 1.0]}))
        >>> run.signal("y").to_dict()
        {0.0: 0.0, 0.5: 1.0}
        """
        if name not in self.signals.columns:
            raise KeyError(f"no recorded signal '{name}'; recorded: {', '.join(self.signals.columns[1:])}")
        return pd.Series(self.signals[name].to_numpy(), index=self.signals["time_s"].to_numpy(), name=name)

    def metrics_frame(self) -> pd.DataFrame:
        """The metrics as a table, as ``metrics.csv`` holds them.

        Returns
        -------
        pandas.DataFrame
            Two columns: ``metric`` and ``value``.

        Examples
        --------
        >>> RunResult(metrics=pd.Series({"y.ISE": 0.25})).metrics_frame().to_dict("records")
        [{'metric': 'y.ISE', 'value': 0.25}]
        """
        return pd.DataFrame({"metric": list(self.metrics.index), "value": list(self.metrics.to_numpy(dtype=float))})

    def to_csv(self, out_dir: str | Path, tables: bool = True) -> Path:
        """Write the run folder (see the module docstring for its files).

        Every file is written atomically (:func:`netsim.safe_write.write_atomic`) and ``meta.json`` last: a
        folder without ``meta.json`` is incomplete (a run killed while writing), and ``netsim report`` and
        ``netsim sweep`` treat it so.

        Parameters
        ----------
        out_dir : str or pathlib.Path
            The folder (created if needed).
        tables : bool, default True
            False: only ``metrics.csv`` and ``meta.json`` (a sweep's ``runs: metrics``).

        Returns
        -------
        pathlib.Path
            The folder; also stored in ``out_dir``.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> folder = RunResult(meta={"scenario": "demo"}).to_csv(tempfile.mkdtemp())
        >>> sorted(p.name for p in folder.iterdir())
        ['jobs.csv', 'messages.csv', 'meta.json', 'metrics.csv', 'schedule.csv', 'signals.csv']
        """
        from netsim.safe_write import write_atomic

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        stale = out / "meta.json"
        if stale.exists() or stale.is_symlink():
            stale.unlink()  # rewriting a folder: it is incomplete until the new meta.json is written
        if tables:
            self._write_tables(out)
        else:  # a folder written before with its tables: they are not this run's
            for name in _TABLE_FILES:
                (out / name).unlink(missing_ok=True)
        from netsim.status import ERROR, INTERRUPTED, kind_of

        if kind_of(self.status) not in (ERROR, INTERRUPTED):  # a failed or cut run has no metrics: see meta.json
            from netsim.results.files import metrics_text

            plain = self._unbuilt_metrics()
            if plain is not None:  # no Series built: the values it would hold (_set_metrics)
                text = metrics_text(list(plain), list(plain.values()))
            else:
                names = [str(k) for k in self.metrics.index]
                text = metrics_text(names, list(self.metrics.to_numpy(dtype=float))) if all(
                    isinstance(k, str) for k in self.metrics.index) else None
            if text is not None:
                write_atomic(out / "metrics.csv", text)
            else:
                write_csv(self.metrics_frame(), out / "metrics.csv")
        # meta.json last: its presence marks the folder complete (a folder without it is incomplete)
        write_atomic(out / "meta.json", json.dumps(self.meta, indent=2, sort_keys=True, default=_json_default) + "\n")
        self.out_dir = out
        return out

    def _write_tables(self, out: Path) -> None:
        """``scenario.yaml``, ``signals.csv``, ``jobs.csv``/``messages.csv`` (or their summaries) into ``out``."""
        from netsim.safe_write import write_atomic

        if self.scenario is not None:
            import yaml

            dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)  # libyaml's emitter: ~4x faster
            write_atomic(out / "scenario.yaml",
                         yaml.dump(self.scenario, Dumper=dumper, sort_keys=False, allow_unicode=True))
        source = object.__getattribute__(self, "_signal_source")
        if source is not None and type(object.__getattribute__(self, "signals")) is Lazy and source.csv_plain():
            write_atomic(out / "signals.csv", source.csv_chunks())  # window by window, never the whole table
        else:
            write_csv(self.signals, out / "signals.csv")
        for name, summary in (("jobs", self.job_summary), ("messages", self.message_summary)):
            if self.traces.get(name, "full") == "full":
                rows = self._table_rows(name)
                chunks = rows.csv_chunks() if rows is not None else None
                if chunks is not None:  # straight from the records: the same bytes as the DataFrame's
                    write_atomic(out / f"{name}.csv", chunks)
                else:
                    write_csv(getattr(self, name), out / f"{name}.csv")
            if summary is not None:
                write_csv(summary, out / f"{name}_summary.csv")
        sched = out / "schedule.csv"
        if self.traces.get("schedule", "on") == "on":
            source = object.__getattribute__(self, "_schedule_source")
            if source is None or type(object.__getattribute__(self, "schedule")) is not Lazy:
                source = schedule_intervals(self.schedule)
            write_atomic(sched, schedule_csv_chunks(source))
        else:
            sched.unlink(missing_ok=True)  # a folder written before: its trace is not this run's

    def plot(self, save: str | Path | None = None, *, window: Any = None, fig: Any = None) -> Figure:
        """The responses figure (:func:`netsim.plotting.responses_figure`): outputs and references, actuator values,
        other signals, in panels.

        Parameters
        ----------
        save : str or pathlib.Path, optional
            A folder: also write ``responses.png``, ``schedule.png`` and ``network.png`` there (otherwise save
            the returned figure yourself with ``fig.savefig(path)``).
        window : float or tuple of float, optional
            Time window of the saved Gantt chart and network timeline: ``(t0, t1)`` or a length in seconds
            (default: the window where every job spans 2 px, the whole run when it fits; see
            :func:`netsim.plotting.density_window`).
        fig : matplotlib.figure.Figure or SubFigure, optional
            An empty figure to draw the panels into (default: a new one).

        Returns
        -------
        matplotlib.figure.Figure
            The figure drawn on; a new one shows inline in a Jupyter notebook without ``%matplotlib inline``.

        Examples
        --------
        >>> result = netsim.run("scenarios/dc_servo_can.yaml")                 # doctest: +SKIP
        >>> result.plot().savefig("responses.pdf")                              # doctest: +SKIP
        """
        from netsim.plotting import responses_figure, save_figures

        if save is not None:
            save_figures(self, save, window=window)
        return responses_figure(self.signals, self.scenario, status=self.status,
                                title=str(self.meta.get("scenario", "")), fig=fig)

    def plot_schedule(self, window: Any = None, *, ax: Any = None) -> Figure:
        """Gantt chart of the kernels' schedules (:func:`netsim.plotting.schedule_figure`).

        A run made with ``output.schedule: off`` kept no trace: the chart then says so in its title.

        Parameters
        ----------
        window : float or tuple of float, optional
            ``(t0, t1)`` or a length in seconds (default: the window where every job spans 2 px, the whole
            run when it fits).
        ax : matplotlib.axes.Axes, optional
            The axes to draw on (default: a new figure's).

        Returns
        -------
        matplotlib.figure.Figure
            The figure drawn on.

        Examples
        --------
        >>> result = netsim.run("scenarios/dc_servo_can.yaml")                 # doctest: +SKIP
        >>> result.plot_schedule(window=(0, 0.05)).savefig("schedule.png")      # doctest: +SKIP
        """
        from netsim.plotting import schedule_figure

        title = "schedule: not kept (output.schedule: off)" if self.traces.get("schedule") == "off" else ""
        return schedule_figure(self.schedule, self.jobs, window=window, end_s=float(self.meta.get("t_end_s") or 0),
                               title=title, ax=ax)

    def plot_network(self, window: Any = None, *, ax: Any = None) -> Figure:
        """Network timeline: transmissions, delays and drops (:func:`netsim.plotting.network_figure`).

        Parameters
        ----------
        window : float or tuple of float, optional
            ``(t0, t1)`` or a length in seconds (default: the window where every job spans 2 px, the whole
            run when it fits).
        ax : matplotlib.axes.Axes, optional
            The axes to draw on (default: a new figure's).

        Returns
        -------
        matplotlib.figure.Figure
            The figure drawn on.

        Examples
        --------
        >>> import matplotlib.pyplot as plt                                     # doctest: +SKIP
        >>> fig, (top, bottom) = plt.subplots(2, 1, sharex=True)                # doctest: +SKIP
        >>> result.plot_schedule(window=0.1, ax=top)                            # doctest: +SKIP
        >>> result.plot_network(window=0.1, ax=bottom)                          # doctest: +SKIP
        """
        from netsim.plotting import network_figure

        return network_figure(self.messages, window=window, end_s=float(self.meta.get("t_end_s") or 0), ax=ax)

    def to_timeresponse(self, *, outputs: list[str] | None = None, inputs: list[str] | None = None,
                        states: list[str] | None = None) -> TimeResponseData:
        """The recorded signals as python-control's ``TimeResponseData``
        (:func:`netsim.results.interop.to_timeresponse`).

        Parameters
        ----------
        outputs : list of str, optional
            Recorded columns to use as the outputs (default: the plant's outputs recorded on
            ``plant.record_grid``, else the ``io`` sensor channels).
        inputs : list of str, optional
            Columns to use as the inputs (default: the plant's held inputs ``<plant>.u[i]``, else the DAC channels).
        states : list of str, optional
            Columns to use as the states (default: ``<plant>.x[i]`` when recorded, labelled with the plant's state
            names; ``[]``: none).

        Returns
        -------
        control.TimeResponseData
            ``time`` in seconds, ``outputs``, ``inputs`` and ``states`` with their signal names as labels.

        Examples
        --------
        >>> result = netsim.run("scenarios/pendulum_lqr.yaml", overrides={"record": None})  # doctest: +SKIP
        >>> resp = result.to_timeresponse()                                                 # doctest: +SKIP
        >>> resp.output_labels, resp.state_labels[:2]                                       # doctest: +SKIP
        (['theta', 'alpha'], ['theta', 'theta_dot'])
        """
        from netsim.results.interop import to_timeresponse

        return to_timeresponse(self.signals, self.scenario, name=str(self.meta.get("scenario", "")), outputs=outputs,
                               inputs=inputs, states=states)

    def to_pandas(self) -> pd.DataFrame:
        """The recorded signals indexed by time in seconds (a copy; python-control's ``to_pandas``).

        Returns
        -------
        pandas.DataFrame
            One column per recorded signal, index ``time_s``.

        Examples
        --------
        >>> RunResult(signals=pd.DataFrame({"time_s": [0.0, 0.5], "y": [0.0, 1.0]})).to_pandas().index.name
        'time_s'
        """
        return self.signals.set_index("time_s")

    def summary(self) -> dict[str, Any]:
        """What a reader wants first (what ``netsim run`` prints, and a notebook shows).

        Returns
        -------
        dict
            ``scenario``, ``status``, ``duration_s`` (simulated), ``wall_time_s``, ``folder`` (or None), and
            ``control`` and ``timing``: ``(name, text)`` rows of the key metrics (:func:`key_metrics`: control
            measures, then worst responses, deadline misses, network loss and delay).

        Examples
        --------
        >>> RunResult(meta={"scenario": "demo", "t_end_s": 2.0}).summary()["duration_s"]
        2.0
        """
        control, timing = key_metrics(self.metric_values())
        return {"scenario": self.meta.get("scenario", ""), "status": self.status,
                "duration_s": self.meta.get("t_end_s", self.meta.get("duration_s")),
                "wall_time_s": self.meta.get("wall_time_s"), "folder": None if self.out_dir is None else
                str(self.out_dir), "control": control, "timing": timing}

    def _repr_html_(self) -> str:
        """A notebook's summary: status, duration, key metrics (the same as ``netsim run`` prints)."""
        from html import escape

        info = self.summary()
        ok = "green" if self.ok else "red"
        head = (f"<b>{escape(str(info['scenario']) or 'run')}</b>: <span style='color:{ok}'>"
                f"{escape(self.status)}</span>")
        facts = []
        if info["duration_s"] is not None:
            facts.append(f"{float(info['duration_s']):.6g} s simulated")
        if info["wall_time_s"] is not None:
            facts.append(f"in {float(info['wall_time_s']):.3g} s")
        if info["folder"]:
            facts.append(f"folder {escape(info['folder'])}")
        rows = "".join(f"<tr><td>{escape(k)}</td><td>{escape(v)}</td></tr>" for k, v in info["control"] + info["timing"])
        table = f"<table>{rows}</table>" if rows else "<p>no metrics</p>"
        said = f" ({', '.join(facts)})" if facts else ""
        return f"<div>{head}{said}{table}</div>"

    def __repr__(self) -> str:
        return (f"RunResult({self.meta.get('scenario', '')!r}, status={self.status!r}, signals={len(self.signals)} "
                f"rows, jobs={len(self.jobs)}, messages={len(self.messages)}, metrics={len(self.metrics)})")

    @classmethod
    def read(cls, run_dir: str | Path) -> "RunResult":
        """Load a run folder written by :meth:`to_csv` (or ``netsim run``): the same values and column types.

        Signals are floats (a signal holding whole numbers stays float), jobs' ``deadline_met`` is a nullable
        boolean, text columns stay text (an empty ``drop_reason`` is ``""``, not NaN).

        Parameters
        ----------
        run_dir : str or pathlib.Path
            The run folder.

        Returns
        -------
        RunResult
            Its tables, metrics, meta and scenario; ``out_dir`` is the folder. A folder written with only its
            metrics (a sweep's ``runs: metrics``) gives empty tables.

        Raises
        ------
        netsim.results.folder.FolderRefused
            One line, for a folder without ``meta.json`` (a run killed while writing, or still running), with a
            damaged one, or a sweep point changed since the sweep wrote it (:class:`netsim.results.folder.RunFolder`
            reads the folder).

        Examples
        --------
        >>> import tempfile
        >>> folder = RunResult(meta={"scenario": "demo"}).to_csv(tempfile.mkdtemp())
        >>> RunResult.read(folder).meta["scenario"]
        'demo'
        """
        from netsim.results.folder import RunFolder

        run = RunFolder.open(run_dir)  # refuses an incomplete folder, or a sweep point changed since it was written
        jobs, messages, schedule = run.jobs(), run.messages(), run.schedule()
        return cls(run.signals(), pd.DataFrame(columns=JOB_COLUMNS) if jobs is None else jobs,
                   pd.DataFrame(columns=MESSAGE_COLUMNS) if messages is None else messages, run.metrics(), run.meta,
                   run.scenario(), schedule=pd.DataFrame(columns=SCHEDULE_COLUMNS) if schedule is None else schedule,
                   out_dir=run.path, traces=run.traces, job_summary=run.job_summary(),
                   message_summary=run.message_summary())
