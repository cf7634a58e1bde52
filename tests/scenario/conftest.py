"""Fake plugins for the scenario tests (registered under ``zzt_*`` names no real plugin uses) and a valid
scenario built from them (fixture ``base``: a function returning a fresh copy)."""

from __future__ import annotations

import copy
from typing import Any

import pytest
from pydantic import Field

from netsim.registry import register
from netsim.units import Bitrate, Duration, StrictModel, Time


@register("plant", "zzt_plant", "test plant: two inputs (u, d), one output (y)")
class ZztPlant:
    """A plant factory that declares its ports cheaply (no build needed)."""

    input_names = ["u", "d"]
    output_names = ["y"]

    class Params(StrictModel):
        gain: float = 1.0
        pole: float = Field(default=1.0, gt=0)


@register("program", "zzt_sampler", "test program: sample a channel, send it")
class ZztSampler:
    class Params(StrictModel):
        channel: str
        network: str | None = None
        to: str | None = None
        bits: int = Field(default=80, gt=0)
        hold: Time = 0


@register("program", "zzt_actuator", "test program: receive, write a channel")
class ZztActuator:
    class Params(StrictModel):
        network: str
        out_channel: str = "u"
        reference: str | None = None


@register("program", "zzt_idle", "test program without a Params model")
class ZztIdle:
    pass


@register("network", "zzt_bus", "test network")
class ZztBus:
    class Params(StrictModel):
        nodes: list[str]
        bitrate: Bitrate = 1_000_000.0
        min_frame_bits: int = Field(default=0, ge=0)
        slot: Duration | None = None


@register("signal", "zzt_step", "test signal")
class ZztStep:
    class Params(StrictModel):
        value: float = 1.0
        at: Time = 0


@register("metric", "zzt_error", "test metric")
def zzt_error(result: Any, params: dict, baseline: Any = None) -> dict[str, float]:
    return {}


zzt_error.Params = type("Params", (StrictModel,), {"__annotations__": {"reference": str}})  # type: ignore[attr-defined]


BASE: dict[str, Any] = {
    "name": "zzt_loop",
    "duration": "1 s",
    "plant": {"model": "zzt_plant", "params": {"gain": 2.0}},
    "io": {
        "y": {"type": "adc", "output": 0},
        "u": {"type": "dac", "input": "u"},
    },
    "signals": {"r": {"type": "zzt_step", "value": 0.5, "at": "0.1 s"}},
    "nodes": {
        "sensor": {
            "policy": "fp",
            "tasks": [
                {
                    "name": "sample",
                    "program": "zzt_sampler",
                    "params": {"channel": "y", "network": "bus", "to": "controller"},
                    "period": "10 ms",
                    "priority": 1,
                    "execution": "0.5 ms",
                }
            ],
        },
        "controller": {
            "policy": "edf",
            "tasks": [
                {
                    "name": "ctl",
                    "program": "zzt_idle",
                    "release": "on_message:bus",
                    "deadline": "5 ms",
                    "execution": {"dist": "uniform", "low": "0.4 ms", "high": "0.6 ms"},
                }
            ],
        },
        "actuator": {
            "policy": "fp",
            "handlers": [
                {
                    "name": "act",
                    "program": "zzt_actuator",
                    "params": {"network": "bus", "reference": "r"},
                    "trigger": {"on_message": "bus"},
                    "execution": "20 us",
                }
            ],
        },
    },
    "networks": {"bus": {"type": "zzt_bus", "nodes": ["sensor", "controller", "actuator"], "bitrate": "80 kbit/s"}},
    "record": ["y", "u", "r"],
    "metrics": [{"type": "zzt_error", "params": {"reference": "r"}}],
}


def make_base() -> dict[str, Any]:
    """A fresh copy of a valid scenario using only the fake plugins."""
    return copy.deepcopy(BASE)


@pytest.fixture
def base() -> Any:
    """A function returning a fresh copy of a valid scenario that uses only the fake plugins."""
    return make_base
