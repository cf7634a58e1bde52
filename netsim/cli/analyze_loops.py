"""``netsim analyze``'s control-loop rows: per PID or state-feedback loop on an LTI plant, the expected ISE that
:mod:`netsim.analysis.loops` computes (fed the sampling offsets and input-output delays the run measured) beside
the run's ``<y>.ISE`` metric. Split from :mod:`netsim.cli.analyze`, which adds these rows to its table.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from netsim.cli.analyze_table import row as _row

if TYPE_CHECKING:
    import pandas as pd

    from netsim.results import RunResult
    from netsim.scenario import Simulation  # the builder's, as netsim.scenario names it
    from netsim.scenario.schema import Scenario

__all__ = ["loop_rows"]


def loop_rows(scenario: Scenario, sim: Simulation, jobs: pd.DataFrame, result: RunResult) -> list[dict]:
    """One ``loop`` row per loop of :func:`~netsim.analysis.loops.find_loops` whose judged output has an ISE
    metric in the run: the expected ISE and the run's, or ``n/a`` with the reason."""
    from netsim.analysis.loops import find_loops, loop_cost, loop_output

    loops = find_loops(scenario, sim)
    if not loops:
        return []
    raw = getattr(result, "metrics", None)
    metrics = {} if raw is None else dict(raw)
    t_end = float(result.signals["time_s"].max()) if len(result.signals) else 0.0
    rows: list[dict] = []
    for loop in loops:
        y_name = loop_output(scenario, sim.plant, loop)
        metric = metrics.get(f"{y_name}.ISE") if y_name else None
        if y_name is None or metric is None:
            continue
        found = loop_cost(scenario, sim, loop, y_name, jobs, t_end)
        if found.cost is None:
            rows.append(_row("loop", loop.name, "n/a", float(metric), "ISE", "n/a", found.why))
            continue
        cost = found.cost
        rel = (float(metric) - cost) / cost if cost else float("nan")
        rows.append(_row("loop", loop.name, cost, float(metric), "ISE", f"{rel * 100:+.1f} %",
                         f"E[ISE] of {loop.reference or 0}-{y_name}, 0-{t_end:.3g} s, {found.pairs} (offset, delay) "
                         "pairs of the run"))
    return rows
