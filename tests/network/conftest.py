"""Helpers for the network tests: fake receivers and a one-call network builder (no kernel needed)."""

from __future__ import annotations

from typing import Any, Callable

import pytest

from netsim.env import SimEnv
from netsim.network import Message, Network, make_network


class FakeReceiver:
    """Records every delivery as (time_ns, msg)."""

    def __init__(self, env: SimEnv, node: str) -> None:
        self.env = env
        self.node = node
        self.got: list[tuple[int, Message]] = []

    def deliver(self, network: str, msg: Message) -> None:
        assert msg.receiver == self.node
        self.got.append((self.env.now, msg))


class Bench:
    """A network under test with a fake receiver on every node."""

    def __init__(self, type_name: str, params: dict[str, Any], seed: int = 0, name: str = "net") -> None:
        self.env = SimEnv(seed=seed)
        self.net: Network = make_network(self.env, name, type_name, params)
        self.rx = {n: FakeReceiver(self.env, n) for n in params["nodes"]}
        for n, r in self.rx.items():
            self.net.attach(n, r)

    def send_at(self, t_ns: int, sender: str, receiver: str | None, bits: int, priority: int = 0,
                tag: str = "") -> None:
        """Send a message at ``t_ns`` from a simpy process (as a kernel would)."""

        def proc():
            yield self.env.timeout(t_ns)
            self.net.send(Message(sender, receiver, None, bits, priority, tag=tag))

        self.env.process(proc())

    def run(self, until_ns: int) -> "Bench":
        self.env.run(until_ns)
        return self

    def deliveries(self, node: str) -> list[tuple[int, str]]:
        """(time, tag) of everything ``node`` received, in order."""
        return [(t, m.tag) for t, m in self.rx[node].got]

    def record(self, tag: str):
        recs = [r for r in self.net.records if r.tag == tag]
        assert len(recs) == 1, f"{len(recs)} records tagged {tag!r}"
        return recs[0]


@pytest.fixture
def bench() -> Callable[..., Bench]:
    """``bench(type_name, params, seed=0, name="net") -> Bench``."""
    return Bench
