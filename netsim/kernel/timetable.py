"""A time-triggered dispatcher: a static schedule table per node (TrueTime's time-triggered dispatcher, OSEKtime).

The table has a ``cycle`` and slots ``(start, task, length)``; slot ``i`` activates a job of its task at
``offset + k * cycle + start_i`` for every ``k >= 0``. A task may have several slots per cycle. The node's policy is
``tt`` (:class:`~netsim.kernel.policies.TimeTriggered`): among slotted jobs the latest activation runs first, other
tasks (message-released, aperiodic, periodic) run in the gaps, first come first served; handlers preempt as
everywhere.

Slot overruns
-------------
A slotted job's absolute deadline is its slot's end (``activation + length``), so its record says whether it
finished inside its slot. A job still unfinished at its slot's end is a *deadline violation* (OSEKtime's term):
:attr:`Timetable.overruns` counts it, the job's ``deadline_overrun`` is set, and then

- ``overrun: continue`` (the default): the job keeps running; the next slot's activation preempts it (stack order)
  and it resumes in the gaps. Its record is a deadline miss.
- ``overrun: kill``: the job is killed at its slot's end (its record is killed and missed), so the next slot
  always starts on time: OSEKtime's deadline monitoring, with the job killed instead of the whole OS shut down.

An activation while the task's previous job is unfinished is queued behind it (the kernel's one-job-at-a-time
rule per task) and keeps its own slot's deadline.

Validation (:func:`create_timetable`): every slot lies inside the cycle, slots do not overlap, a slot is at least
its task's ``wcet`` long when the task has one, and a slotted task is activated only by the table (no period,
sporadic arrivals, messages or own deadline). Each refusal names the slot's path (``timetable.slots[i].length``).
"""

from __future__ import annotations

from heapq import heappush
from typing import TYPE_CHECKING, Any, NamedTuple

from netsim.errors import BuildError
from netsim.kernel.events import DEADLINE, NORMAL
from netsim.kernel.policies import TimeTriggered
from netsim.kernel.task import did_you_mean
from netsim.timebase import format_time

if TYPE_CHECKING:  # pragma: no cover
    from netsim.kernel.job import Job
    from netsim.kernel.kernel import Kernel

__all__ = ["Slot", "Timetable", "create_timetable", "OVERRUN_RULES"]

#: What happens to a job still running at its slot's end (see the module notes).
OVERRUN_RULES = ("continue", "kill")


class Slot(NamedTuple):
    """A slot of the table: its ``task`` is activated at ``start`` (ns from the cycle's start) and should finish
    within ``length`` ns."""

    start: int
    task: str
    length: int


class Timetable:
    """A node's static schedule table, running (made by :func:`create_timetable`).

    Attributes
    ----------
    cycle, offset : int
        Cycle length and the start of the first cycle (ns).
    slots : tuple[Slot, ...]
        In order of start.
    overrun : str
        ``"continue"`` or ``"kill"``.
    activations, overruns : int
        Jobs activated, and those unfinished at their slot's end.
    """

    def __init__(self, kernel: Kernel, cycle: int, slots: tuple[Slot, ...], offset: int, overrun: str) -> None:
        self.kernel = kernel
        self.cycle = cycle
        self.slots = slots
        self.offset = offset
        self.overrun = overrun
        self.activations = 0
        self.overruns = 0

    def _on_slot(self, ev: tuple) -> None:
        kernel = self.kernel
        if kernel.halted:
            return
        index, base = ev[1]
        slot = self.slots[index]
        now = kernel.now
        job = kernel._release(kernel.tasks[slot.task], None)
        job.deadline = end = now + slot.length  # the slot's end
        self.activations += 1
        queue, eid = kernel._queue, kernel._eid
        heappush(queue, (end, DEADLINE, next(eid), (self._on_slot_end, job)))
        index += 1
        if index == len(self.slots):
            index = 0
            base += self.cycle
        heappush(queue, (base + self.slots[index].start, NORMAL, next(eid), (self._on_slot, (index, base))))
        kernel._request_dispatch()

    def _on_slot_end(self, ev: tuple) -> None:
        job: Job = ev[1]
        if job.finish is not None:
            return
        self.overruns += 1
        job.deadline_overrun = True
        if self.overrun == "kill":
            self.kernel._kill(job)
            self.kernel._request_dispatch()

    def __repr__(self) -> str:
        return (f"<Timetable {self.kernel.name}: cycle {format_time(self.cycle)}, "
                f"{', '.join(f'{s.task}@{format_time(s.start)}' for s in self.slots)}>")


