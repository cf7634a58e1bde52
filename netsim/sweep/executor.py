"""Where sweep points run: in this process, a local process pool, or a Dask cluster -- one code path.

Every backend is a :class:`concurrent.futures.Executor`: a :class:`SerialExecutor` (runs each call at
``submit``), a :class:`~concurrent.futures.ProcessPoolExecutor` (the default, all cores), or the executor a
``dask.distributed.Client`` hands out (``client.get_executor()``). The sweep submits *chunks* of points
(:func:`~netsim.sweep.points.run_chunk`), so tiny runs do not pay the per-task overhead of a cluster one by one.
What a worker does with a chunk (run each point, write its ``point.json``) is in :mod:`netsim.sweep.points`.

Plugin files: the user's permission (``--allow-plugins``, :mod:`netsim.trust`) is decided in the sweep's process
and travels with every Dask task (:func:`with_plugin_permission`), so a worker of a remote scheduler, started
by someone else with another environment, runs a scenario's plugin files exactly when a local run would.

Faults on a Dask cluster: a worker that dies mid-point has its tasks rescheduled on the others by the
scheduler (the points are pure: the same point gives the same record); a scheduler that goes away ends
the sweep (:class:`SchedulerLost`, raised by :func:`netsim.sweep.run_sweep` after ``summary.csv`` is
written). Worker processes of a local cluster ignore Ctrl-C (:func:`dask_setup`, as pool workers do) and
write their output to ``<out>/dask-scratch/workers.log``; a Ctrl-C while the cluster starts is held back
until it is up. The sweep's own process stops the sweep, so one Ctrl-C gives one message, not a traceback
per worker.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import signal
import sys
import threading
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping

from netsim.errors import NetsimError
from netsim.sweep.points import _SINGLE_THREAD_ENV

__all__ = [
    "SerialExecutor",
    "SchedulerUnreachable",
    "SchedulerLost",
    "DaskExecutor",
    "dask_setup",
    "open_executor",
    "scheduler_lost",
    "with_plugin_permission",
]

log = logging.getLogger(__name__)



class SchedulerUnreachable(NetsimError):
    """The Dask scheduler named by the user did not answer in time."""


class SchedulerLost(NetsimError):
    """The Dask scheduler went away mid-sweep; finished runs are kept, ``summary.csv`` is written.

    Attributes
    ----------
    result
        The :class:`~netsim.sweep.SweepResult` of what finished (``None`` until the summary is written).
    out_dir
        The sweep's output folder (also named in the message).
    """

    def __init__(self, message: str, result: Any = None, out_dir: Path | None = None) -> None:
        super().__init__(message)
        self.result = result
        self.out_dir = out_dir


class DaskExecutor(Executor):
    """The executor of a ``dask.distributed.Client`` that can tell when its scheduler is gone.

    ``client.get_executor()`` alone keeps accepting work after the scheduler died (the futures then never
    finish, and the sweep would wait forever); :meth:`scheduler_lost` lets the sweep stop instead.
    """

    def __init__(self, client: Any) -> None:
        from netsim.trust import plugins_allowed

        self.client = client
        self._inner = client.get_executor(pure=False)
        #: Whether the user allows plugin files (``--allow-plugins``, their environment or config), decided here:
        #: a worker process of a remote scheduler was started by someone else, with another environment.
        self.plugins_allowed = plugins_allowed()

    def scheduler_lost(self) -> bool:
        """True once the client lost its scheduler (reconnecting, or closed after failing to)."""
        return scheduler_lost_client(self.client)

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:  # noqa: D102
        if self.scheduler_lost():
            raise SchedulerLost("the Dask scheduler went away")
        return self._inner.submit(with_plugin_permission, self.plugins_allowed, fn, *args, **kwargs)


def with_plugin_permission(allowed: bool, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Any:
    """``fn(*args, **kwargs)`` in a worker, with plugin files allowed exactly when the submitting user allowed them
    (:func:`netsim.trust.task_permission`), whatever the worker's own environment or config say."""
    from netsim.trust import task_permission

    with task_permission(allowed):
        return fn(*args, **kwargs)


