"""``run_sweep``: expand a sweep file, run its points on an executor, resume, summarise.

Output folder layout::

    <out>/sweep.json                 which sweep this folder holds (name, file, factors, number of runs)
    <out>/points/<index>-<key>/      one run folder per run (scenario.yaml, *.csv, meta.json) + point.json, and
                                     manifest.json (sha256 of its files) written last
    <out>/.sweep.lock                held (flock, with the pid) by the sweep writing the folder
    <out>/summary.csv                one row per run (see netsim.sweep.summary)
    <out>/optimum.json, surface.png  when the sweep file has a ``surface:`` section (netsim.sweep.surface)
    <out>/dask-scratch/              Dask's scratch space when a local Dask cluster ran the sweep, and
                                     workers.log: the output of its worker processes

A run is *finished* when its folder matches its manifest (:func:`netsim.sweep.points.verified_record`: nothing
added, changed or symlinked since it was written) and its ``point.json`` says ``ok`` with the same seed and the
same scenario hash (:func:`netsim.scenario.scenario_hash` of the point's scenario with its seed, as in the run's
``meta.json``) as now; running the sweep again skips those
and runs the rest (failed runs are retried). Ctrl-C stops the sweep, whatever the executor and whenever it
comes (while a local Dask cluster starts, runs or closes): runs in progress are abandoned, finished ones
are kept, ``summary.csv`` is written with ``status = pending`` for the rest, and the returned result has
``interrupted = True``. A Dask worker that dies costs only time (the scheduler reruns its runs elsewhere);
a Dask scheduler that goes away stops the sweep the same way, then :class:`SchedulerLost` is raised.

Why this module is long: resume (which points are finished), chunking, the drive loop over in-flight
futures, progress, Ctrl-C and a lost Dask scheduler all act on the same in-flight state of one sweep;
the worker side is :mod:`netsim.sweep.points`, the backends :mod:`netsim.sweep.executor`.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import shutil
import time
from concurrent.futures import FIRST_COMPLETED, CancelledError, Executor, Future, wait
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterator, Mapping

from netsim.errors import ConfigError
from netsim.results.folder import SUMMARY_NAME, SWEEP_MARKER, SweepFolder, read_summary
from netsim.sweep.executor import SchedulerLost, open_executor, scheduler_lost
from netsim.sweep.points import (PointFn, default_point_fn, metrics_point_fn, point_hash, run_chunk,
                                 verified_record, write_manifest)
from netsim.sweep.spec import Point, Sweep, load_sweep
from netsim.sweep.summary import write_summary

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["SweepResult", "run_sweep", "ChunkPlanner", "SWEEP_MARKER"]

log = logging.getLogger(__name__)

#: The lock a running sweep holds on its output folder (its pid inside): one sweep per folder at a time.
LOCK_NAME = ".sweep.lock"
_OWNED = ("points", SUMMARY_NAME, "optimum.json", "surface.png", "surface.csv", SWEEP_MARKER, "dask-scratch")


@dataclass
class SweepResult:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    name
        The sweep name.
    out_dir
        The sweep's output folder.
    summary
        ``summary.csv`` as a DataFrame (:func:`netsim.results.folder.read_summary`).
    n_runs, n_ok, n_failed, n_pending
        Runs in the sweep; finished ok; failed (error recorded); not run (interrupted).
    n_executed, n_resumed
        Runs executed by this call; runs found finished and skipped.
    interrupted
        True when Ctrl-C stopped the sweep.
    optimum
        The arg-min of the surface (``optimum.json``) when the sweep has a ``surface:`` section.
    executor
        Which backend ran the points.
    wall_time_s
        Wall time of this call.
    """

    name: str
    out_dir: Path
    summary: pd.DataFrame
    n_runs: int
    n_ok: int
    n_failed: int
    n_pending: int
    n_executed: int
    n_resumed: int
    interrupted: bool
    executor: str
    wall_time_s: float
    optimum: dict[str, Any] | None = None
    files: dict[str, Path] = field(default_factory=dict)

    @property
    def summary_path(self) -> Path:
        """``<out_dir>/summary.csv``."""
        return self.out_dir / SUMMARY_NAME

    @property
    def folder(self) -> SweepFolder:
        """The sweep folder, to read its runs' folders (:meth:`netsim.results.folder.SweepFolder.runs`)."""
        return SweepFolder.open(self.out_dir)

    def describe(self) -> str:
        """One paragraph for the terminal: counts, where the summary is, and the optimum."""
        from netsim.status import count_statuses

        counts = count_statuses(self.summary["status"]) if self.summary is not None else None
        told = counts.describe("run") if counts is not None and counts.total == self.n_runs else (
            f"{self.n_ok} of {self.n_runs} runs ok, {self.n_failed} failed, {self.n_pending} not run")
        text = (
            f"sweep {self.name}: {told} ({self.n_resumed} resumed, {self.n_executed} executed on "
            f"{self.executor}, {self.wall_time_s:.1f} s)\nsummary: {self.summary_path}"
        )
        if self.optimum:
            from netsim.sweep.surface import describe_optimum

            text += "\n" + describe_optimum(self.optimum)
        return text


