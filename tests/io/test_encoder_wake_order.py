"""The exact encoder's wake-up keeps its place among entries due at the same instant.

A re-prediction that finds the same tick keeps the wake-up already in the event loop's heap (issue 19: one
heap entry fewer per control period on the cart) instead of pushing a new one. The kept entry was pushed
earlier, so it must still run where an entry pushed by the re-prediction would: after anything scheduled for
that instant in between. Polling is the reference.
"""

from __future__ import annotations

from netsim.env import SimEnv
from netsim.io import Encoder
from netsim.plant import LTIPlant
from netsim.timebase import US

# x(t) = 0.3e-4 + 0.047 t leaves the band [0, 1e-4) at t = 0.7e-4 / 0.047 s = 1.4894 ms: the first 10 us
# tick after it is 1.49 ms
EDGE_TICK = 1_490_000


def _seen_at_edge_tick(mode: str) -> tuple[list, list]:
    env = SimEnv(seed=0)
    plant = LTIPlant([[0.0, 1.0], [0.0, 0.0]], [0.0, 1.0], [1.0, 0.0], None, x0=[0.3e-4, 0.047], name="cart")
    plant.bind(env)
    edges: list[tuple[int, int, int]] = []
    enc = Encoder(plant, 0, step=1e-4, tick_ns=10 * US, mode=mode)
    enc.start(env, lambda c, d, s: edges.append((c, d, s)))
    seen: list[tuple[int, int]] = []
    sim = env.sim
    # scheduled after the first prediction, before the input change re-predicts: its entry lies between them
    sim.call_at(EDGE_TICK, lambda: seen.append((sim.now, enc.count)))
    # an input too small to move the edge to another tick (0.5 * 1e-9 * (1 ms)^2 = 5e-16 m): same tick
    sim.call_at(500 * US, lambda: plant.set_input(0, 1e-9))
    sim.call_at(EDGE_TICK + 10 * US, lambda: seen.append((sim.now, enc.count)))
    env.run(3_000_000)
    return seen, edges


def test_a_kept_wake_up_runs_after_what_was_scheduled_for_its_instant_in_between():
    exact, exact_edges = _seen_at_edge_tick("exact")
    polled, polled_edges = _seen_at_edge_tick("polling")
    assert exact_edges[0] == (1, 1, EDGE_TICK)
    assert exact_edges == polled_edges
    # at the edge tick the reader runs before the ISR reports (count still 0), one tick later it sees 1
    assert polled == [(EDGE_TICK, 0), (EDGE_TICK + 10 * US, 1)]
    assert exact == polled
