"""Fake plugins and helpers for the CLI tests (registered under ``zzc_*`` names no real plugin uses)."""

from __future__ import annotations

import textwrap
from pathlib import Path

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


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


def line_of(path: Path, needle: str) -> int:
    """1-based line of the first line containing ``needle`` (independent of the loader)."""
    for i, line in enumerate(path.read_text().splitlines(), start=1):
        if needle in line:
            return i
    raise AssertionError(needle)
