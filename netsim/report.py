"""CSV tables (and figures) from a run folder, a batch folder or a sweep folder: ``netsim report DIR``.

:func:`report` reads the run folders (``metrics.csv``, ``jobs.csv``, ``messages.csv``, ``meta.json``) through
:mod:`netsim.results.folder` (an incomplete run folder, or a sweep point changed since the sweep wrote it, is
refused in one line) and returns, and writes as CSV into ``out`` (default ``<DIR>/report/``):

``utilization``
    One row per case (run, batch entry or sweep run): ``case`` (sweep runs: ``index``, ``replicate`` and
    the factor columns), ``status``, then the indices of Cuenca et al. as the run's ``et_control`` metric
    computed them: ``Nsc_count, Nca_count, NTTS_count`` (transmissions sensor->controller,
    controller->actuator, and of the time-triggered run), ``Uc_ratio, Ua_ratio`` (eqs 26-27),
    ``Cc_pct`` (eq 28), ``CS_pct`` (eq 20), ``ISE, ISEP`` (eqs 23-24, in output units), ``NE_ratio``
    (eq 25) and ``GPI`` (eq 29). A metric a run does not have is empty.
``nodes``
    One row per case and node: ``case, node, cpu_util_ratio`` (all tasks, handlers and context switches,
    the run's ``cpu.<node>.utilization`` metric).
``tasks``
    One row per case and task (from ``jobs.csv``): ``case, node, task, jobs_count, cpu_time_s,
    cpu_util_ratio`` (CPU time / run duration), ``response_mean_s, response_std_s, response_min_s,
    response_p95_s, response_max_s`` (completed jobs only: killed and unfinished jobs have no response time),
    ``deadline_misses_count`` (finished late, unfinished past the deadline, or killed), ``preemptions_count,
    killed_count, pending_count`` (unfinished and not yet due at the end: neither met nor missed).
``networks``
    One row per case and network (from ``messages.csv``; one row there per receiver copy):
    ``case, network, messages_count, delivered_count, dropped_count, loss_ratio, bits_total,
    delay_mean_s, delay_std_s, delay_min_s, delay_p95_s, delay_max_s`` (delivered copies, send to
    delivery), ``wait_mean_s`` (send to start of transmission), ``utilization_ratio`` (the run's
    ``net.<name>.utilization`` metric).
``summary`` (sweeps)
    ``summary.csv`` as written by the sweep; ``optimum`` (sweeps with a surface) one row.

Figures (``plots=True``, paper style, in the format of :func:`netsim.figure_style.plot_format`):
``utilization.png`` (Uc, Ua, NE and GPI: for a sweep over two numeric factors a heat map per index over
them, else bars per case, up to 40 cases),
``response_times.png`` and ``network_delays.png`` (mean and max per task/network, up to 40 rows), and for
sweeps with a ``surface:`` the surface figure again.

If the argument is not a folder but the name of a registered ``report`` (``netsim list reports``), that
case-study report function ``fn(out_dir, plots)`` is called instead.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import Any, Iterable

import numpy as np
import pandas as pd

from netsim.errors import ConfigError
from netsim.lazy_import import callable_module as _callable_module
from netsim.metrics.runtime import job_outcome_counts
from netsim.results.folder import SWEEP_MARKER, RunFolder, SweepFolder, run_folders_in

__all__ = [
    "report",
    "UTILIZATION_COLUMNS",
    "TASK_COLUMNS",
    "NETWORK_COLUMNS",
    "find_runs",
    "utilization_table",
    "task_table",
    "network_table",
    "node_table",
    "NODE_COLUMNS",
]

log = logging.getLogger(__name__)

#: (metric name in metrics.csv, column in the utilization table)
UTILIZATION_COLUMNS: list[tuple[str, str]] = [
    ("et.Nsc", "Nsc_count"),
    ("et.Nca", "Nca_count"),
    ("et.N_TTS", "NTTS_count"),
    ("et.Uc", "Uc_ratio"),
    ("et.Ua", "Ua_ratio"),
    ("et.Cc", "Cc_pct"),
    ("et.CS", "CS_pct"),
    ("et.ISE", "ISE"),
    ("et.ISEP", "ISEP"),
    ("et.NE", "NE_ratio"),
    ("et.GPI", "GPI"),
]
TASK_COLUMNS = [
    "case", "node", "task", "jobs_count", "cpu_time_s", "cpu_util_ratio", "response_mean_s", "response_std_s",
    "response_min_s", "response_p95_s", "response_max_s", "deadline_misses_count", "preemptions_count",
    "killed_count", "pending_count",
]
NETWORK_COLUMNS = [
    "case", "network", "messages_count", "delivered_count", "dropped_count", "loss_ratio", "bits_total",
    "delay_mean_s", "delay_std_s", "delay_min_s", "delay_p95_s", "delay_max_s", "wait_mean_s",
    "utilization_ratio",
]
NODE_COLUMNS = ["case", "node", "cpu_util_ratio"]
_MAX_PLOTTED = 40


# --------------------------------------------------------------------------------------------- finding runs
#: One case of a report: its name, its run folder and the columns placed after ``case`` (sweep runs: index,
#: replicate, factor values).
Case = tuple[str, RunFolder, dict[str, Any]]


def find_runs(folder: Path) -> tuple[str, list[Case]]:
    """The kind of ``folder`` (``run``, ``sweep`` or ``batch``) and its runs as ``(case, run folder, extra)``.

    ``extra`` holds columns placed after ``case`` (sweep runs: index, replicate, factor values). The folders are
    read by :mod:`netsim.results.folder`: an incomplete run folder, or a sweep point changed since the sweep
    wrote it, is refused (:class:`~netsim.results.folder.FolderRefused`, one line); incomplete folders inside a
    batch folder are skipped with a warning.
    """
    kind, runs, _ = _find(folder)
    return kind, runs


def _find(folder: Path) -> tuple[str, list[Case], SweepFolder | None]:
    """:func:`find_runs`, and the sweep folder when ``folder`` holds a sweep."""
    if (folder / SWEEP_MARKER).is_file():  # a sweep folder; without summary.csv it is refused: resume the sweep
        sweep = SweepFolder.open(folder)
        sweep.verify()
        runs: list[Case] = [(r.folder.path.name, r.folder, {"index": r.index, "replicate": r.replicate, **r.values})
                            for r in sweep.runs()]
        return "sweep", runs, sweep
    run = RunFolder(folder)
    if run.has_results:
        run.refuse_if_unreadable()
        return "run", [(run.name, run, {})], None
    if run.is_incomplete:
        run.refuse_if_unreadable()  # raises: no meta.json
    subs = run_folders_in(folder)
    if not subs:
        raise ConfigError(
            f"'{folder}' is not a run folder (no metrics.csv), a sweep folder (no sweep.json) or a batch folder "
            "(no run folders inside); give the folder that `netsim run/batch/sweep` wrote"
        )
    return "batch", [(p.path.name, p, {}) for p in subs], None


def _metrics(run: RunFolder) -> dict[str, float]:
    from netsim.metrics.et import canonical_metric_names

    # run folders of older versions used unprefixed names (Nsc, GPI, ...): read them under today's names
    return canonical_metric_names(run.metric_values())


def _as_bool(series: pd.Series) -> pd.Series:
    if series.dtype == bool:
        return series
    return series.astype(str).str.strip().str.lower().isin({"true", "1", "1.0", "yes"})


# --------------------------------------------------------------------------------------------- tables
def utilization_table(runs: Iterable[Case]) -> pd.DataFrame:
    """The utilization table (see the module docstring) of ``runs``."""
    rows = []
    extra_cols: list[str] = []
    for case, folder, extra in runs:
        for k in extra:
            if k not in extra_cols:
                extra_cols.append(k)
        metrics = _metrics(folder)
        row: dict[str, Any] = {"case": case, **extra, "status": str(folder.meta.get("status", ""))}
        for metric, col in UTILIZATION_COLUMNS:
            row[col] = metrics.get(metric, math.nan)
        rows.append(row)
    columns = ["case", *extra_cols, "status", *(c for _, c in UTILIZATION_COLUMNS)]
    return pd.DataFrame(rows, columns=columns)


def _stats(values: np.ndarray) -> tuple[float, float, float, float, float]:
    v = values[np.isfinite(values)]
    if v.size == 0:
        return math.nan, math.nan, math.nan, math.nan, math.nan
    return float(v.mean()), float(v.std(ddof=0)), float(v.min()), float(np.percentile(v, 95)), float(v.max())


def task_table(runs: Iterable[Case]) -> pd.DataFrame:
    """Per-task CPU utilization and response-time statistics (from ``jobs.csv``)."""
    rows = []
    for case, folder, _ in runs:
        jobs = folder.jobs()
        if jobs is None or jobs.empty:
            continue
        duration = folder.duration_s
        for (node, task), g in jobs.groupby(["node", "task"], sort=True):
            response = pd.to_numeric(g["response_s"], errors="coerce")
            if "killed" in g:  # folders of older versions gave killed jobs a response time: a killed job has none
                response = response.where(~_as_bool(g["killed"]))
            cpu = float(pd.to_numeric(g["cpu_time_s"], errors="coerce").fillna(0.0).sum())
            mean, std, lo, p95, hi = _stats(response.to_numpy(float))
            counts = job_outcome_counts(g)  # the run's one deadline rule (netsim.kernel.records.deadline_verdict)
            rows.append({
                "case": case, "node": node, "task": task, "jobs_count": int(len(g)), "cpu_time_s": cpu,
                "cpu_util_ratio": cpu / duration if duration > 0 else math.nan,
                "response_mean_s": mean, "response_std_s": std, "response_min_s": lo, "response_p95_s": p95,
                "response_max_s": hi, "deadline_misses_count": counts["missed"] + counts["killed"],
                "preemptions_count": int(pd.to_numeric(g["preemptions"], errors="coerce").fillna(0).sum())
                if "preemptions" in g else 0,
                "killed_count": counts["killed"], "pending_count": counts["pending"],
            })
    return pd.DataFrame(rows, columns=TASK_COLUMNS)


def network_table(runs: Iterable[Case]) -> pd.DataFrame:
    """Per-network delay and loss statistics (from ``messages.csv``)."""
    rows = []
    for case, folder, _ in runs:
        msgs = folder.messages()
        if msgs is None or msgs.empty:
            continue
        metrics = _metrics(folder)
        for net, g in msgs.groupby("network", sort=True):
            dropped = _as_bool(g["dropped"])
            delivered = ~dropped & pd.to_numeric(g["delivered_s"], errors="coerce").notna()
            delay = pd.to_numeric(g["delay_s"], errors="coerce")[delivered].to_numpy(float)
            wait = (pd.to_numeric(g["tx_start_s"], errors="coerce") - pd.to_numeric(g["sent_s"], errors="coerce"))
            mean, std, lo, p95, hi = _stats(delay)
            n = int(len(g))
            rows.append({
                "case": case, "network": net, "messages_count": n, "delivered_count": int(delivered.sum()),
                "dropped_count": int(dropped.sum()), "loss_ratio": float(dropped.sum()) / n if n else math.nan,
                "bits_total": float(pd.to_numeric(g["bits"], errors="coerce").sum()),
                "delay_mean_s": mean, "delay_std_s": std, "delay_min_s": lo, "delay_p95_s": p95,
                "delay_max_s": hi, "wait_mean_s": float(wait.mean()) if wait.notna().any() else math.nan,
                "utilization_ratio": metrics.get(f"net.{net}.utilization", math.nan),
            })
    return pd.DataFrame(rows, columns=NETWORK_COLUMNS)


def node_table(runs: Iterable[Case]) -> pd.DataFrame:
    """Per-node CPU utilization (tasks, handlers and context switches) from the run's ``cpu.<node>.utilization``."""
    rows = []
    for case, folder, _ in runs:
        for name, value in _metrics(folder).items():
            parts = name.split(".")
            if len(parts) == 3 and parts[0] == "cpu" and parts[2] == "utilization":
                rows.append({"case": case, "node": parts[1], "cpu_util_ratio": value})
    frame = pd.DataFrame(rows, columns=NODE_COLUMNS)
    return frame.sort_values(["case", "node"], kind="stable").reset_index(drop=True) if rows else frame


