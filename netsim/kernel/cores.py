"""A scenario node's CPU: the keywords of its ``cores``, ``multicore``, ``migration_cost``, ``speed`` and
``speed_levels`` for :class:`~netsim.kernel.kernel.Kernel`, checked with their YAML paths.

The kernel itself (:mod:`netsim.kernel.multicore`, :mod:`netsim.kernel.speed`) checks the same rules with the
node and task named; here each problem is reported at its place in the scenario (``nodes.<n>.tasks[i].core``),
before the kernel is built, so ``netsim validate`` and ``netsim run`` refuse the same scenarios.
"""

from __future__ import annotations

from typing import Any

from netsim.errors import BuildError

__all__ = ["MULTICORE_MODES", "cpu_options"]

#: The ways a multicore node schedules its cores (the first is the default).
MULTICORE_MODES = ("global", "partitioned")


def cpu_options(node: Any, npath: str) -> dict[str, Any]:
    """The ``Kernel`` keywords of a scenario node's ``cores``, ``multicore``, ``migration_cost``, ``speed`` and
    ``speed_levels`` (only those given), after checking its tasks' ``core`` against them.

    Raises
    ------
    BuildError
        At ``<npath>.tasks[i].core`` (a core out of range, a core under global scheduling, a task without a
        core under partitioned scheduling) or at ``<npath>.<field>``.
    """
    cores = getattr(node, "cores", None)
    mode = getattr(node, "multicore", None)
    out: dict[str, Any] = {}
    for key in ("cores", "multicore", "migration_cost", "speed", "speed_levels"):
        value = getattr(node, key, None)
        if value is not None:
            out[key] = value
    m = 1 if cores is None else cores
    partitioned = mode == "partitioned"
    if partitioned and m < 2:
        raise BuildError(f"multicore: partitioned needs cores: 2 or more (the node has {m})", path=f"{npath}.multicore")
    for i, task in enumerate(getattr(node, "tasks", [])):
        core = getattr(task, "core", None)
        where = f"{npath}.tasks[{i}].core"
        if core is None:
            if partitioned:
                raise BuildError(f"task '{task.name}' needs a core under multicore: partitioned (0..{m - 1})",
                                 path=where)
            continue
        if not partitioned:
            raise BuildError(f"task '{task.name}': a core is only used with partitioned scheduling; set "
                             f"{npath}.multicore: partitioned, or remove the core", path=where)
        if not 0 <= core < m:
            raise BuildError(f"task '{task.name}': core {core} is out of range; the node has {m} cores "
                             f"(0..{m - 1})", path=where)
    levels = getattr(node, "speed_levels", None)
    speed = getattr(node, "speed", None)
    if levels is not None and speed is None:
        raise BuildError("speed_levels needs an initial speed (e.g. speed: 1)", path=f"{npath}.speed_levels")
    if levels is not None and speed not in levels:
        raise BuildError(f"speed {speed} is not one of speed_levels {list(levels)}", path=f"{npath}.speed")
    return out
