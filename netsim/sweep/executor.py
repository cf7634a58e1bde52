"""Where sweep points run: in this process, a local process pool, or a Dask cluster -- one code path.

Every backend is a :class:`concurrent.futures.Executor`: a :class:`SerialExecutor` (runs each call at
``submit``), a :class:`~concurrent.futures.ProcessPoolExecutor` (the default, all cores), or the executor a
``dask.distributed.Client`` hands out (``client.get_executor()``). The sweep submits *chunks* of points
(:func:`run_chunk`), so tiny runs do not pay the per-task overhead of a cluster one by one.

A worker runs each point with the *point function* (``netsim.runner.run_point`` unless a caller injects
another picklable module-level function with the same signature ``fn(raw, out, seed) -> metrics``) and
writes the point's record ``point.json`` into the point's folder as soon as the point is done, so an
interrupted sweep keeps every finished point.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import signal
import time
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping

from netsim.errors import NetsimError

__all__ = [
    "PointFn",
    "SerialExecutor",
    "SchedulerUnreachable",
    "open_executor",
    "run_chunk",
    "read_record",
    "RECORD_NAME",
    "default_point_fn",
    "point_hash",
]

log = logging.getLogger(__name__)

#: ``fn(raw_scenario, run_folder, seed) -> {metric: value}``
PointFn = Callable[[Mapping[str, Any], Path, int], Mapping[str, float]]

#: The per-point record written by the worker when a point finishes (ok or error).
RECORD_NAME = "point.json"

_SINGLE_THREAD_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


class SchedulerUnreachable(NetsimError):
    """The Dask scheduler named by the user did not answer in time."""


def default_point_fn(raw: Mapping[str, Any], out: Path, seed: int) -> dict[str, float]:
    """The production point function: :func:`netsim.runner.run_point` (imported in the worker)."""
    from netsim.runner import run_point

    return run_point(raw, out, seed)


class SerialExecutor(Executor):
    """Runs each submitted call at once, in this process (the 1-worker backend; simplest to debug)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:  # noqa: D102
        fut: Future = Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except Exception as exc:  # noqa: BLE001 - delivered through the future like any executor
            fut.set_exception(exc)
        return fut


def _init_worker() -> None:
    """Pool worker start: single-threaded BLAS, ignore Ctrl-C (the parent stops the sweep cleanly)."""
    os.environ.update(_SINGLE_THREAD_ENV)
    os.environ.setdefault("MPLBACKEND", "Agg")
    with contextlib.suppress(ImportError):
        from threadpoolctl import threadpool_limits

        threadpool_limits(1)
    with contextlib.suppress(ValueError):  # not the main thread
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def _probe_scheduler(address: str, timeout: float) -> None:
    """Ask the scheduler at ``address`` for its identity; raise :class:`SchedulerUnreachable` after ``timeout``.

    ``Client(address, timeout=...)`` alone can wait forever on a socket that accepts but never answers, so
    the whole handshake runs under one deadline here.
    """

    async def ask() -> Any:
        from distributed.core import rpc

        remote = rpc(address, timeout=timeout)
        try:
            return await remote.identity()
        finally:
            await remote.close_rpc()

    async def main() -> Any:
        return await asyncio.wait_for(ask(), timeout)

    try:
        ident = asyncio.run(main())
    except (TimeoutError, asyncio.TimeoutError):
        raise SchedulerUnreachable(
            f"no Dask scheduler answered at '{address}' within {timeout:g} s; start one "
            f"(`dask scheduler` + `dask worker {address}`) or drop --scheduler to use the local process pool"
        ) from None
    except Exception as exc:  # noqa: BLE001 - any failure here is "not a scheduler we can talk to"
        raise SchedulerUnreachable(
            f"cannot talk to a Dask scheduler at '{address}': {type(exc).__name__}: {exc}; "
            "check the address (tcp://host:8786) or drop --scheduler to use the local process pool"
        ) from None
    if not isinstance(ident, dict) or ident.get("type") != "Scheduler":
        raise SchedulerUnreachable(f"'{address}' answered but is not a Dask scheduler ({ident!r:.80})")


