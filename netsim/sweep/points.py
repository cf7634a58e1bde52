"""What a sweep worker does: run the points of a chunk, one after the other, and write each point's record.

A worker runs each point with the *point function* (``netsim.runner.run_point`` unless a caller injects
another picklable module-level function with the same signature ``fn(raw, out, seed) -> metrics``) and
writes the point's record ``point.json`` into the point's folder as soon as the point is done, so an
interrupted sweep keeps every finished point. Last of all it writes ``manifest.json`` (atomically): the sha256 of
every file of the folder. A point is trusted on resume only when its folder is a real folder (no symlink, in
it or as it) holding exactly those files with those digests (:func:`verified_record`): a point killed half-way,
an edited ``point.json``, ``metrics.csv`` or ``meta.json`` or a planted symlink is run again, never read
(issue 31). A point is run in a fresh folder: whatever was there (a symlink is removed, not followed) goes first.
Where the chunks run (this process, a pool, Dask) is :mod:`netsim.sweep.executor`.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import shutil
import time
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping

# the point folder's record and manifest are read by the one folder reader (netsim.results.folder)
from netsim.results.folder import (MANIFEST_NAME, RECORD_NAME, RunFolder, manifest_digests, read_record,
                                   verified_record)

__all__ = ["PointFn", "RECORD_NAME", "MANIFEST_NAME", "default_point_fn", "metrics_point_fn", "run_chunk",
           "read_record", "point_hash", "write_manifest", "verified_record", "fresh_folder"]

#: ``fn(raw_scenario, run_folder, seed) -> {metric: value}``
PointFn = Callable[[Mapping[str, Any], Path, int], Mapping[str, float]]


_SINGLE_THREAD_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def default_point_fn(raw: Mapping[str, Any], out: Path, seed: int) -> dict[str, float]:
    """The production point function: :func:`netsim.runner.run_point` (imported in the worker)."""
    from netsim.runner import run_point

    return run_point(raw, out, seed)


def metrics_point_fn(raw: Mapping[str, Any], out: Path, seed: int) -> dict[str, float]:
    """The point function of a sweep with ``runs: metrics``: :func:`netsim.runner.run_point` writing only
    ``metrics.csv`` and ``meta.json`` into the run folder."""
    from netsim.runner import run_point

    return run_point(raw, out, seed, tables=False)


def _run_status(folder: Path) -> tuple[str, str]:
    """The run's own status and error from its ``meta.json`` (``diverged at ...``, ``unstable at ...``); ``ok``
    when the point function wrote none."""
    meta = RunFolder(folder).meta
    status = str(meta.get("status") or "ok")
    return status, ("" if status == "ok" else str(meta.get("error") or ""))


def _write_json(path: Path, data: Any) -> None:
    from netsim.safe_write import write_atomic  # written after the run folder: a point without it is unfinished

    write_atomic(path, json.dumps(data, indent=1, sort_keys=True, allow_nan=True))


def write_manifest(folder: Path) -> None:
    """Write ``manifest.json``: the sha256 of every file of the point folder (written last, atomically)."""
    _write_json(folder / MANIFEST_NAME, {"files": manifest_digests(folder)})


def fresh_folder(folder: Path) -> None:
    """Empty ``folder`` for a (re)run: a symlink there is removed (never followed), a folder deleted."""
    if folder.is_symlink() or (folder.exists() and not folder.is_dir()):
        folder.unlink()
    elif folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)


def point_hash(raw: Mapping[str, Any], seed: int) -> str:
    """The scenario hash of a run: :func:`netsim.scenario.scenario_hash` of ``raw`` with its ``seed`` set.

    This equals the ``scenario_hash`` the runner writes into the run's ``meta.json``.
    """
    from netsim.scenario import scenario_hash

    return scenario_hash({**dict(raw), "seed": int(seed)})


def _run_hash(folder: Path, raw: Mapping[str, Any], seed: int) -> str:
    """The hash from the run folder's ``meta.json`` (written by the runner) or, failing that, computed."""
    meta = RunFolder(folder).meta
    given = meta.get("scenario_hash")
    seed_given = meta.get("seed")
    if isinstance(seed_given, int) and seed_given == int(seed) and isinstance(given, str) and given:
        return given
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
            fresh_folder(folder)  # nothing of an earlier (killed, tampered) attempt is kept or followed
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
            t0 = time.perf_counter()
            try:
                metrics = point_fn(task["raw"], folder, task["seed"])
                record["metrics"] = {str(k): float(v) for k, v in dict(metrics).items()}
                record["scenario_hash"] = _run_hash(folder, task["raw"], task["seed"])
                record["status"], record["error"] = _run_status(folder)  # diverged, unstable (issue 26)
            except Exception as exc:  # noqa: BLE001 - a failing point is a result of the sweep
                record["status"] = "error"
                record["error"] = f"{type(exc).__name__}: {exc}".strip()
                record["metrics"] = {}
            record["elapsed_s"] = time.perf_counter() - t0  # in point.json only, never in summary.csv
            record["warnings"] = list(caught.messages)
            _write_json(folder / RECORD_NAME, record)
            write_manifest(folder)  # last: the point is finished only now
            out.append(record)
    return out
