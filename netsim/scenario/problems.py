"""Problems found in a scenario, and the error that carries all of them at once.

Every check (YAML syntax, schema, plugin parameters, cross references) produces :class:`Problem` records
with the dotted YAML path of the offending value; the loader adds the file and line. A scenario that has
at least one problem of severity ``"error"`` raises :class:`ScenarioError`, which lists them all.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from typing import Iterable

from netsim.errors import ConfigError

__all__ = ["Problem", "ScenarioError", "ERROR", "WARNING", "sort_problems", "shorten"]

ERROR = "error"
WARNING = "warning"

#: A run of non-space characters longer than this in a path or message is cut (a key or value pasted from a file).
LONG_TOKEN = 200
#: The longest message kept whole (lists of known names included).
LONG_MESSAGE = 2000
_LONG = re.compile(r"\S{%d,}" % (LONG_TOKEN + 1))


def _one_line(text: str) -> str:
    """``text`` with its line breaks (and the spaces around them) turned into single spaces."""
    return " ".join(part.strip() for part in text.splitlines() if part.strip()) if "\n" in text or "\r" in text else text


def shorten(text: str) -> str:
    """``text`` with every token over :data:`LONG_TOKEN` characters cut to its start and its length.

    A message names what it refuses; when that is a 10^6-character key, value or alias name it must not echo it
    (issue 14: "an error message never echoes a whole file's content"). Text of at most :data:`LONG_TOKEN`
    characters is returned as it is (the same object).
    """
    if len(text) <= LONG_TOKEN:
        return text
    out = _LONG.sub(lambda m: f"{m.group()[:60]}...({len(m.group())} characters)", text)
    return out if len(out) <= LONG_MESSAGE else out[:LONG_MESSAGE] + "..."


@dataclass(frozen=True)
class Problem:
    """One thing wrong (or suspicious) in a scenario.

    Attributes
    ----------
    path
        Dotted YAML path (``nodes.controller.tasks[1].period``); empty for the whole file.
    message
        What is wrong and what to change. Path and message are cut where a word runs over
        :data:`LONG_TOKEN` characters (:func:`shorten`).
    line
        1-based line in ``file``, when known.
    file
        The scenario file, when the scenario came from a file.
    severity
        ``"error"`` (the scenario cannot run) or ``"warning"`` (it runs, but look again).
    supersedes
        True when this problem says all there is to say about the value at ``path`` (a NaN or a 5000-digit
        number): :func:`sort_problems` then drops the other errors at the same path, which would only describe
        the same unusable value from another angle.
    """

    path: str
    message: str
    line: int | None = None
    file: str | None = None
    severity: str = ERROR
    supersedes: bool = False

    def __post_init__(self) -> None:
        # every problem, whichever check made it, is one short line (shorten): no message echoes a file, and a
        # library's multi-line error text (scipy, slycot) does not spill onto lines without a path
        object.__setattr__(self, "path", shorten(self.path))
        object.__setattr__(self, "message", shorten(_one_line(self.message)))

    @property
    def is_error(self) -> bool:
        """True for problems that stop the scenario from running."""
        return self.severity == ERROR

    def located(self, line: int | None, file: str | None) -> Problem:
        """A copy with ``line`` and ``file`` filled in where still missing."""
        return replace(self, line=self.line if self.line is not None else line, file=self.file or file)

    def __str__(self) -> str:
        return self.describe()

    def describe(self, *, tag: bool = True) -> str:
        """``file:line: [warning: ]path: message`` (``tag=False`` leaves out the severity tag)."""
        where = ""
        if self.file:
            where = f"{self.file}:{self.line}: " if self.line is not None else f"{self.file}: "
        elif self.line is not None:
            where = f"line {self.line}: "
        mark = "warning: " if tag and self.severity == WARNING else ""
        body = f"{self.path}: {self.message}" if self.path else self.message
        return f"{where}{mark}{body}"


_NON_FINITE = re.compile(r"\bnan\b|\binf\b|infinit", re.IGNORECASE)


def _inside(path: str, container: str) -> bool:
    """True when ``path`` lies strictly inside ``container`` (``plant.A[1][0]`` inside ``plant.A``)."""
    if not container:
        return bool(path)
    return len(path) > len(container) and path.startswith(container) and path[len(container)] in ".["


def sort_problems(problems: Iterable[Problem]) -> list[Problem]:
    """Problems without duplicates, ordered by file and line (problems without a line keep their order, last).

    An error at the path of a problem with ``supersedes=True`` is dropped (see :class:`Problem`), and so is an
    error about NaN or infinite values at a path that holds such a problem (``plant.A: A contains NaN or
    infinite entries`` beside ``plant.A[1][0]: infinity is not a usable number; write ...``): it names the same
    value less precisely.
    """
    problems = list(problems)
    final = [(p.file, p.path) for p in problems if p.supersedes and p.is_error]
    exact = set(final)

    def superseded(p: Problem) -> bool:
        if not p.is_error or p.supersedes:
            return False
        if (p.file, p.path) in exact:
            return True
        return _NON_FINITE.search(p.message) is not None and any(
            f == p.file and _inside(q, p.path) for f, q in final)

    seen: set[tuple[str, str, str]] = set()
    unique: list[Problem] = []
    for p in problems:
        key = (p.path, p.message, p.severity)
        if final and superseded(p):
            continue
        if key not in seen:
            seen.add(key)
            unique.append(p)
    order = {id(p): i for i, p in enumerate(unique)}
    return sorted(unique, key=lambda p: (p.file or "", p.line is None, p.line or 0, order[id(p)]))


class ScenarioError(ConfigError):
    """A scenario has problems; ``problems`` lists every one (errors and warnings).

    The message is one problem per line, as ``netsim validate`` prints them.
    """

    def __init__(self, problems: list[Problem]) -> None:
        self.problems = list(problems)
        errors = [p for p in self.problems if p.is_error] or self.problems
        first = errors[0] if errors else None
        n = len(errors)
        head = f"scenario has {n} problem{'s' if n != 1 else ''}"
        lines = "\n".join(f"  {p}" for p in self.problems)
        super().__init__(f"{head}:\n{lines}" if lines else head)
        self.path = first.path if first else None
        self.args = (self.problems,)  # re-creatable from args, like the other netsim errors

    def __str__(self) -> str:
        return self.message

    @property
    def errors(self) -> list[Problem]:
        """Only the problems of severity ``"error"``."""
        return [p for p in self.problems if p.is_error]