@contextlib.contextmanager
def open_executor(
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    local_dask: bool = False,
    scratch: Path | None = None,
    connect_timeout: float = 5.0,
    cluster_kwargs: Mapping[str, Any] | None = None,
) -> Iterator[tuple[Executor, int, str]]:
    """Open the executor the options name; yield ``(executor, n_workers, description)``.

    Parameters
    ----------
    workers
        Number of worker processes (pool, local Dask). ``None`` = all cores; ``1`` (with no Dask option)
        runs in this process.
    scheduler
        ``tcp://host:port`` of a running Dask scheduler.
    local_dask
        Start a Dask ``LocalCluster`` (scratch files in ``scratch``).
    connect_timeout
        Seconds to wait for the scheduler to answer.
    cluster_kwargs
        Extra ``LocalCluster`` arguments (e.g. ``{"processes": False}`` for an in-process cluster).

    Raises
    ------
    SchedulerUnreachable
        When ``scheduler`` does not answer within ``connect_timeout`` seconds.
    """
    os.environ.update(_SINGLE_THREAD_ENV)  # inherited by workers started from here
    if scheduler or local_dask:
        from distributed import Client, LocalCluster

        cluster = None
        if scheduler:
            _probe_scheduler(scheduler, connect_timeout)
            client = Client(scheduler, timeout=connect_timeout)
            desc = f"dask scheduler {scheduler}"
        else:
            kwargs: dict[str, Any] = {
                "n_workers": workers or os.cpu_count() or 1,
                "threads_per_worker": 1,
                "dashboard_address": None,
            }
            if scratch is not None:
                scratch.mkdir(parents=True, exist_ok=True)
                kwargs["local_directory"] = str(scratch)
            kwargs.update(cluster_kwargs or {})
            cluster = LocalCluster(**kwargs)
            client = Client(cluster, timeout=connect_timeout)
            desc = f"local dask cluster ({kwargs['n_workers']} workers)"
        try:
            n = sum(client.nthreads().values()) or 1
            yield client.get_executor(pure=False), n, desc
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
        return
    n = workers or os.cpu_count() or 1
    if n <= 1:
        yield SerialExecutor(), 1, "serial (this process)"
        return
    import multiprocessing

    ctx = multiprocessing.get_context("fork") if "fork" in multiprocessing.get_all_start_methods() else None
    pool = ProcessPoolExecutor(max_workers=n, mp_context=ctx, initializer=_init_worker)
    try:
        yield pool, n, f"process pool ({n} workers)"
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _write_json(path: Path, data: Any) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=1, sort_keys=True, allow_nan=True), encoding="utf-8")
    os.replace(tmp, path)


def read_record(folder: Path) -> dict[str, Any] | None:
    """The ``point.json`` of a point folder, or ``None`` when it is missing or unreadable."""
    try:
        data = json.loads((folder / RECORD_NAME).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def point_hash(raw: Mapping[str, Any], seed: int) -> str:
    """The scenario hash of a run: :func:`netsim.scenario.scenario_hash` of ``raw`` with its ``seed`` set.

    This equals the ``scenario_hash`` the runner writes into the run's ``meta.json``.
    """
    from netsim.scenario import scenario_hash

    return scenario_hash({**dict(raw), "seed": int(seed)})


def _run_hash(folder: Path, raw: Mapping[str, Any], seed: int) -> str:
    """The hash from the run folder's ``meta.json`` (written by the runner) or, failing that, computed."""
    try:
        meta = json.loads((folder / "meta.json").read_text(encoding="utf-8"))
        if int(meta.get("seed", -1)) == int(seed) and isinstance(meta.get("scenario_hash"), str) and meta["scenario_hash"]:
            return meta["scenario_hash"]
    except (OSError, ValueError, TypeError, AttributeError):
        pass
    return point_hash(raw, seed)


class _Collect(logging.Handler):
    """Keeps the (distinct) warning messages logged while a point runs."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        try:
            text = f"{record.name}: {record.getMessage()}"
        except Exception:  # noqa: BLE001 - a broken log call must not fail the point
            return
        if text not in self.messages and len(self.messages) < 50:
            self.messages.append(text)


@contextlib.contextmanager
def _captured_warnings() -> Iterator[_Collect]:
    """Route netsim's warnings of a point into its record instead of the terminal (the progress bar).

    Scenario warnings were shown once for the base scenario; run-time warnings (e.g. a horizon too short
    for a wide threshold) end up in the point's ``point.json`` under ``warnings``.
    """
    logger = logging.getLogger("netsim")
    handler = _Collect()
    old = logger.propagate
    logger.addHandler(handler)
    logger.propagate = False
    try:
        yield handler
    finally:
        logger.removeHandler(handler)
        logger.propagate = old


def run_chunk(point_fn: PointFn, tasks: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Run the points of one chunk in order; return (and write) one record per point.

    Each task is ``{"index", "values", "replicate", "seed", "raw", "folder"}``. A point that raises an
    ``Exception`` is recorded with ``status: "error"`` and its message; ``KeyboardInterrupt`` propagates.
    """
    os.environ.update(_SINGLE_THREAD_ENV)
    out = []
    with _captured_warnings() as caught:
        for task in tasks:
            caught.messages.clear()
            folder = Path(task["folder"])
            folder.mkdir(parents=True, exist_ok=True)
            (folder / RECORD_NAME).unlink(missing_ok=True)
            record: dict[str, Any] = {
                "index": task["index"],
                "values": task["values"],
                "replicate": task["replicate"],
                "seed": task["seed"],
                "scenario_hash": "",
                "status": "ok",
                "error": "",
                "metrics": {},
            }
            (folder / "meta.json").unlink(missing_ok=True)
            t0 = time.perf_counter()
            try:
                metrics = point_fn(task["raw"], folder, task["seed"])
                record["metrics"] = {str(k): float(v) for k, v in dict(metrics).items()}
                record["scenario_hash"] = _run_hash(folder, task["raw"], task["seed"])
            except Exception as exc:  # noqa: BLE001 - a failing point is a result of the sweep
                record["status"] = "error"
                record["error"] = f"{type(exc).__name__}: {exc}".strip()
                record["metrics"] = {}
            record["elapsed_s"] = time.perf_counter() - t0  # in point.json only, never in summary.csv
            record["warnings"] = list(caught.messages)
            _write_json(folder / RECORD_NAME, record)
            out.append(record)
    return out
