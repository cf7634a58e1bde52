"""Independent parts of an LTI plant propagated one at a time (issue 29, :mod:`netsim.plant.blocks`): a read or a
write advances only its own part, and every value equals the joint plant's (the same model propagated as one
block, computed in the test) to 1e-12."""

from __future__ import annotations

import numpy as np
import pytest

from netsim.errors import SimulationError
from netsim.models.dc_servo import dc_servo
from netsim.plant import LTIPlant, blocks
from netsim.plant.blocks import independent_parts
from netsim.timebase import MS, US


def _model() -> tuple[np.ndarray, ...]:
    """Four parts: two servos 1000/(s(s+1)) (outputs 0, 1), a coupled 2-state part with a feed-through (output 2,
    inputs 2 and 3), and a pure gain (output 3 = 0.5 u4, no state)."""
    A = np.zeros((6, 6))
    B = np.zeros((6, 5))
    C = np.zeros((4, 6))
    D = np.zeros((4, 5))
    for k in (0, 1):
        A[2 * k, 2 * k + 1], A[2 * k + 1, 2 * k + 1], B[2 * k + 1, k], C[k, 2 * k] = 1.0, -1.0, 1000.0, 1.0
    A[4:, 4:] = [[-2.0, 1.0], [-3.0, -0.5]]
    B[4:, 2:4] = [[1.0, 0.0], [0.5, 2.0]]
    C[2, 4:], D[2, 2] = [1.0, 0.3], 0.1
    D[3, 4] = 0.5
    return A, B, C, D


def test_independent_parts_are_the_connected_states_inputs_and_outputs():
    parts = independent_parts(*_model())
    got = [(list(x), list(u), list(y)) for x, u, y in parts]
    assert got == [([0, 1], [0], [0]), ([2, 3], [1], [1]), ([4, 5], [2, 3], [2]), ([], [4], [3])]


def _pair(monkeypatch) -> tuple[LTIPlant, LTIPlant]:
    joint = LTIPlant(*_model(), x0=[0.1, 0.0, -0.2, 0.3, 0.5, -0.5])
    monkeypatch.setattr(blocks, "MIN_BLOCKS", 2)
    parted = LTIPlant(*_model(), x0=[0.1, 0.0, -0.2, 0.3, 0.5, -0.5])
    parted.advance_to(0)
    monkeypatch.setattr(blocks, "MIN_BLOCKS", 10**9)
    joint.advance_to(0)
    assert parted._blocks is not None and joint._blocks is None
    return joint, parted


def test_parts_read_and_written_at_random_equal_the_joint_plant(monkeypatch):
    joint, parted = _pair(monkeypatch)
    rng = np.random.default_rng(5)
    t = 0
    for _ in range(600):
        t += int(rng.integers(0, 900)) * US  # repeated instants (0) too
        if rng.random() < 0.5:
            i = int(rng.integers(0, 4))
            want, got = joint.output_value(i, t), parted.output_value(i, t)
            assert got == pytest.approx(want, rel=1e-12, abs=1e-12)
        else:
            j, v = int(rng.integers(0, 5)), float(rng.uniform(-1, 1))
            joint.set_input(j, v, t)
            parted.set_input(j, v, t)
    t += 3 * MS
    assert parted.state(t) == pytest.approx(joint.state(t), rel=1e-12, abs=1e-12)  # every part brought to t
    assert parted.output(t) == pytest.approx(joint.output(t), rel=1e-12, abs=1e-12)
    assert np.array_equal(parted.inputs, joint.inputs)


def test_a_read_advances_only_its_own_part(monkeypatch):
    _, parted = _pair(monkeypatch)
    parted.output_value(1, 7 * MS)
    parted.set_input(2, 1.0, 9 * MS)
    assert parted._blocks.times.tolist() == [0, 7 * MS, 9 * MS, 0]
    assert parted.transition_cache_info()["expm"] == 0  # no exponential of the joint model
    assert parted._blocks.expm_count == 2  # one per part and step length


def test_identical_servos_share_their_transitions():
    plant = dc_servo(count=40)  # 40 parts >= MIN_BLOCKS: propagated one at a time
    for k in range(40):
        plant.set_input(k, 1.0 + k, 0)
    for k in range(40):
        plant.output_value(k, 5 * MS)
    assert plant._blocks is not None and plant._blocks.expm_count == 1


