"""Fuzz figures: run every generated case (or a sample) through validate and run; print the counts.

Usage: ``python tests/fuzz/fuzz_figures.py [--every N] [--jobs J] [--json OUT] [--validate-only] [--scenario S]``
(from the repository root). Each worker process has a memory limit (a blow-up counts as a traceback: MemoryError)
and every command a time limit (a hang). ``--json`` also lists every case with a defect, with the message or
error behind it. ``--validate-only`` skips ``netsim run`` (quick: messages without a path or a fix only).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import concurrent.futures as cf
import multiprocessing as mp
import resource
import sys
import tempfile
from pathlib import Path
from typing import Iterator

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from tests.fuzz.mutations import Figures, Outcome, all_mutations, case_file_name, evaluate  # noqa: E402


def _init() -> None:
    limit = 6 * 1024**3
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def _one(args: tuple[int, object, float, bool]) -> tuple[int, object]:
    i, m, seconds, run = args
    with tempfile.TemporaryDirectory() as tmp:
        return i, evaluate(m, Path(tmp), seconds=seconds, run=run)


#: Cases per pool of worker processes: a fresh pool per chunk bounds what a worker accumulates. (Python 3.11's
#: ``max_tasks_per_child`` left the executor waiting forever once its workers retired: twice here, 0 cases done.)
CHUNK = 40


def _outcomes(cases: list, a: argparse.Namespace) -> Iterator[tuple[int, Outcome]]:
    """``(index, outcome)`` of every case, in completion order; a case whose worker died or never answered
    (stuck outside Python, where the alarm of :func:`evaluate` cannot reach) is a traceback or a hang."""
    commands = 3 if not a.validate_only else 1
    for start in range(0, len(cases), CHUNK):
        chunk = list(range(start, min(start + CHUNK, len(cases))))
        # workers are not daemonic (a scenario's run may start processes of its own)
        pool = cf.ProcessPoolExecutor(a.jobs, mp_context=mp.get_context("spawn"), initializer=_init)
        late: set[cf.Future] = set()
        try:
            futures = {pool.submit(_one, (i, cases[i], a.seconds, not a.validate_only)): i for i in chunk}
            # every case may use its full time limit per command, plus start-up
            limit = (len(chunk) / a.jobs + 1) * (commands * a.seconds + 10)
            finished, late = cf.wait(futures, timeout=limit)
            for future in finished:
                try:
                    yield future.result()
                except Exception as exc:  # noqa: BLE001 - a worker that died (BrokenProcessPool) is a defect
                    yield futures[future], Outcome(traceback=f"worker died: {type(exc).__name__}: {exc}"[:300])
            for future in late:
                yield futures[future], Outcome(hang=f"no answer from the worker after {limit:.0f} s")
        finally:
            if late:
                for proc in list(getattr(pool, "_processes", {}).values()):  # stuck: nothing else stops them
                    proc.kill()
            pool.shutdown(wait=True, cancel_futures=True)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--every", type=int, default=1, help="take every N-th case of each kind")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--json", default=None)
    ap.add_argument("--validate-only", action="store_true", help="run only netsim validate on each case")
    ap.add_argument("--scenario", action="append", default=None, help="only cases of this scenario file name")
    a = ap.parse_args()
    by_kind: dict[str, list] = {}
    for m in all_mutations():
        if a.scenario is None or m.scenario in a.scenario:
            by_kind.setdefault(m.kind, []).append(m)
    # every N-th case of each kind; kinds with few cases (names, duplicates, empties) are taken whole
    cases = [m for ms in by_kind.values() for m in (ms if len(ms) < 60 else ms[:: a.every])]
    figures = Figures()
    defects = []
    for done, (i, outcome) in enumerate(_outcomes(cases, a), 1):
        m = cases[i]
        if done % 50 == 0 or done == len(cases):
            print(f"{done}/{len(cases)} cases", file=sys.stderr, flush=True)
        bad = figures.add(m, outcome, case_file_name(m))
        if bad:
            defects.append({"scenario": m.scenario, "kind": m.kind, "path": m.path, "detail": m.detail,
                            "defects": bad})
    d = dataclasses.asdict(figures)
    examples = d.pop("examples")
    print(json.dumps(d, indent=1))
    for k, v in examples.items():
        print(f"-- {k}")
        for e in v:
            print("   ", e)
    if a.json:
        Path(a.json).write_text(json.dumps({"figures": d, "examples": examples, "defects": defects}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
