"""Builder: a scenario becomes kernels, programs, channels, networks and triggers wired as the YAML says."""

import math

import numpy as np
import pytest

from netsim.errors import BuildError
from netsim.registry import register
from netsim.build.builder import build
from netsim.scenario.loader import load_scenario
from netsim.units import StrictModel

MS = 1_000_000


@register("program", "test_builder_probe", "test helper: records job.now and an optional analog input")
class Probe:
    class Params(StrictModel):
        channel: str | None = None
        label: str = "probe"

    def __init__(self, ctx, params):
        self.ctx, self.p = ctx, params

    def __call__(self, job):
        value = job.now
        if self.p.channel is not None:
            value = yield job.analog_in(self.p.channel)
        if "net" in job.kernel.networks:
            msg = yield job.receive("net")
            if msg is not None:
                value = msg.payload
        self.ctx.record(self.p.label, value, job.now)
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)


def _base(**extra):
    sc = {"name": "t", "duration": "10 ms",
          "plant": {"model": "dc_servo", "x0": [0.25, 0.0]},
          "io": {"y": {"type": "adc", "output": 0}, "u": {"type": "dac", "input": 0}}}
    sc.update(extra)
    return sc


def test_timer_handler_runs_at_its_period_and_reads_the_shared_adc_with_x0():
    sim = build(load_scenario(_base(nodes={
        "a": {"handlers": [{"name": "tick", "program": "test_builder_probe", "params": {"channel": "y", "label": "ya"},
                            "trigger": {"timer": {"period": "2 ms", "start": "1 ms"}}}]},
        "b": {"tasks": [{"name": "t", "program": "test_builder_probe", "params": {"channel": "y", "label": "yb"},
                         "period": "5 ms", "priority": 1}]},
    })))
    sim.run()
    rec = sim.env.recorder
    assert rec.times["ya"] == [1 * MS, 3 * MS, 5 * MS, 7 * MS, 9 * MS]
    assert rec.times["yb"] == [0, 5 * MS, 10 * MS]  # events at the end instant run too
    # no input: the servo stays at its initial angle x0[0] = 0.25 on both nodes' ADC
    assert rec.values["ya"] == [0.25] * 5 and rec.values["yb"] == [0.25] * 3


def test_on_message_bindings_release_task_and_invoke_handler():
    sc = _base(nodes={
        "s": {"tasks": [{"name": "send", "program": "sampler", "period": "4 ms", "priority": 1, "execution": "1 ms",
                         "params": {"channel": "y", "network": "net", "to": "all", "bits": 8}}]},
        "t": {"tasks": [{"name": "got", "program": "test_builder_probe", "release": "on_message:net",
                         "priority": 1, "params": {"label": "task_rx"}}]},
        "h": {"handlers": [{"name": "rx", "program": "test_builder_probe", "trigger": {"on_message": "net"},
                            "params": {"label": "handler_rx"}}]},
    }, networks={"net": {"type": "ideal", "nodes": ["s", "t", "h"]}})
    sim = build(load_scenario(sc))
    sim.run()
    rec = sim.env.recorder
    # broadcast at the end of each 1 ms execution (1, 5, 9 ms), zero-delay ideal network
    assert rec.times["task_rx"] == [1 * MS, 5 * MS, 9 * MS]
    assert rec.times["handler_rx"] == [1 * MS, 5 * MS, 9 * MS]
    assert rec.values["task_rx"] == [0.25] * 3


def test_step_disturbance_on_the_plant_input_matches_the_closed_form():
    sc = _base(signals={"d": {"type": "step", "at": "2 ms", "value": 0.01}}, record=["y"])
    sc["plant"]["disturbances"] = {0: "d"}
    sc["plant"]["x0"] = None
    sc["plant"]["record_grid"] = "1 ms"
    sim = build(load_scenario(sc))
    sim.run()
    t = 10 * MS
    y = float(sim.plant.output(t)[0])
    # 1000/(s(s+1)) from rest under a step c at t0: y = 1000 c (tau - 1 + e^-tau), tau = t - t0
    tau = (t - 2 * MS) / 1e9
    assert y == pytest.approx(1000 * 0.01 * (tau - 1 + math.exp(-tau)), rel=1e-9)


def test_recorded_reference_is_sampled_at_its_jumps_only():
    sc = _base(signals={"r": {"type": "square", "period": "4 ms"}}, record=["r"])
    sim = build(load_scenario(sc))
    sim.run()
    assert sim.env.recorder.times["r"] == [0, 2 * MS, 4 * MS, 6 * MS, 8 * MS, 10 * MS]
    assert sim.env.recorder.values["r"] == [1.0, -1.0, 1.0, -1.0, 1.0, -1.0]


def test_program_that_cannot_be_built_gives_build_error_with_yaml_path():
    sc = _base(nodes={"c": {"tasks": [{"name": "ctl", "program": "controller", "release": "aperiodic", "priority": 1,
                                       "params": {"channel": "y", "output_channel": "u", "K": 1.0}}]}})
    # validate refuses it first (it makes the same check build makes: an aperiodic PID needs its sampling period h)
    from netsim.scenario import ScenarioError
    from netsim.scenario.schema import Scenario

    with pytest.raises(ScenarioError) as refused:
        load_scenario(sc)
    assert [p.path for p in refused.value.errors] == ["nodes.c.tasks[0].params"]
    # build, given the unvalidated scenario, still names the task in its BuildError
    with pytest.raises(BuildError) as err:
        build(Scenario.model_validate(sc))
    assert err.value.path == "nodes.c.tasks[0]"
    assert "h" in err.value.message


def test_the_builder_takes_only_a_validated_scenario_and_names_the_loading_build():
    # loading validates by building, so the builder never loads (no import circle, tests/test_house.py);
    # netsim.scenario.build is the one that takes a file or a dict
    from pathlib import Path

    from netsim.scenario import build as build_from_source
    from netsim.build.builder import build as build_scenario

    with pytest.raises(TypeError, match="netsim.scenario.build"):
        build_scenario({"name": "x"})
    sim = build_from_source(str(Path(__file__).resolve().parents[2] / "scenarios" / "dc_servo_ideal.yaml"))
    assert type(sim).__name__ == "Simulation"
