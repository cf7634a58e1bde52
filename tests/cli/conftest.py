"""Fake plugins for the CLI tests (registered under ``zzc_*`` names no real plugin uses) and a valid scenario
using them (fixture ``good``: its YAML text)."""

from __future__ import annotations

import textwrap

import pytest
from pydantic import Field

from netsim.registry import register
from netsim.units import Bitrate, StrictModel


@register("plant", "zzc_plant", "cli test plant")
class ZzcPlant:
    output_names = ["y"]
    input_names = ["u"]

    class Params(StrictModel):
        gain: float = 1.0


@register("program", "zzc_prog", "cli test program")
class ZzcProg:
    class Params(StrictModel):
        network: str | None = None
        to: str | None = None
        bits: int = Field(default=8, gt=0)


@register("network", "zzc_net", "cli test network")
class ZzcNet:
    class Params(StrictModel):
        nodes: list[str]
        bitrate: Bitrate = 1e6


GOOD = textwrap.dedent(
    """\
    name: zzc_good
    duration: 1 s
    plant: {model: zzc_plant, x0: [0]}
    nodes:
      a:
        policy: fp
        tasks:
          - name: send
            program: zzc_prog
            params: {network: net, to: b}
            period: 10 ms
            priority: 1
            execution: 1 ms
      b:
        policy: edf
        tasks:
          - name: recv
            program: zzc_prog
            release: on_message:net
    networks:
      net: {type: zzc_net, nodes: [a, b], bitrate: 80 kbit/s}
    """
)


@pytest.fixture
def good() -> str:
    """YAML text of a valid two-node scenario using only the fake plugins."""
    return GOOD
