"""Checking a sweep file before anything runs (``netsim validate`` on a sweep).

A sweep is valid when its own schema holds, its base scenario is valid and every value of every factor
gives a valid scenario. Each factor level is checked once (with the other factors at their first level), so
a 21 x 21 grid costs 42 scenario checks, not 441.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from netsim.errors import ConfigError
from netsim.scenario.problems import Problem

__all__ = ["is_sweep_file", "check_sweep"]

_SWEEP_KEY = re.compile(r"^sweep\s*:", re.MULTILINE)


def is_sweep_file(path: str | Path) -> bool:
    """True when the YAML file at ``path`` is a sweep (it has a top-level ``sweep:`` key)."""
    from netsim.scenario.safe_yaml import YamlRefused, read_text

    try:  # bounded and regular files only: a FIFO or /dev/zero must not hang here (issue 14)
        text = read_text(str(path))
    except (OSError, YamlRefused):
        return False
    return _SWEEP_KEY.search(text) is not None


def _describe(values: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v!r}" for k, v in values.items())


class _Lines:
    """The lines of a sweep file's YAML paths, read once when first asked for (None when unknown)."""

    def __init__(self, path: str | Path) -> None:
        self.path = path
        self._index: Any = None

    def __call__(self, where: str | None) -> int | None:
        if not where:
            return None
        if self._index is None:
            from netsim.scenario.loader import LineIndex
            from netsim.scenario.safe_yaml import YamlRefused, read_text
            from netsim.sweep.spec import quote_flow_paths

            try:  # read as load_sweep reads it (flow lists of paths quoted, lines kept)
                self._index = LineIndex(quote_flow_paths(read_text(str(self.path))))
            except (OSError, YamlRefused):
                self._index = LineIndex()
        try:
            return self._index.line_of(where)
        except ConfigError:  # a path that does not parse: the problem keeps its file, without a line
            return None


def check_sweep(path: str | Path) -> list[Problem]:
    """Every problem of the sweep file at ``path`` (never raises for user mistakes).

    Problems of the sweep file itself carry its path; problems of a point name the point's factor values,
    e.g. ``point (sigma_s=1e-05, sigma_c=0.0132): nodes.sensor...: must not be negative``.
    """
    from netsim.scenario import check_scenario
    from netsim.sweep.spec import load_sweep

    file = str(path)
    line_of = _Lines(path)
    try:
        sweep = load_sweep(path)
    except ConfigError as exc:
        listed = getattr(exc, "problems", None)
        if listed is None:
            message = exc.message.removeprefix(f"{file}: ")  # the problem line names the file already
            return [Problem(exc.path or "", message, line=line_of(exc.path), file=file)]
        where = getattr(exc, "file", file)
        return [Problem(at, message, line=line if line is not None or where != file else line_of(at), file=where)
                for at, message, line in listed]
    base_problems = check_scenario(sweep.base_path or sweep.base)
    problems = list(base_problems)
    if any(p.is_error for p in base_problems):
        return problems  # points inherit the base's errors; reporting them per point would only repeat them
    seen: set[tuple[str, str]] = set()
    for point in sweep.points:
        fresh = [(name, repr(value)) for name, value in point.values.items() if (name, repr(value)) not in seen]
        if not fresh:
            continue
        seen.update(fresh)
        label = f"point ({_describe(point.values)})"
        line = line_of(f"factors.{fresh[0][0]}")  # the factor whose new level this point checks
        for problem in [*sweep.point_problems(point), *check_scenario(sweep.point_raw(point))]:
            if problem.is_error:
                path_text = f"{label}: {problem.path}" if problem.path else label
                problems.append(Problem(path_text, problem.message, line=line, file=file))
    return problems