# --------------------------------------------------------------------------------------------- figures
def _bar_figure(frame: pd.DataFrame, label_cols: list[str], value_cols: dict[str, str], title: str, path: Path,
                xlabel: str = "") -> Path | None:
    """Save :func:`netsim.plotting.bar_figure` of the first ``_MAX_PLOTTED`` rows (log axis when the values
    span decades), the value columns shown by their names in ``value_cols`` (column -> legend text); None
    when nothing has a value."""
    from netsim.figure_style import save_figure
    from netsim.plotting import bar_figure

    data = frame.dropna(subset=list(value_cols), how="all").head(_MAX_PLOTTED).rename(columns=value_cols)
    fig = bar_figure(data, label_cols, list(value_cols.values()), title=title, xlabel=xlabel)
    if fig is None:
        return None
    return save_figure(fig, path)


#: The metrics of ``utilization.png`` (summary column -> legend text of the bar figure).
_UTIL_FIGURE = {"Uc_ratio": "$U_c$", "Ua_ratio": "$U_a$", "NE_ratio": "NE", "GPI": "GPI"}


def _spans_decades(values: pd.Series) -> bool:
    """True for positive values spanning at least two decades (listed values drawn on a log axis)."""
    v = pd.to_numeric(values, errors="coerce").dropna().to_numpy(float)
    return bool(v.size and (v > 0).all() and v.max() / v.min() >= 100.0)