class ChunkPlanner:
    """Chunk sizes chosen as the sweep goes: one run per task until run times are known, then enough runs
    per task to make a task last about ``target_s`` (at most ``max_chunk``, and at most a quarter of the
    remaining runs per worker, so the tail stays balanced).

    Slow runs (simulations of a second or more) thus go one per task -- Ctrl-C waits for at most one run per
    worker -- while tiny runs are batched so the executor's per-task overhead does not dominate.
    """

    def __init__(self, n_workers: int, fixed: int | None = None, target_s: float = 0.25, max_chunk: int = 32) -> None:
        self.n_workers = max(1, n_workers)
        self.fixed = fixed
        self.target_s = target_s
        self.max_chunk = max_chunk
        self.total_s = 0.0
        self.timed = 0

    def observe(self, seconds: float, runs: int) -> None:
        """Record that ``runs`` runs took ``seconds`` (worker-side time)."""
        self.total_s += max(0.0, seconds)
        self.timed += runs

    def next_size(self, remaining: int) -> int:
        """Size of the next chunk with ``remaining`` runs left."""
        if self.fixed:
            return max(1, min(self.fixed, remaining))
        if self.timed == 0:
            return 1
        per_run = self.total_s / self.timed
        want = int(self.target_s / per_run) if per_run > 0 else self.max_chunk
        return max(1, min(want, self.max_chunk, remaining // (4 * self.n_workers)))


def _prepare_out(out: Path, sweep: Sweep, overwrite: bool) -> None:
    marker = out / SWEEP_MARKER
    if out.exists() and not out.is_dir():
        raise ConfigError(f"output '{out}' is a file; give a folder with --out")
    if out.is_dir() and any(p.name != LOCK_NAME for p in out.iterdir()):
        held = None
        if marker.exists():
            info = SweepFolder.read_info(out)
            held = "?" if info is None else info.get("sweep")
        if held != sweep.name and not overwrite:
            what = f"sweep '{held}'" if held else "files that are not a sweep"
            raise ConfigError(
                f"output folder '{out}' holds {what}, not sweep '{sweep.name}'; choose another --out, "
                "or pass --overwrite (overwrite=True) to replace it"
            )
        if overwrite:
            for name in _OWNED:
                target = out / name
                if target.is_dir():
                    shutil.rmtree(target)
                elif target.exists():
                    target.unlink()
    out.mkdir(parents=True, exist_ok=True)
    (out / "points").mkdir(exist_ok=True)
    info = {
        "sweep": sweep.name,
        "file": str(sweep.path) if sweep.path else None,
        "base": str(sweep.base_path) if sweep.base_path else None,
        "factors": {k: v.paths for k, v in sweep.spec.factors.items()},
        "runs": len(sweep.points),
        "spec": sweep.spec.model_dump(mode="json"),
    }
    from netsim.safe_write import write_atomic

    write_atomic(marker, json.dumps(info, indent=1, sort_keys=True))


@contextlib.contextmanager
def _folder_lock(out: Path) -> Iterator[None]:
    """Hold ``<out>/.sweep.lock`` (an ``flock``, released by the kernel however the process ends) while the
    sweep writes ``out``; another sweep into the same folder is refused, naming the process that holds it.
    The pool's worker processes inherit the lock, so a sweep killed outright keeps its folder until its last
    worker is gone."""
    try:
        import fcntl
    except ImportError:  # not POSIX: no lock
        yield
        return
    if out.exists() and not out.is_dir():
        raise ConfigError(f"output '{out}' is a file; give a folder with --out")
    out.mkdir(parents=True, exist_ok=True)
    path = out / LOCK_NAME
    fd = os.open(path, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            holder = os.pread(fd, 64, 0).decode("ascii", "replace").strip() or "?"
            raise ConfigError(f"output folder '{out}' is being written by another sweep (process {holder}); wait "
                              "for it to end, or choose another --out") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode("ascii"), 0)
        yield
    finally:
        os.close(fd)


def _finished(point: Point, folder: Path, raw: Mapping[str, Any]) -> dict[str, Any] | None:
    """The point's record if it finished ok with the same seed and scenario hash as now."""
    from netsim.status import DIVERGED, OK, UNSTABLE, kind_of

    rec = verified_record(folder)  # a diverged or unstable run is a finished result (run again, it is the same)
    if not rec or kind_of(rec.get("status")) not in (OK, DIVERGED, UNSTABLE) or rec.get("seed") != point.seed \
            or rec.get("index") != point.index:
        return None
    try:
        now = point_hash(raw, point.seed)
    except ConfigError:
        return None
    return rec if rec.get("scenario_hash") == now else None


def _task(sweep: Sweep, point: Point, out: Path, raw: dict[str, Any]) -> dict[str, Any]:
    return {
        "index": point.index,
        "values": point.values,
        "replicate": point.replicate,
        "seed": point.seed,
        "raw": raw,
        "folder": str(out / point.folder),
    }


class _Progress:
    """A rich progress bar on stderr (or nothing)."""

    def __init__(self, enabled: bool, total: int, label: str) -> None:
        self.bar = None
        self.failed = 0
        if not enabled:
            return
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self.bar = Progress(
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("failed {task.fields[failed]}"),
            TimeElapsedColumn(),
            TextColumn("left"),
            TimeRemainingColumn(),
            console=Console(stderr=True),
            transient=False,
        )
        self.task = self.bar.add_task(label, total=total, failed=0)

    def __enter__(self) -> "_Progress":
        if self.bar is not None:
            self.bar.start()
        return self

    def advance(self, records: list[dict[str, Any]]) -> None:
        self.failed += sum(1 for r in records if r.get("status") != "ok")
        if self.bar is not None:
            self.bar.update(self.task, advance=len(records), failed=self.failed)

    def __exit__(self, *exc: Any) -> None:
        if self.bar is not None:
            self.bar.stop()


#: How often (seconds) the sweep loop wakes up to check that the Dask scheduler is still there.
_POLL_S = 0.5


def _execute(
    sweep: Sweep,
    todo: list[tuple[Point, dict[str, Any]]],
    out: Path,
    point_fn: PointFn,
    *,
    workers: int | None,
    scheduler: str | None,
    local_dask: bool,
    progress: bool,
    chunk_size: int | None,
    connect_timeout: float,
    cluster_kwargs: Mapping[str, Any] | None,
    dashboard: str | None = None,
) -> tuple[str, str]:
    """Run ``todo`` (point, raw) on the chosen executor; return ``(outcome, executor description)``.

    ``outcome`` is ``"done"``, ``"interrupted"`` (Ctrl-C, at any moment: while the executor starts, runs or
    closes) or ``"lost"`` (the Dask scheduler went away; the runs it held are left pending, not failed).
    """
    outcome, desc = "done", "not started"
    try:
        with open_executor(
            workers=workers,
            scheduler=scheduler,
            local_dask=local_dask,
            scratch=out / "dask-scratch",
            connect_timeout=connect_timeout,
            cluster_kwargs=cluster_kwargs,
            dashboard=dashboard,
        ) as (executor, n_workers, desc):
            try:
                outcome = _drive(sweep, todo, out, point_fn, executor, n_workers, desc, progress, chunk_size)
            except KeyboardInterrupt:
                outcome = "interrupted"
                raise
    except KeyboardInterrupt:
        outcome = "interrupted"
    if outcome == "interrupted":
        log.warning("sweep %s interrupted; finished runs are kept, run it again to resume", sweep.name)
    return outcome, desc


def _drive(
    sweep: Sweep,
    todo: list[tuple[Point, dict[str, Any]]],
    out: Path,
    point_fn: PointFn,
    executor: Executor,
    n_workers: int,
    desc: str,
    progress: bool,
    chunk_size: int | None,
) -> str:
    """Submit chunks, collect records; return ``"done"`` or ``"lost"`` (Ctrl-C propagates, after the
    runs still in flight are cancelled)."""
    planner = ChunkPlanner(n_workers, chunk_size)
    log.info("sweep %s: %d runs on %s", sweep.name, len(todo), desc)
    in_flight: dict[Future, list[dict[str, Any]]] = {}
    limit = 2 * n_workers
    pos = 0
    root = out.resolve()  # workers (other machines, other working directories) get absolute folders
    with _Progress(progress, len(todo), f"{sweep.name}") as bar:
        try:
            while True:
                if scheduler_lost(executor):
                    return "lost"
                while pos < len(todo) and len(in_flight) < limit:
                    size = planner.next_size(len(todo) - pos)
                    chunk = [_task(sweep, p, root, raw) for p, raw in todo[pos : pos + size]]
                    try:
                        fut = executor.submit(run_chunk, point_fn, chunk)
                    except SchedulerLost:
                        return "lost"
                    pos += size
                    in_flight[fut] = chunk
                if not in_flight:
                    return "done"
                done, _ = wait(list(in_flight), timeout=_POLL_S, return_when=FIRST_COMPLETED)
                for fut in done:
                    chunk = in_flight.pop(fut)
                    try:
                        records = fut.result()
                    except KeyboardInterrupt:
                        raise
                    except CancelledError:  # only Dask cancels on its own: its scheduler went away
                        if scheduler_lost(executor):
                            return "lost"
                        records = [_lost(task, RuntimeError("the executor cancelled the run")) for task in chunk]
                    except BaseException as exc:  # noqa: BLE001 - a lost chunk fails its points, not the sweep
                        records = [_lost(task, exc) for task in chunk]
                    planner.observe(sum(float(r.get("elapsed_s", 0.0)) for r in records), len(records))
                    bar.advance(records)
        finally:
            for fut in in_flight:
                fut.cancel()


def _lost(task: dict[str, Any], exc: BaseException) -> dict[str, Any]:
    """Record of a point whose chunk never came back (worker crashed, could not be pickled ...)."""
    from netsim.sweep.points import RECORD_NAME, _write_json

    rec = {
        "index": task["index"],
        "values": task["values"],
        "replicate": task["replicate"],
        "seed": task["seed"],
        "scenario_hash": "",
        "status": "error",
        "error": f"{type(exc).__name__}: {exc}".strip(),
        "metrics": {},
    }
    folder = Path(task["folder"])
    if verified_record(folder) is None:
        from netsim.sweep.points import fresh_folder

        fresh_folder(folder)
        _write_json(folder / RECORD_NAME, rec)
        write_manifest(folder)
    return rec


def _refuse_invalid(path: str | Path) -> None:
    """Check the sweep file, its base scenario and every factor level once (:func:`check_sweep`) before
    anything runs; log the warnings, raise one :class:`ConfigError` listing every error (``.problems``)."""
    from netsim.sweep.check import check_sweep

    problems = check_sweep(path)
    for problem in problems:
        if not problem.is_error:
            log.warning("%s", problem.describe(tag=False))
    errors = [p for p in problems if p.is_error]
    if errors:
        n = len(errors)
        lines = "\n".join(f"  {p}" for p in errors)
        exc = ConfigError(f"sweep {path}: {n} problem{'s' if n != 1 else ''}; nothing was run:\n{lines}")
        exc.problems = errors  # type: ignore[attr-defined]  # the CLI prints these one per line
        raise exc


def run_sweep(
    path: str | Path,
    *,
    out: str | Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    local_dask: bool = False,
    overwrite: bool = False,
    progress: bool = True,
    point_fn: PointFn | None = None,
    chunk_size: int | None = None,
    connect_timeout: float = 5.0,
    cluster_kwargs: Mapping[str, Any] | None = None,
    dashboard: str | None = None,
) -> SweepResult:
    """Run a sweep file; write the point folders, ``summary.csv`` and the surface; resume when re-run.

    Parameters
    ----------
    path : str or pathlib.Path
        The sweep YAML file.
    out : str or pathlib.Path, optional
        Output folder (default ``reports/<sweep name>/``).
    workers : int, optional
        Worker processes (default: all cores; ``1`` runs in this process).
    scheduler : str, optional
        Address ``tcp://host:port`` of a Dask scheduler to run on.
    local_dask : bool, default False
        Run on a local Dask cluster started for this sweep (scratch in ``<out>/dask-scratch``).
    overwrite : bool, default False
        Replace an output folder that holds another sweep, and re-run every point.
    progress : bool, default True
        Show a progress bar on stderr.
    point_fn : callable, optional
        The function run for each point, ``fn(raw, out, seed) -> metrics`` (default
        :func:`netsim.runner.run_point`); must be a picklable module-level function for process backends.
    chunk_size : int, optional
        Runs per executor task (default: adaptive, see :class:`ChunkPlanner`).
    connect_timeout : float, default 5.0
        Seconds to wait for the Dask scheduler.
    cluster_kwargs : Mapping[str, Any], optional
        Extra ``LocalCluster`` arguments for ``local_dask`` (e.g. ``{"processes": False}``).
    dashboard : str, optional
        Address for the local Dask cluster's dashboard (e.g. ``"127.0.0.1:8787"``); default: none, and
        the cluster listens on no HTTP port.

    Returns
    -------
    SweepResult
        Counts of runs (ok, failed, pending, resumed), the output folder, ``summary`` as a DataFrame and the
        surface's ``optimum``.

    Raises
    ------
    ConfigError
        Before any run, listing every problem (``.problems``) of a bad sweep file (unknown factor path with a
        "did you mean", empty factors ...), an invalid base scenario, or a factor level that gives an invalid
        scenario (each level is checked once); also for an output folder that holds another sweep, or a
        scheduler that does not answer.
    SchedulerLost
        When the Dask scheduler goes away mid-sweep: the finished runs are kept and ``summary.csv`` is
        written (the rest ``pending``) before it is raised; ``.result`` holds the :class:`SweepResult`.
        Running the sweep again resumes.

    Examples
    --------
    >>> import netsim
    >>> result = netsim.run_sweep("scenarios/hdd_gpi_sweep.yaml", workers=2)   # doctest: +SKIP
    >>> print(result.describe())                                               # doctest: +SKIP
    >>> result.summary.sort_values("GPI").head()                               # doctest: +SKIP
    """
    t0 = time.perf_counter()
    if scheduler and local_dask:
        raise ConfigError("give either a scheduler address or local_dask=True, not both")
    _refuse_invalid(path)
    sweep = load_sweep(path)
    folder = Path(out) if out is not None else Path("reports") / sweep.name
    raws = [sweep.point_raw(p) for p in sweep.points]
    with _folder_lock(folder):
        return _run_locked(sweep, folder, raws, overwrite, t0, point_fn=point_fn, workers=workers,
                           scheduler=scheduler, local_dask=local_dask, progress=progress, chunk_size=chunk_size,
                           connect_timeout=connect_timeout, cluster_kwargs=cluster_kwargs, dashboard=dashboard)


def _run_locked(sweep: Sweep, folder: Path, raws: list[dict[str, Any]], overwrite: bool, t0: float, *,
                point_fn: PointFn | None, workers: int | None, scheduler: str | None, local_dask: bool,
                progress: bool, chunk_size: int | None, connect_timeout: float,
                cluster_kwargs: Mapping[str, Any] | None, dashboard: str | None) -> SweepResult:
    """:func:`run_sweep` once its output folder is locked."""
    _prepare_out(folder, sweep, overwrite)

    todo: list[tuple[Point, dict[str, Any]]] = []
    resumed = 0
    outcome, desc = "done", "nothing to run"
    try:  # from here on, Ctrl-C (even while finished runs are being looked up) still writes summary.csv
        for point, raw in zip(sweep.points, raws):
            if _finished(point, folder / point.folder, raw) is not None:
                resumed += 1
            else:
                todo.append((point, raw))
    except KeyboardInterrupt:
        outcome, todo = "interrupted", []
        log.warning("sweep %s interrupted; finished runs are kept, run it again to resume", sweep.name)
    if resumed:
        log.info("sweep %s: %d of %d runs already finished, %d to run", sweep.name, resumed, len(raws), len(todo))

    if todo:
        outcome, desc = _execute(
            sweep,
            todo,
            folder,
            point_fn or (metrics_point_fn if sweep.spec.runs == "metrics" else default_point_fn),
            workers=workers,
            scheduler=scheduler,
            local_dask=local_dask,
            progress=progress,
            chunk_size=chunk_size,
            connect_timeout=connect_timeout,
            cluster_kwargs=cluster_kwargs,
            dashboard=dashboard,
        )
    result = _collect(sweep, folder, len(todo), resumed, outcome != "done", desc, time.perf_counter() - t0)
    if outcome == "lost":
        raise SchedulerLost(
            f"the Dask scheduler {scheduler or '(local)'} went away mid-sweep; {result.n_ok} of {result.n_runs} "
            f"runs finished and are kept in {folder} (summary.csv written, {result.n_pending} pending); start "
            "the scheduler and workers again and rerun the same command to resume",
            result=result,
            out_dir=folder,
        )
    return result


def _collect(
    sweep: Sweep, folder: Path, executed: int, resumed: int, interrupted: bool, desc: str, elapsed: float
) -> SweepResult:
    """Read every point's record, write ``summary.csv`` (and the surface), build the result."""
    rows = []
    for point in sweep.points:
        rec = verified_record(folder / point.folder)  # a changed folder is not trusted: pending, run it again
        if not rec or rec.get("index") != point.index or rec.get("seed") != point.seed:
            rec = {"index": point.index, "values": point.values, "replicate": point.replicate,
                   "seed": point.seed, "status": "pending", "error": "", "metrics": {}}
        rec = {**rec, "values": point.values, "folder": point.folder}
        rows.append(rec)
    factors = list(sweep.spec.factors)
    summary_path = write_summary(folder / SUMMARY_NAME, factors, rows)
    summary = read_summary(summary_path)  # the one parse of summary.csv (netsim.results.folder)
    warned = [r for r in rows if r.get("warnings")]
    if warned:
        first = warned[0]
        log.warning(
            "%d of %d runs logged warnings (see points/*/point.json, key 'warnings'); first, run %d: %s",
            len(warned), len(rows), first["index"], first["warnings"][0],
        )
    n_ok = sum(r["status"] == "ok" for r in rows)
    n_pending = sum(r["status"] == "pending" for r in rows)
    files = {"summary": summary_path}
    optimum = None
    if sweep.spec.surface is not None and not interrupted and n_ok:
        from netsim.sweep.surface import surface_from_summary

        surf = sweep.spec.surface
        logx = surf.logx if surf.logx is not None else sweep.spec.factors[surf.x].is_log
        logy = surf.logy if surf.logy is not None else sweep.spec.factors[surf.y].is_log
        optimum, written = surface_from_summary(
            summary_path, x=surf.x, y=surf.y, z=surf.z, logx=logx, logy=logy, out=folder
        )
        files.update(written)
    result = SweepResult(
        name=sweep.name,
        out_dir=folder,
        summary=summary,
        n_runs=len(rows),
        n_ok=n_ok,
        n_failed=len(rows) - n_ok - n_pending,
        n_pending=n_pending,
        n_executed=executed - n_pending,
        n_resumed=resumed,
        interrupted=interrupted,
        executor=desc,
        wall_time_s=elapsed,
        optimum=optimum,
        files=files,
    )
    log.info("%s", result.describe())
    return result
