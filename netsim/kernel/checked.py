"""What the type checker reads for the kernel's checked task and handler records.

:mod:`netsim.kernel.task` makes :class:`~netsim.kernel.task.CheckedTask` and
:class:`~netsim.kernel.task.CheckedHandler` at import time from the fields of ``TaskSpec`` and ``HandlerSpec``
(``dataclasses.make_dataclass``: frozen, slotted, so the kernel's reads at every release are cheap). A class
made at run time cannot be read by the type checker, so task.py imports these declarations instead under
``TYPE_CHECKING``; nothing imports this module at run time. Their fields are the specs' fields after the check
(integer ns, defaults filled); tests/kernel/test_checked_types.py keeps the two lists equal.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from netsim.distributions import Distribution
    from netsim.kernel.task import HandlerRef, SetPeriodRule


@dataclasses.dataclass(frozen=True, slots=True)
class CheckedTask:
    """A checked TaskSpec (see ``TaskSpec.checked``)."""

    name: str
    period: int | None
    offset: int
    deadline: int | None
    priority: int | float | None
    wcet: int | None
    release: str | None
    preemptible: bool
    wcet_handler: HandlerRef
    deadline_handler: HandlerRef
    release_jitter: Distribution | None
    min_interarrival: int | None
    extra_interarrival: Distribution | None
    abort_on_miss: bool
    set_period: SetPeriodRule

    @property
    def release_kind(self) -> str:
        """``"periodic"``, ``"aperiodic"``, ``"sporadic"`` or ``"on_message"``."""
        raise NotImplementedError  # TaskSpec.release_kind at run time

    @property
    def release_network(self) -> str | None:
        """The network whose messages release this task, else None."""
        raise NotImplementedError  # TaskSpec.release_network at run time

    @property
    def self_released(self) -> bool:
        """True for a task the kernel releases by itself (periodic or sporadic)."""
        raise NotImplementedError  # TaskSpec.self_released at run time

    def replaced(self, **changes: Any) -> CheckedTask:
        """A copy with ``changes`` (run-time parameters in integer ns)."""
        raise NotImplementedError  # task._replaced at run time


@dataclasses.dataclass(frozen=True, slots=True)
class CheckedHandler:
    """A checked HandlerSpec (see ``HandlerSpec.checked``)."""

    name: str
    priority: int | float
    latency: int
