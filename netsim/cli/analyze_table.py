"""The rows of ``netsim analyze``'s table (:mod:`netsim.cli.analyze`): their columns and small helpers."""

from __future__ import annotations

import math

import pandas as pd

__all__ = ["COLUMNS", "NS", "jobs_of", "ms", "row"]

#: Columns of the table (and of ``analysis.csv``).
COLUMNS = ["kind", "name", "analysis", "simulated", "unit", "verdict", "note"]
#: Seconds per nanosecond.
NS = 1e-9


def row(kind: str, name: str, analysis: float | str, simulated: float | str, unit: str, verdict: str,
        note: str = "") -> dict:
    """One row of the table."""
    return {"kind": kind, "name": name, "analysis": analysis, "simulated": simulated, "unit": unit,
            "verdict": verdict, "note": note}


def jobs_of(jobs: pd.DataFrame, node: str, task: str) -> pd.DataFrame:
    """The jobs of one task (or handler) of one node."""
    return jobs[(jobs["node"] == node) & (jobs["task"] == task)]


def ms(x: float) -> float:
    """Seconds (``None``/NaN allowed) as milliseconds (NaN)."""
    return float("nan") if x is None or (isinstance(x, float) and math.isnan(x)) else float(x) * 1e3