def create_timetable(kernel: Kernel, cycle: int, slots: list[tuple[int, str, int]], *, offset: int = 0,
                     overrun: str = "continue", path: str = "timetable") -> Timetable:
    """Run ``kernel``'s tasks from a static schedule table (the node's policy must be ``tt``).

    Parameters
    ----------
    cycle
        Cycle length, ns.
    slots
        ``(start, task, length)`` per slot, in any order (ns from the cycle's start).
    offset
        Start of the first cycle (absolute, ns).
    overrun
        ``"continue"`` or ``"kill"`` (see the module notes).
    path
        The table's YAML path, used in messages (``nodes.<n>.timetable``).

    Raises
    ------
    BuildError
        With the path of the first slot or field at fault.
    """
    node = kernel.name
    policy = kernel.policy
    if not isinstance(policy, TimeTriggered):
        raise BuildError(f"node '{node}': a timetable needs policy 'tt' (the node's is '{policy.name}')",
                         path=f"{path}")
    if getattr(kernel, "timetable", None) is not None:
        raise BuildError(f"node '{node}' already has a timetable", path=path)
    for what, value in (("cycle", cycle), ("offset", offset)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 0 or (what == "cycle" and not value):
            raise BuildError(f"node '{node}': the timetable's {what} must be a {'positive' if what == 'cycle' else 'non-negative'}"
                             f" integer number of ns, got {value!r}", path=f"{path}.{what}")
    if overrun not in OVERRUN_RULES:
        raise BuildError(f"node '{node}': overrun must be one of {', '.join(OVERRUN_RULES)}, got {overrun!r}",
                         path=f"{path}.overrun")
    if not slots:
        raise BuildError(f"node '{node}': the timetable has no slots; add e.g. {{start: 0 ms, task: ctl, "
                         "length: 2 ms}", path=f"{path}.slots")
    made: list[tuple[Slot, int]] = []
    for i, (start, task, length) in enumerate(slots):
        at = f"{path}.slots[{i}]"
        t = kernel.tasks.get(task)
        if t is None:
            raise BuildError(f"node '{node}': no task '{task}' on this node{did_you_mean(str(task), kernel.tasks)}",
                             path=f"{at}.task")
        if isinstance(start, bool) or not isinstance(start, int) or start < 0:
            raise BuildError(f"slot start must be a non-negative integer number of ns, got {start!r}",
                             path=f"{at}.start")
        if isinstance(length, bool) or not isinstance(length, int) or length <= 0:
            raise BuildError(f"slot length must be a positive integer number of ns, got {length!r}",
                             path=f"{at}.length")
        if start + length > cycle:
            raise BuildError(f"the slot of '{task}' ends at {format_time(start + length)}, after the cycle's end "
                             f"({format_time(cycle)}); shorten it, start it earlier or lengthen the cycle",
                             path=f"{at}.length")
        spec = t.spec
        if spec.wcet is not None and length < spec.wcet:
            raise BuildError(f"the slot of '{task}' ({format_time(length)}) is shorter than the task's wcet "
                             f"({format_time(spec.wcet)}); lengthen the slot", path=f"{at}.length")
        if spec.self_released or spec.release_kind != "aperiodic":
            raise BuildError(f"task '{task}' is activated by the timetable, so it must not have its own release "
                             f"(it is '{spec.release}'); drop its period, min_interarrival or release", path=f"{at}.task")
        if spec.deadline is not None:
            raise BuildError(f"task '{task}' is activated by the timetable: its deadline is its slot's end; drop "
                             "its 'deadline'", path=f"{at}.task")
        made.append((Slot(start, task, length), i))
    made.sort(key=lambda item: item[0].start)
    for (prev, _), (slot, i) in zip(made, made[1:]):
        if slot.start < prev.start + prev.length:
            raise BuildError(f"the slot of '{slot.task}' at {format_time(slot.start)} overlaps the slot of "
                             f"'{prev.task}' ({format_time(prev.start)} to {format_time(prev.start + prev.length)})",
                             path=f"{path}.slots[{i}].start")
    table = Timetable(kernel, cycle, tuple(s for s, _ in made), offset, overrun)
    policy.slotted = frozenset(s.task for s in table.slots)
    kernel.timetable = table  # type: ignore[attr-defined]
    now = kernel.now
    heappush(kernel._queue, (now + offset + table.slots[0].start, NORMAL, next(kernel._eid),
                             (table._on_slot, (0, now + offset))))
    return table