def _as_sweep(folder: Path | SweepFolder) -> SweepFolder | None:
    """``folder`` as a sweep folder, None when its ``sweep.json`` is missing or unreadable."""
    if isinstance(folder, SweepFolder):
        return folder
    info = SweepFolder.read_info(folder)
    return None if info is None else SweepFolder(Path(folder), info)


def _sweep_heatmaps(folder: Path | SweepFolder, out: Path) -> Path | None:
    """``utilization.png`` of a sweep: a heat map per index (Uc, Ua, NE, GPI) over two numeric factors (the
    surface's, else the first two with several values), mean over replicates; None when the sweep has fewer
    than two such factors or none of the indices."""
    from netsim.figure_style import save_figure
    from netsim.sweep.spec import SweepSpec
    from netsim.sweep.surface import metric_heatmaps

    sweep = _as_sweep(folder)
    if sweep is None or sweep.spec_data is None:  # no readable sweep record: the bar figure is drawn instead
        return None
    try:
        spec = SweepSpec.model_validate(sweep.spec_data)
        summary = sweep.summary()
    except (OSError, ValueError):  # a spec of another version, no summary: the bar figure is drawn instead
        return None
    if spec.surface is not None:
        axes = [spec.surface.x, spec.surface.y]
    else:
        axes = [n for n in spec.factors
                if pd.to_numeric(summary[n], errors="coerce").notna().all() and summary[n].nunique() > 1][:2]
    if len(axes) < 2:
        return None
    given = [spec.surface.logx, spec.surface.logy] if spec.surface is not None else [None, None]
    logs = [(spec.factors[n].is_log or _spans_decades(summary[n])) if g is None else bool(g)
            for g, n in zip(given, axes)]
    fig = metric_heatmaps(summary, x=axes[0], y=axes[1], metrics=["et.Uc", "et.Ua", "et.NE", "et.GPI"],
                          logx=logs[0], logy=logs[1])
    return None if fig is None else save_figure(fig, out / "utilization.png")


