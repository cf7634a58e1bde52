"""Run many scenarios, in parallel processes, and summarise them in one table.

``netsim batch FILE... | DIR`` calls :func:`run_batch`. Each scenario writes its own run folder
``<out>/<file stem>/``; ``<out>/summary.csv`` has one row per scenario (in the order given): ``scenario,
path, status, error, wall_time_s, run_dir`` and then every metric as a column. A scenario that fails (invalid
file, build error, exception) does not stop the batch: its row carries the error text. A run that diverges or
whose loop is unstable keeps its tables and its row (``status: diverged at t = ...``, ``unstable at t = ...``,
with the reason in ``error``). All count as not ok, by the same rule as ``netsim run`` (:mod:`netsim.status`):
the returned count of runs that are not ok is then non-zero.

Default output folder: ``reports/batch/<UTC time stamp>/``.
"""

from __future__ import annotations

import logging
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Iterable

import pandas as pd

from netsim.results import write_csv
from netsim.status import count_statuses
from netsim.sweep.check import is_sweep_file

__all__ = ["run_batch", "expand_paths", "SUMMARY_COLUMNS"]

log = logging.getLogger(__name__)

SUMMARY_COLUMNS = ["scenario", "path", "status", "error", "wall_time_s", "run_dir"]


def expand_paths(paths: Iterable[str | Path]) -> list[Path]:
    """Files as given; folders become their ``*.yaml``/``*.yml`` scenario files (sorted, sweeps skipped)."""
    out: list[Path] = []
    for p in paths:
        path = Path(p)
        if path.is_dir():
            found = sorted([*path.glob("*.yaml"), *path.glob("*.yml")])
            out += [f for f in found if not is_sweep_file(f)]
        else:
            out.append(path)
    return out


def _init_worker() -> None:
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    os.environ["OMP_NUM_THREADS"] = "1"
    os.environ.setdefault("MPLBACKEND", "Agg")


def _run_one(path: str, run_dir: str) -> dict[str, Any]:
    """One batch row (never raises)."""
    import time

    t0 = time.perf_counter()
    row: dict[str, Any] = {"scenario": Path(path).stem, "path": path, "status": "error", "error": "",
                           "wall_time_s": 0.0, "run_dir": run_dir}
    try:
        from netsim.runner import run

        result = run(path, out=run_dir)
        row["scenario"] = str(result.meta.get("scenario", row["scenario"]))
        row["status"] = result.status
        row["error"] = str(result.meta.get("error", "") or "")
        row.update({f"metric:{k}": float(v) for k, v in result.metrics.items()})
    except Exception as exc:  # noqa: BLE001 - a failing scenario becomes a row with its error
        row["status"] = "error"
        row["error"] = f"{type(exc).__name__}: {exc}"
    row["wall_time_s"] = time.perf_counter() - t0
    return row


def _run_dirs(files: list[Path], out: Path) -> list[Path]:
    seen: dict[str, int] = {}
    dirs = []
    for f in files:
        k = seen.get(f.stem, 0)
        seen[f.stem] = k + 1
        dirs.append(out / (f.stem if k == 0 else f"{f.stem}-{k + 1}"))
    return dirs


def run_batch(
    paths: Iterable[str | Path],
    *,
    out: str | Path | None = None,
    workers: int | None = None,
    progress: bool = True,
) -> tuple[pd.DataFrame, int]:
    """Run every scenario in ``paths`` (files or folders); write ``summary.csv``.

    Parameters
    ----------
    paths
        Scenario files and/or folders of scenario files.
    out
        Output folder (default ``reports/batch/<UTC stamp>``).
    workers
        Worker processes (default: CPU count; 1 runs in this process).
    progress
        Show a progress bar on stderr.

    Returns
    -------
    (summary, n_not_ok)
        The summary table (one row per scenario, metrics as columns) and the number of rows whose status
        is not ``ok`` (diverged, unstable or error; :func:`netsim.status.count_statuses` of
        ``summary["status"]`` splits them).
    """
    files = expand_paths(paths)
    folder = Path(out) if out is not None else (
        Path("reports") / "batch" / datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    )
    folder.mkdir(parents=True, exist_ok=True)
    dirs = _run_dirs(files, folder)
    n_workers = max(1, min(workers or os.cpu_count() or 1, max(1, len(files))))
    rows: list[dict[str, Any] | None] = [None] * len(files)

    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    bar = Progress(TextColumn("batch"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                   TextColumn("{task.description}"), console=Console(stderr=True), disable=not progress,
                   transient=False)
    with bar:
        task = bar.add_task("", total=len(files))
        if n_workers == 1:
            for i, (f, d) in enumerate(zip(files, dirs)):
                bar.update(task, description=f.name)
                rows[i] = _run_one(str(f), str(d))
                bar.advance(task)
        else:
            with ProcessPoolExecutor(max_workers=n_workers, initializer=_init_worker) as pool:
                futures = {pool.submit(_run_one, str(f), str(d)): i for i, (f, d) in enumerate(zip(files, dirs))}
                for fut in as_completed(futures):
                    i = futures[fut]
                    try:
                        rows[i] = fut.result()
                    except Exception as exc:  # noqa: BLE001 - a crashed worker process
                        rows[i] = {"scenario": files[i].stem, "path": str(files[i]), "status": "error",
                                   "error": f"{type(exc).__name__}: {exc}", "wall_time_s": 0.0,
                                   "run_dir": str(dirs[i])}
                    bar.update(task, description=files[i].name)
                    bar.advance(task)

    summary = _summary([r for r in rows if r is not None])
    write_csv(summary, folder / "summary.csv")
    counts = count_statuses(summary["status"] if not summary.empty else [])
    summary.attrs["path"] = str(folder / "summary.csv")
    if counts.not_ok:
        log.warning("%s; see %s", counts.describe("scenario"), folder / "summary.csv")
    return summary, counts.not_ok


def _summary(rows: list[dict[str, Any]]) -> pd.DataFrame:
    metric_cols = sorted({k for r in rows for k in r if k.startswith("metric:")})
    frame = pd.DataFrame(rows, columns=SUMMARY_COLUMNS + metric_cols)
    return frame.rename(columns={c: c.removeprefix("metric:") for c in metric_cols})
