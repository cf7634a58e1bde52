"""Warnings about a finished run whose status is ``ok`` but whose numbers should not be trusted as they stand.

:func:`load_warnings` looks at the tables and metrics of a run for the signs of a network or a CPU that could not
carry its load: a network busy nearly all the time (utilization at or above :data:`SATURATED`), a network that
dropped a sizeable share of its message copies (:data:`DROP_SHARE`, with the reasons), and a task of the scenario
that never had a job (a controller whose messages never arrived, for instance). Each warning names what to look
at; the runner logs them and keeps them in ``meta.json`` (``warnings``).
"""

from __future__ import annotations

from typing import Any, Iterable, Mapping

__all__ = ["SATURATED", "DROP_SHARE", "load_warnings"]

#: A network whose utilization is at least this is saturated.
SATURATED = 0.95
#: A network that drops at least this share of its message copies gets a warning.
DROP_SHARE = 0.01


def load_warnings(metrics: Mapping[str, float], jobs: Any, nodes: Mapping[str, Any] | None,
                  networks: Iterable[str]) -> list[str]:
    """The warnings of one run (empty when nothing looks overloaded).

    Parameters
    ----------
    metrics
        The run's metrics (``net.<name>.utilization``, ``net.<name>.copies``, ``net.<name>.dropped[.<reason>]``).
    jobs
        The jobs table (``node, task`` columns): a DataFrame, a summary table, or the records' columns
        (:class:`netsim.results.rows.Rows`, whose ``jobs["node"]`` is a numpy array).
    nodes
        The scenario's node specs (each with ``tasks``), to find tasks that never ran.
    networks
        Names of the scenario's networks.
    """
    out: list[str] = []
    for net in sorted(networks):
        util = metrics.get(f"net.{net}.utilization")
        if util is not None and util == util and util >= SATURATED:
            out.append(f"network '{net}' is saturated: busy {100 * util:.1f} % of the run; messages wait or are "
                       f"dropped (lower the offered load, or raise networks.{net}.bitrate)")
        copies = metrics.get(f"net.{net}.copies") or metrics.get(f"net.{net}.messages") or 0.0
        dropped = metrics.get(f"net.{net}.dropped") or 0.0
        if copies and dropped / copies >= DROP_SHARE:
            prefix = f"net.{net}.dropped."
            reasons = sorted(((k[len(prefix):], v) for k, v in metrics.items() if k.startswith(prefix) and v),
                             key=lambda kv: -kv[1])
            why = ", ".join(f"{name} {int(v)}" for name, v in reasons) or "see messages.csv"
            out.append(f"network '{net}' dropped {int(dropped)} of {int(copies)} message copies "
                       f"({100 * dropped / copies:.1f} %: {why})")
    ran = set()
    if jobs is not None and len(jobs):
        ran = set(zip(jobs["node"].astype(str), jobs["task"].astype(str)))
    for node, spec in (nodes or {}).items():
        for task in getattr(spec, "tasks", None) or []:
            if (str(node), str(task.name)) not in ran:
                release = getattr(task, "release", None)
                how = f" (released {release})" if release else ""
                out.append(f"task {node}.{task.name}{how} never ran: nothing released it during the run")
    return out