@pytest.mark.parametrize("n", [12, 80])  # parts grouped in Python (fewer than 64 behind) and by numpy
def test_a_full_advance_of_many_parts_equals_the_joint_plant(monkeypatch, n):
    # a record grid every 1 ms between reads and writes of a few servos: most parts share one step length at
    # each grid sample (one batched product), those read or written since take their own
    monkeypatch.setattr(blocks, "MIN_BLOCKS", 2)
    parted = dc_servo(count=n)
    parted.advance_to(0)
    monkeypatch.setattr(blocks, "MIN_BLOCKS", 10**9)
    joint = dc_servo(count=n)
    assert parted._blocks is not None and joint._blocks is None
    rng = np.random.default_rng(n)
    for plant in (parted, joint):
        plant.set_inputs(np.linspace(-1.0, 1.0, n), 0)
    for ms in range(1, 60):
        t = ms * MS
        for dt in sorted(int(d) * US for d in rng.integers(0, 900, 3)):
            i = int(rng.integers(0, n))
            v = float(rng.uniform(-1, 1))
            assert parted.output_value(i, t - MS + dt) == pytest.approx(joint.output_value(i, t - MS + dt),
                                                                         rel=1e-12, abs=1e-12)
            parted.set_input(i, v, t - MS + dt)
            joint.set_input(i, v, t - MS + dt)
        assert parted.output(t) == pytest.approx(joint.output(t), rel=1e-12, abs=1e-12)  # every part brought to t
    assert parted.state() == pytest.approx(joint.state(), rel=1e-12, abs=1e-12)


def test_an_exact_encoder_listener_brings_every_part_to_one_instant(monkeypatch):
    joint, parted = _pair(monkeypatch)
    for plant in (joint, parted):
        plant.set_input(0, 0.5, 2 * MS)
        plant.output_value(2, 5 * MS)
        plant.on_input_change(lambda t: None)
    assert parted._blocks is None
    assert parted.state(8 * MS) == pytest.approx(joint.state(8 * MS), rel=1e-12, abs=1e-12)


def test_a_plant_with_a_disturbance_or_few_parts_propagates_jointly():
    few = dc_servo(count=3)  # the shipped three-servo scenarios: joint, as they were pinned
    few.output_value(0, 1 * MS)
    assert few._blocks is None
    disturbed = dc_servo(count=40)
    disturbed.add_disturbance(0, 0.1)
    disturbed.output_value(0, 1 * MS)
    assert disturbed._blocks is None


def test_a_part_read_before_the_latest_access_is_refused_as_on_the_joint_plant(monkeypatch):
    joint, parted = _pair(monkeypatch)
    messages = []
    for plant in (joint, parted):
        plant.output_value(0, 5 * MS)
        with pytest.raises(SimulationError, match="time cannot go backwards") as info:
            plant.output_value(1, 4 * MS)  # another part, but before the plant's latest instant
        messages.append(str(info.value))
    assert messages[0] == messages[1]


def _loops(n: int) -> dict:
    """n DC servo loops (count: n), each sampled every 10 ms by its own node and controlled over one CAN bus."""
    nodes: dict = {}
    io: dict = {}
    for i in range(1, n + 1):
        io[f"y{i}"], io[f"u{i}"] = {"type": "adc", "output": f"y{i}"}, {"type": "dac", "input": f"u{i}"}
        nodes[f"s{i}"] = {"policy": "dm", "tasks": [{
            "name": "sample", "program": "sampler", "period": "10 ms", "execution": "0.1 ms",
            "params": {"channel": f"y{i}", "network": "can", "to": f"c{i}", "bits": 80, "priority": 2 * i,
                       "tag": "y"}}]}
        nodes[f"c{i}"] = {"policy": "dm", "tasks": [{
            "name": "control", "program": "controller", "release": "on_message:can", "deadline": "10 ms",
            "execution": "0.1 ms", "params": {"input_network": "can", "output_channel": f"u{i}", "reference": "r", "K": 1.0,
                                               "Td": 0.04, "N": 100, "h": "10 ms", "record_as": f"u{i}"}}]}
    return {"name": "loops", "seed": 1, "duration": "0.5 s",
            "plant": {"model": "dc_servo", "params": {"gain": 1000, "a": 1, "count": n}},
            "io": io, "signals": {"r": {"type": "square", "amplitude": 1.0, "period": "0.2 s"}}, "nodes": nodes,
            "networks": {"can": {"type": "can", "nodes": list(nodes), "bitrate": "1 Mbit/s"}},
            "record": [f"u{i}" for i in range(1, n + 1)]}


def test_a_run_of_independent_loops_equals_the_joint_plants_run(monkeypatch):
    import netsim

    made = []
    monkeypatch.setattr(blocks, "MIN_BLOCKS", 2)  # 8 servos propagated one at a time
    monkeypatch.setattr(blocks.Blocks, "sync", lambda self, t, zu, f=blocks.Blocks.sync: made.append(t) or f(self, t, zu))
    parted = netsim.run(_loops(8), write=False)
    assert made  # the run went through the parts (the end of the run brings them all to one instant)
    monkeypatch.setattr(blocks, "MIN_BLOCKS", 10**9)
    joint = netsim.run(_loops(8), write=False)
    assert parted.status == joint.status == "ok"
    names = [f"u{i}" for i in range(1, 9)]
    a, b = parted.signals[names].to_numpy(), joint.signals[names].to_numpy()
    assert a.shape == b.shape and np.nanmax(np.abs(b)) > 0.1  # a wide table: NaN where a signal has no sample
    assert np.array_equal(np.isnan(a), np.isnan(b))
    assert np.allclose(a, b, rtol=1e-12, atol=1e-12, equal_nan=True)
