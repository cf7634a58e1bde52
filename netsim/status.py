"""Run statuses and what they mean for counts and exit codes: one rule for ``run``, ``batch`` and ``sweep``.

A run's status (``meta.json``, the ``status`` column of every summary) is one of

``ok``
    the run finished normally;
``diverged at t = ... s``
    the loop went unstable and the run stopped there (its tables up to that instant are written), or a signal
    became non-finite or ran away past ``diverged_above`` times the loop's scale;
``unstable at t = ... s``
    the run went to its end, but the loop left its operating region (:mod:`netsim.results.verdict`): an error envelope
    that kept growing, a signal past its ``verdict.bound``, or a metric's own verdict (a fallen pendulum);
``error``
    the run could not be built or raised (the error text is recorded);
``interrupted at t = ... s``
    Ctrl-C or SIGTERM stopped the run; its tables up to that instant are written, without metrics;
``pending``
    a sweep run not executed yet (Ctrl-C).

Only ``ok`` is a success. A diverged or unstable run is a result worth keeping (it is a point of a surface, a row
of a batch), but it is not a success: ``netsim run``, ``netsim batch`` and ``netsim sweep`` all exit with
:data:`EXIT_FAILED` when any run is not ``ok`` (``pending`` runs of an interrupted sweep exit with
:data:`EXIT_INTERRUPTED`). ``netsim validate`` exits with :data:`EXIT_PROBLEMS` when a file has problems and prints
their count.
"""

from __future__ import annotations

from collections import Counter
from typing import Iterable

__all__ = [
    "OK",
    "ERROR",
    "PENDING",
    "DIVERGED",
    "UNSTABLE",
    "INTERRUPTED",
    "EXIT_OK",
    "EXIT_FAILED",
    "EXIT_INVALID",
    "EXIT_PROBLEMS",
    "EXIT_INTERRUPTED",
    "kind_of",
    "is_ok",
    "StatusCounts",
    "count_statuses",
]

OK = "ok"
ERROR = "error"
PENDING = "pending"
DIVERGED = "diverged"
UNSTABLE = "unstable"
INTERRUPTED = "interrupted"

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_INVALID = 2
#: ``netsim validate`` found problems (it prints how many; the count is never the exit code).
EXIT_PROBLEMS = 1
EXIT_INTERRUPTED = 130


def kind_of(status: object) -> str:
    """``ok``, ``diverged``, ``unstable``, ``interrupted``, ``pending`` or ``error`` (anything else, including an
    empty status)."""
    text = str(status).strip() if status is not None else ""
    if text == OK:
        return OK
    if text.startswith(DIVERGED):
        return DIVERGED
    if text.startswith(UNSTABLE):
        return UNSTABLE
    if text.startswith(INTERRUPTED):
        return INTERRUPTED
    if text == PENDING:
        return PENDING
    return ERROR


def is_ok(status: object) -> bool:
    """True only for a run that finished normally."""
    return kind_of(status) == OK


class StatusCounts:
    """How many runs ended in each kind of status, with the exit code and a one-line summary they imply.

    Parameters
    ----------
    statuses
        The status of every run.
    """

    def __init__(self, statuses: Iterable[object]) -> None:
        counts = Counter(kind_of(s) for s in statuses)
        self.ok = counts[OK]
        self.diverged = counts[DIVERGED]
        self.unstable = counts[UNSTABLE]
        self.error = counts[ERROR]
        self.pending = counts[PENDING]
        self.interrupted = counts[INTERRUPTED]
        self.total = self.ok + self.diverged + self.unstable + self.error + self.pending + self.interrupted

    @property
    def not_ok(self) -> int:
        """Runs that ran and did not finish normally (diverged, unstable, error or interrupted)."""
        return self.diverged + self.unstable + self.error + self.interrupted

    def exit_code(self, interrupted: bool = False) -> int:
        """:data:`EXIT_INTERRUPTED` if interrupted, else :data:`EXIT_FAILED` if any run is not ok, else 0."""
        if interrupted:
            return EXIT_INTERRUPTED
        return EXIT_FAILED if self.not_ok else EXIT_OK

    def describe(self, what: str = "run") -> str:
        """E.g. ``1 of 2 scenarios ok, 1 diverged``."""
        plural = what if self.total == 1 else f"{what}s"
        text = f"{self.ok} of {self.total} {plural} ok"
        for n, word in ((self.diverged, "diverged"), (self.unstable, "unstable"), (self.error, "failed"), (self.interrupted, "interrupted"),
                        (self.pending, "not run")):
            if n:
                text += f", {n} {word}"
        return text


def count_statuses(statuses: Iterable[object]) -> StatusCounts:
    """:class:`StatusCounts` of ``statuses``."""
    return StatusCounts(statuses)