def _sweep_surface(sweep: SweepFolder, out: Path, plots: bool) -> pd.DataFrame | None:
    """Re-make the surface of a sweep folder with a ``surface:`` section; the optimum as a one-row table."""
    from netsim.sweep.surface import surface_from_summary
    from netsim.sweep.spec import SweepSpec

    data = sweep.spec_data
    if data is None or not data.get("surface"):
        return None
    spec = SweepSpec.model_validate(data)
    surf = spec.surface
    assert surf is not None
    logx = surf.logx if surf.logx is not None else spec.factors[surf.x].is_log
    logy = surf.logy if surf.logy is not None else spec.factors[surf.y].is_log
    opt, _ = surface_from_summary(sweep.summary_path, x=surf.x, y=surf.y, z=surf.z, logx=logx, logy=logy,
                                  out=out, plot=plots)
    row = {k: v for k, v in opt.items() if k != "metrics"}
    row.update({f"metric:{k}": v for k, v in opt["metrics"].items()})
    return pd.DataFrame([row])


def _by_values(frame: pd.DataFrame, folder: Path | SweepFolder) -> pd.DataFrame:
    """A copy of a sweep table whose ``case`` column reads ``sigma_s = 1e-05, sigma_c = 0.0132`` (symbols),
    plus ``#r`` for replicates after the first."""
    from netsim.figure_style import symbol

    sweep = _as_sweep(folder)
    if sweep is None:  # no readable sweep record: rows keep their folder names
        return frame
    names = [f for f in sweep.factors if f in frame.columns]
    if "case" not in frame.columns or not names or frame.empty:
        return frame
    out = frame.copy()

    def label(row: pd.Series) -> str:
        text = ", ".join(f"{symbol(n)} = {row[n]:.3g}" if isinstance(row[n], float) else f"{symbol(n)} = {row[n]}"
                         for n in names)
        rep = row.get("replicate", 0)
        return text + (f" #{int(rep)}" if pd.notna(rep) and int(rep) else "")

    out["case"] = out.apply(label, axis=1)
    return out