def scheduler_lost(executor: Executor) -> bool:
    """True when ``executor`` runs on a Dask scheduler that has gone away (never for the pool or serial)."""
    return isinstance(executor, DaskExecutor) and executor.scheduler_lost()


def dask_setup(worker: Any) -> None:  # noqa: ARG001 - the Dask preload hook's signature
    """Dask preload hook (``preload=["netsim.sweep.executor"]``): the worker process ignores Ctrl-C.

    A terminal's Ctrl-C reaches every process of the foreground group, local Dask workers included; the
    sweep's own process handles it (cancels, writes ``summary.csv``) and closes the cluster.
    """
    with contextlib.suppress(ValueError):  # not the main thread: leave it
        signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def _stderr_to(path: Path | None) -> Iterator[None]:
    """Point file descriptor 2 at ``path`` (``None``: the null device) while local worker processes start.

    The worker processes inherit it for good: their output goes to ``<out>/dask-scratch/workers.log``, not
    to the terminal. A Ctrl-C that reaches a worker still starting Python (before :func:`dask_setup` can
    ignore it) would otherwise print a traceback per worker on the user's screen.
    """
    target = os.open(str(path) if path is not None else os.devnull, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    saved = os.dup(2)
    with contextlib.suppress(Exception):
        sys.stderr.flush()
    os.dup2(target, 2)
    try:
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(target)


@contextlib.contextmanager
def _sigint_deferred() -> Iterator[None]:
    """Hold a Ctrl-C back until the block ends, then raise it (in the main thread; elsewhere do nothing).

    A local cluster interrupted while it starts is left half-built to Dask's exit handler, which prints
    tracebacks; held back, the Ctrl-C arrives as soon as the cluster is up (or has failed), and the sweep
    closes it and stops cleanly. Dask clusters created in the block that could not finish starting are
    closed here and removed from Dask's exit handler.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    before = _dask_clusters()
    old = signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    except BaseException:
        _forget_clusters(_dask_clusters() - before)
        if not caught:
            raise
    finally:
        signal.signal(signal.SIGINT, old)
    if caught:
        raise KeyboardInterrupt


def _dask_clusters() -> set[int]:
    from distributed.deploy.spec import SpecCluster

    return {id(c) for c in list(getattr(SpecCluster, "_instances", ()))}


def _forget_clusters(ids: set[int]) -> None:
    """Close the half-started clusters ``ids`` and take them off Dask's exit-time list."""
    from distributed.deploy.spec import SpecCluster

    instances = getattr(SpecCluster, "_instances", None)
    if instances is None:  # a Dask without the exit-time list: nothing to take off it
        return
    for cluster in [c for c in list(instances) if id(c) in ids]:
        with contextlib.suppress(Exception):
            cluster.close(timeout=5)
        instances.discard(cluster)


#: Loggers of Dask and its network layer, quietened during a Dask sweep (the sweep reports faults itself).
_DASK_LOGGERS = ("distributed", "tornado")


@contextlib.contextmanager
def _quiet_dask_logs() -> Iterator[None]:
    """Dask's own log lines (tracebacks of a closed connection, "reconnecting", "worker killed") are
    silenced unless netsim logs at INFO or below (``-v``): the sweep says in one line what happened.

    Dask's logging configuration gives several child loggers their own level and handler
    (``distributed.client``, ``tornado.application`` ...), so each existing logger is set, not just the parents.
    """
    import distributed  # noqa: F401 - configures its loggers on import; they must exist to be quietened

    if logging.getLogger("netsim").isEnabledFor(logging.INFO):
        yield
        return
    names = [name for name in list(logging.root.manager.loggerDict)
             if any(name == p or name.startswith(p + ".") for p in _DASK_LOGGERS)]
    loggers = [logging.getLogger(name) for name in {*names, *_DASK_LOGGERS}]
    old = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for lg, level in zip(loggers, old):
            lg.setLevel(level)


def _local_cluster(workers: int | None, scratch: Path | None, dashboard: str | None,
                   cluster_kwargs: Mapping[str, Any] | None) -> Any:
    """A ``LocalCluster`` whose worker processes ignore Ctrl-C and whose scheduler serves no HTTP unless
    ``dashboard`` names an address.

    ``dashboard_address=None`` alone does not do that: the scheduler still serves its HTTP pages (worker
    info, JSON, Prometheus) on port 8787. With ``dashboard=None`` the scheduler's HTTP server is started
    on an ephemeral loopback port with no routes and stopped at once (nothing listens), and the workers'
    HTTP servers (always started by Dask, on an ephemeral loopback port) serve no routes either.
    """
    import dask
    from distributed import LocalCluster

    kwargs: dict[str, Any] = {
        "n_workers": workers or os.cpu_count() or 1,
        "threads_per_worker": 1,
        "dashboard_address": dashboard if dashboard is not None else "127.0.0.1:0",
        # the worker processes' own Dask log lines (e.g. "task cancelled" when Ctrl-C closes them)
        "silence_logs": logging.DEBUG if logging.getLogger("netsim").isEnabledFor(logging.DEBUG) else logging.CRITICAL,
    }
    if scratch is not None:
        scratch.mkdir(parents=True, exist_ok=True)
        kwargs["local_directory"] = str(scratch)
    if (cluster_kwargs or {}).get("processes", True):
        kwargs["preload"] = [__name__]
    kwargs.update(cluster_kwargs or {})
    if dashboard is not None:
        return LocalCluster(**kwargs)
    with dask.config.set({"distributed.scheduler.http.routes": [], "distributed.worker.http.routes": []}):
        cluster = LocalCluster(**kwargs)

    async def stop_http(scheduler: Any) -> None:
        scheduler.http_server.stop()
        scheduler.services.pop("dashboard", None)

    try:
        cluster.sync(stop_http, cluster.scheduler)
    except BaseException:
        cluster.close()
        raise
    return cluster


class SerialExecutor(Executor):
    """Runs each submitted call at once, in this process (the 1-worker backend; simplest to debug)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:  # noqa: D102
        fut: Future = Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except Exception as exc:  # noqa: BLE001 - delivered through the future like any executor
            fut.set_exception(exc)
        return fut


def _die_with(parent: int) -> None:
    """Linux: this process gets SIGKILL when its parent dies (``PR_SET_PDEATHSIG``). A sweep killed outright
    (SIGKILL, the OOM killer) would otherwise leave its pool workers waiting forever for work, holding the output
    folder's lock (:mod:`netsim.sweep.run`); a point they had in hand is left unfinished (no manifest) and rerun."""
    if not sys.platform.startswith("linux"):
        return
    with contextlib.suppress(Exception):
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG
        if os.getppid() != parent:  # the parent died before the line above
            os._exit(1)


def _init_worker(parent: int | None = None) -> None:
    """Pool worker start: single-threaded BLAS, ignore Ctrl-C (the parent stops the sweep cleanly), and die at
    SIGTERM (the handler the forked worker inherits from the CLI would turn it into an interrupted run that
    writes its folder and goes on with its chunk: the parent's stop would wait for that), and with ``parent``
    (:func:`_die_with`)."""
    if parent is not None:
        _die_with(parent)
    os.environ.update(_SINGLE_THREAD_ENV)
    os.environ.setdefault("MPLBACKEND", "Agg")
    with contextlib.suppress(ImportError):
        from threadpoolctl import threadpool_limits

        threadpool_limits(1)
    with contextlib.suppress(ValueError):  # not the main thread
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


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


def require_dask(option: str) -> None:
    """Refuse ``option`` (``--scheduler``, ``--dask-local``, ``scheduler=``...) when the optional ``[dask]`` extra
    (dask.distributed) is not installed, with the command that installs it (it is not imported here).

    Raises
    ------
    ConfigError
        When ``distributed`` cannot be found.
    """
    import importlib.util

    from netsim.errors import ConfigError

    if importlib.util.find_spec("distributed") is None:
        raise ConfigError(f"{option} needs Dask's distributed scheduler, which is not installed: "
                          "pip install 'netsim[dask]' (or leave the option out to run in local processes)")


@contextlib.contextmanager
def open_executor(
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    local_dask: bool = False,
    scratch: Path | None = None,
    connect_timeout: float = 5.0,
    cluster_kwargs: Mapping[str, Any] | None = None,
    dashboard: str | None = None,
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
        Seconds to wait for the scheduler to answer (and to reconnect to it before the sweep gives up).
    cluster_kwargs
        Extra ``LocalCluster`` arguments (e.g. ``{"processes": False}`` for an in-process cluster).
    dashboard
        Address of the local cluster's dashboard (e.g. ``"127.0.0.1:8787"``); ``None`` (default): no
        dashboard, the scheduler listens for no HTTP at all (see :func:`_local_cluster`).

    Raises
    ------
    SchedulerUnreachable
        When ``scheduler`` does not answer within ``connect_timeout`` seconds.
    """
    os.environ.update(_SINGLE_THREAD_ENV)  # inherited by workers started from here
    if scheduler or local_dask:
        require_dask("scheduler=" if scheduler else "local_dask=True")
        with _quiet_dask_logs():
            from distributed import Client

            cluster = client = None
            try:
                if scheduler:
                    _probe_scheduler(scheduler, connect_timeout)
                    client = Client(scheduler, timeout=connect_timeout)
                    desc = f"dask scheduler {scheduler}"
                else:
                    in_process = not (cluster_kwargs or {}).get("processes", True)
                    log_file = None
                    if scratch is not None:
                        log_file = scratch / "workers.log"
                        scratch.mkdir(parents=True, exist_ok=True)
                    with _sigint_deferred():
                        with contextlib.nullcontext() if in_process else _stderr_to(log_file):
                            cluster = _local_cluster(workers, scratch, dashboard, cluster_kwargs)
                    client = Client(cluster, timeout=connect_timeout)
                    desc = f"local dask cluster ({len(cluster.workers)} workers)"
                    if dashboard is not None:
                        desc += f", dashboard {cluster.dashboard_link}"
            except BaseException:
                if client is not None:
                    _close_quietly(client, cluster)
                elif cluster is not None:
                    cluster.close()
                raise
            try:
                n = sum(client.nthreads().values()) or 1
                yield DaskExecutor(client), n, desc
            finally:
                _close_quietly(client, cluster)
        return
    n = workers or os.cpu_count() or 1
    if n <= 1:
        yield SerialExecutor(), 1, "serial (this process)"
        return
    import multiprocessing

    ctx = multiprocessing.get_context("fork") if "fork" in multiprocessing.get_all_start_methods() else None
    pool = ProcessPoolExecutor(max_workers=n, mp_context=ctx, initializer=_init_worker, initargs=(os.getpid(),))
    try:
        yield pool, n, f"process pool ({n} workers)"
    except BaseException:  # Ctrl-C / SIGTERM: the runs in flight are lost anyway, do not wait for them to end
        _stop_workers(pool)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _stop_workers(pool: ProcessPoolExecutor) -> None:
    """Terminate the pool's worker processes (an interrupted sweep stops at once; resuming redoes their runs).

    ``ProcessPoolExecutor.terminate_workers`` exists from Python 3.14; before, the pool's process table.
    """
    stop = getattr(pool, "terminate_workers", None)
    if callable(stop):
        stop()
        return
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        with contextlib.suppress(Exception):
            proc.terminate()


def scheduler_lost_client(client: Any) -> bool:
    """True when the Dask ``client`` is not connected to its scheduler."""
    return str(getattr(client.status, "value", client.status)) not in ("running", "newly-created")


def _close_quietly(client: Any, cluster: Any) -> None:
    """Close the client, then the local cluster: a client that cannot close cleanly (its scheduler is
    gone) waits at most 2 s and never keeps the local cluster's worker processes alive."""
    try:
        if scheduler_lost_client(client):
            client.close(timeout=2)
        else:
            client.close()
    except Exception:  # noqa: BLE001 - a client whose scheduler died may fail to close cleanly; nothing to keep
        log.debug("closing the Dask client failed", exc_info=True)
    finally:
        if cluster is not None:
            cluster.close()


