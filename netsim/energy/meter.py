"""Energy used by one node while it runs, and its battery running out.

:class:`EnergyMeter` reads the CPU time of the node's kernel (``Kernel.cpu_time``: tasks, handlers, context
switches) and the radio time its wireless media keep per state (:class:`~netsim.network.wireless.RadioClock`);
the energy used up to ``t`` is

    E(t) = P_idle t + (P_busy - P_idle) busy(t) + sum over radios and states of P_state time_state(t),

exact for the piecewise-constant powers of :class:`~netsim.energy.params.EnergyModel`. On a node with ``m``
cores or speed scaling (:mod:`netsim.kernel.multicore`) the powers are per core and the busy time is kept per
speed ``s`` (``Kernel.busy_by_speed``, core-ns):

    E_cpu(t) = m P_idle t + sum over speeds s of (P_busy(s) - P_idle) busy_s(t),

with ``P_busy(s) = static + (busy - static) s^exponent`` (:class:`~netsim.energy.params.CpuPower`), the
integral of that power law over the run.

The battery: a check at ``t`` knows the energy left ``R = C - E(t)``; the node cannot use it faster than
``P_max`` (CPU busy plus every radio in its most costly state), so it cannot run out before
``t + R / P_max``, where the next check is. The checks close in on the instant ``E`` reaches ``C`` and stop
within a nanosecond of it (fewer than ``ln(C / (P_max 1 ns)) P_max / P_mean`` checks per run: a few hundred);
then the node stops (:meth:`Kernel.halt`) and uses nothing more, and every network it is on drops its queued
frames (:meth:`Network.halt_node`, ``sender_dead``; a radio also stops receiving).
A node without a battery costs no event at all: its energy is read once, after the run.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from netsim.energy.params import EnergyModel
from netsim.timebase import MAX_TIME, S

if TYPE_CHECKING:
    from netsim.kernel.kernel import Kernel
    from netsim.env import SimEnv

__all__ = ["EnergyMeter"]


class EnergyMeter:
    """The energy of node ``node`` (see the module docstring).

    Parameters
    ----------
    env
        The simulation environment.
    node
        Node name.
    kernel
        The node's kernel.
    model
        Its energy model.
    media
        The wireless media the node is on (their radio time is tracked when the model has radio powers).

    Attributes
    ----------
    depleted_ns : int | None
        When the battery ran out (None: it did not, or there is none).
    checks : int
        Battery checks run (events on the loop).
    """

    def __init__(self, env: SimEnv, node: str, kernel: Kernel, model: EnergyModel, media: list[Any]) -> None:
        self.env = env
        self.node = node
        self.kernel = kernel
        self.model = model
        self.media = list(media)
        radio = model.radio
        self._clocks = [m.track_radio(node, radio.listen) for m in self.media] if radio is not None else []
        self._radio_w = ({"tx": radio.tx, "rx": radio.rx, "idle": radio.idle, "sleep": radio.sleep}
                         if radio is not None else {})
        cpu = model.cpu
        self._busy_w = cpu.busy if cpu is not None else 0.0
        self._idle_w = cpu.idle if cpu is not None else 0.0
        self._p_max = (getattr(kernel, "cores", 1) * max(self._busy_w, self._idle_w)  # P_busy(s) <= busy
                       + len(self._clocks) * max(self._radio_w.values(), default=0.0))
        self.depleted_ns: int | None = None
        self._frozen: dict[str, float] | None = None
        self.checks = 0
        battery = model.battery
        if battery is not None and self._p_max > 0:
            self._capacity = battery.capacity
            env.sim.call_at(0, self._check)

    # ------------------------------------------------------------------------------------------ reading
    def breakdown(self, t_ns: int) -> dict[str, float]:
        """Energy (J) and times (s) up to ``t_ns`` (at most the instant the battery ran out)."""
        if self._frozen is not None:
            return dict(self._frozen)
        busy = sum(self.kernel.cpu_time.values())
        by_speed = getattr(self.kernel, "busy_by_speed", None)
        if by_speed is None:
            cpu_j = (self._idle_w * t_ns + (self._busy_w - self._idle_w) * busy) / S
        else:  # several cores and/or speed scaling: each core idles or draws P_busy(s) at its speed
            cpu = self.model.cpu
            cores = self.kernel.cores
            dynamic = sum(((cpu.busy_at(s) if cpu is not None else 0.0) - self._idle_w) * ns
                          for s, ns in sorted(by_speed().items()))
            cpu_j = (self._idle_w * cores * t_ns + dynamic) / S
        times = {k: 0 for k in ("tx", "rx", "idle", "sleep")}
        for clock in self._clocks:
            for k, v in clock.times(t_ns).items():
                times[k] += v
        radio_j = sum(self._radio_w.get(k, 0.0) * v for k, v in times.items()) / S
        out = {"J": cpu_j + radio_j, "cpu_J": cpu_j, "cpu_busy_s": busy / S}
        if self._clocks:
            out["radio_J"] = radio_j
            out.update({f"radio_{k}_s": v / S for k, v in times.items()})
        return out

    def energy(self, t_ns: int) -> float:
        """Energy used up to ``t_ns`` (J)."""
        return self.breakdown(t_ns)["J"]

    def metrics(self, t_end_ns: int) -> dict[str, float]:
        """``J``, ``cpu_J``, ``cpu_busy_s``, with a radio ``radio_J`` and ``radio_<state>_s``, with a battery
        ``battery_left_J`` and ``depleted_s`` (NaN: it did not run out)."""
        out = self.breakdown(t_end_ns)
        if self.model.battery is not None:
            out["battery_left_J"] = max(0.0, self.model.battery.capacity - out["J"])
            out["depleted_s"] = float("nan") if self.depleted_ns is None else self.depleted_ns / S
        return out

    # ------------------------------------------------------------------------------------------ battery
    def _check(self) -> None:
        self.checks += 1
        now = self.env.sim.now
        left = self._capacity - self.energy(now)
        later = left / self._p_max * S  # the battery cannot run out before now + later
        if later > MAX_TIME - now:  # nor before the last time netsim represents (a tiny power: inf here)
            return
        dt = int(later)
        if dt >= 1:
            self.env.sim.call_at(now + dt, self._check)
            return
        self._frozen = self.breakdown(now)
        self.depleted_ns = now
        self.kernel.halt()
        for net in self._networks():
            net.halt_node(self.node)

    def _networks(self) -> list[Any]:
        """Every network the node is on: its wireless media, and the others among ``env.components``."""
        out = list(self.media)
        for key, comp in getattr(self.env, "components", {}).items():
            if key.startswith("network.") and comp not in out and self.node in getattr(comp, "nodes", ()):
                out.append(comp)
        return out
