"""Run cache of the cart report: the rows of points already run with the same code.

Each point's row is kept in ``<folder>/points_<hash>.pkl``, keyed by the point and the engine; ``<hash>``
(:func:`code_hash`) covers the cart's numeric modules, the scenario file and what the caller adds (the run
durations), so a change there starts a new cache and everything runs again. netsim's own code is not in the
key: the golden trace of ``scenarios/cart.yaml`` (tests/test_golden_traces.py) pins its output. Only runs
that ended ``ok`` are kept, so a run that failed (for example on a half-edited tree) runs again next time.
"""

from __future__ import annotations

import hashlib
import json
import pickle
from pathlib import Path
from typing import Any

__all__ = ["NUMERIC_MODULES", "code_hash", "PointCache"]

#: The cart modules whose code decides a run's numbers (the cache's key).
NUMERIC_MODULES = ("controllers.py", "dynamics.py", "encoding.py", "estimators.py", "friction.py", "jmap.py",
                   "metrics.py", "plant.py", "programs.py", "sim.py", "tuning.py")


def code_hash(scenario: Path, extra: str = "") -> str:
    """Hash of :data:`NUMERIC_MODULES`, the bytes of ``scenario`` and ``extra`` (12 hex digits)."""
    h = hashlib.sha256()
    for name in NUMERIC_MODULES:
        h.update((Path(__file__).parent / name).read_bytes())
    h.update(Path(scenario).read_bytes())
    h.update(extra.encode())
    return h.hexdigest()[:12]


class PointCache:
    """Rows of runs made with the code of hash ``code``, keyed by point and engine.

    Parameters
    ----------
    folder
        Where the cache file lives (``None``: no cache, every point runs).
    code
        The code's hash (:func:`code_hash`); it names the cache file.
    """

    def __init__(self, folder: Path | None, code: str) -> None:
        self.path = None if folder is None else Path(folder) / f"points_{code}.pkl"
        self.rows: dict[str, dict[str, Any]] = {}
        self.reused = 0
        if self.path is not None and self.path.is_file():
            with open(self.path, "rb") as fh:
                self.rows = pickle.load(fh)

    @staticmethod
    def key(point: dict[str, Any], engine: str) -> str:
        """The key of a point run with ``engine``."""
        return json.dumps({**point, "engine": engine}, sort_keys=True)

    def get(self, point: dict[str, Any], engine: str) -> dict[str, Any] | None:
        """A copy of the cached row, or ``None``."""
        row = self.rows.get(self.key(point, engine))
        return None if row is None else dict(row)

    def put(self, point: dict[str, Any], engine: str, row: dict[str, Any]) -> None:
        """Keep ``row`` (the caller keeps only runs that ended ``ok``)."""
        self.rows[self.key(point, engine)] = dict(row)

    def save(self) -> None:
        """Write the cache (atomically: a temporary file, then renamed)."""
        if self.path is not None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            tmp = self.path.with_suffix(".tmp")
            with open(tmp, "wb") as fh:
                pickle.dump(self.rows, fh)
            tmp.replace(self.path)
