"""Fuzz figures: run every generated case (or a sample) through validate and run; print the counts.

Usage: ``python tests/fuzz/fuzz_figures.py [--every N] [--jobs J] [--json OUT]`` (from the repository root).
Each worker process has a memory limit (a blow-up counts as a traceback: MemoryError) and every command a
time limit (a hang).
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

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from tests.fuzz.mutations import Figures, all_mutations, case_file_name, evaluate  # noqa: E402


def _init() -> None:
    limit = 6 * 1024**3
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def _one(args: tuple[int, object, float]) -> tuple[int, object]:
    i, m, seconds = args
    with tempfile.TemporaryDirectory() as tmp:
        return i, evaluate(m, Path(tmp), seconds=seconds)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--every", type=int, default=1, help="take every N-th case of each kind")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    by_kind: dict[str, list] = {}
    for m in all_mutations():
        by_kind.setdefault(m.kind, []).append(m)
    # every N-th case of each kind; kinds with few cases (names, duplicates, empties) are taken whole
    cases = [m for ms in by_kind.values() for m in (ms if len(ms) < 60 else ms[:: a.every])]
    figures = Figures()
    defects = []
    # workers are not daemonic (a scenario's run may start processes of its own)
    with cf.ProcessPoolExecutor(a.jobs, mp_context=mp.get_context("spawn"), initializer=_init,
                                max_tasks_per_child=25) as pool:
        futures = [pool.submit(_one, (i, m, a.seconds)) for i, m in enumerate(cases)]
        for future in cf.as_completed(futures):
            i, outcome = future.result()
            m = cases[i]
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