def _figures(tables: dict[str, pd.DataFrame], out: Path, folder: Path | SweepFolder, kind: str) -> list[Path]:
    from netsim.figure_style import paper_style

    made: list[Path | None] = []
    if kind == "sweep":  # rows named by their factor values, not by the point folder's hash
        tables = {k: _by_values(v, folder) for k, v in tables.items()}
    util = tables["utilization"]
    with paper_style():
        heat = _sweep_heatmaps(folder, out) if kind == "sweep" else None
        made.append(heat)
        if kind != "sweep" or len(util) <= _MAX_PLOTTED:
            if heat is None:
                made.append(_bar_figure(util, ["case"], _UTIL_FIGURE, "Utilization and performance indices",
                                        out / "utilization.png", "value (ratio)"))
            made.append(_bar_figure(tables["tasks"], ["case", "node", "task"],
                                    {"response_mean_s": "mean", "response_max_s": "max"}, "Task response times",
                                    out / "response_times.png", "response time (s)"))
            made.append(_bar_figure(tables["networks"], ["case", "network"],
                                    {"delay_mean_s": "mean", "delay_max_s": "max"}, "Network delays",
                                    out / "network_delays.png", "delay (s)"))
    return [p for p in made if p is not None]


# --------------------------------------------------------------------------------------------- entry point
def report(path_or_name: str | Path, *, out: str | Path | None = None, plots: bool = True) -> dict[str, pd.DataFrame]:
    """Tables (and figures) of a run, batch or sweep folder, or a registered case-study report.

    Exported as ``netsim.make_report`` (the name ``netsim.report`` is this module).

    Parameters
    ----------
    path_or_name : str or pathlib.Path
        A folder written by ``netsim run``/``batch``/``sweep``, or the name of a registered ``report``.
    out : str or pathlib.Path, optional
        Where to write the CSV tables and figures (default ``<folder>/report/``; for a registered report,
        passed to it as is).
    plots : bool, default True
        Also write the figures.

    Returns
    -------
    dict[str, pandas.DataFrame]
        ``utilization``, ``nodes``, ``tasks``, ``networks`` (and ``summary``, ``optimum`` for sweeps).

    Raises
    ------
    ConfigError
        When the argument is neither such a folder nor a registered report name.

    Examples
    --------
    >>> import netsim
    >>> netsim.run("scenarios/dc_servo_can.yaml", out="out/run")                 # doctest: +SKIP
    >>> tables = netsim.make_report("out/run", plots=False)                      # doctest: +SKIP
    >>> tables["tasks"][["task", "response_max_s", "deadline_misses_count"]]     # doctest: +SKIP
    """
    folder = Path(path_or_name)
    if not folder.is_dir():
        from netsim.registry import lookup

        name = str(path_or_name)
        try:
            fn = lookup("report", name)
        except ConfigError as exc:
            raise ConfigError(f"'{name}' is neither a folder nor a registered report: {exc}") from None
        return fn(Path(out) if out is not None else None, plots)
    kind, runs, sweep = _find(folder)
    tables: dict[str, pd.DataFrame] = {
        "utilization": utilization_table(runs),
        "nodes": node_table(runs),
        "tasks": task_table(runs),
        "networks": network_table(runs),
    }
    if sweep is not None:
        tables["summary"] = sweep.summary()
    target = Path(out) if out is not None else folder / "report"
    target.mkdir(parents=True, exist_ok=True)
    if sweep is not None:
        optimum = _sweep_surface(sweep, target, plots)
        if optimum is not None:
            tables["optimum"] = optimum
    if plots:
        _figures(tables, target, sweep if sweep is not None else folder, kind)
    from netsim.results import write_csv

    for name, frame in tables.items():
        if name != "summary":
            write_csv(frame, target / f"{name}.csv")
    log.info("report of %s (%s, %d runs) written to %s", folder, kind, len(runs), target)
    return tables


# ``netsim.report`` was once the function report (issue 27): calling the module still runs it, with a warning
_callable_module(__name__, "netsim.report:report", "netsim.make_report")
