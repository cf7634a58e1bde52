"""ADC and DAC channels: sampling instant, noise, quantization, saturation, zero-order hold."""

from __future__ import annotations

import numpy as np
import pytest

from netsim.env import SimEnv
from netsim.errors import ConfigError
from netsim.io import ADC, DAC
from netsim.plant import LTIPlant
from netsim.timebase import MS, S


def _integrator(**kw) -> LTIPlant:
    return LTIPlant([[0.0]], [[1.0]], [[1.0]], None, **kw)


def test_adc_samples_the_output_at_the_request_instant():
    plant = _integrator(x0=[0.0])
    plant.set_input(0, 2.0, 0)
    adc = ADC(plant, 0)
    assert adc.read(250 * MS) == pytest.approx(0.5, rel=1e-14)
    assert adc.read(1 * S) == pytest.approx(2.0, rel=1e-14)


def test_adc_quantizes_to_the_nearest_step_and_saturates():
    plant = _integrator(x0=[0.0])
    plant.set_input(0, 1.0, 0)
    adc = ADC(plant, 0, quant_step=0.1, saturation=(-1.0, 0.5))
    assert adc.read(123 * MS) == pytest.approx(0.1)  # 0.123 -> 0.1
    assert adc.read(177 * MS) == pytest.approx(0.2)  # 0.177 -> 0.2
    assert adc.read(2 * S) == pytest.approx(0.5)  # saturated at the high limit


def test_adc_noise_has_the_requested_std_and_comes_from_a_named_stream():
    env = SimEnv(seed=9)
    plant = _integrator(x0=[3.0])
    plant.bind(env)
    adc = ADC(plant, 0, noise_std=0.2, name="y")
    vals = np.array([adc.read(0) for _ in range(20_000)])
    # sample std of 20000 Gaussians: relative standard error 1/sqrt(2N) = 0.5 %; 5 sigma bounds
    assert vals.std() == pytest.approx(0.2, rel=5 / np.sqrt(2 * 20_000))
    assert vals.mean() == pytest.approx(3.0, abs=5 * 0.2 / np.sqrt(20_000))
    ref = SimEnv(seed=9).rng("io.y.noise").standard_normal(3)
    np.testing.assert_allclose(vals[:3], 3.0 + 0.2 * ref, rtol=1e-15)


def test_dac_holds_saturated_and_rounded_value():
    plant = _integrator(x0=[0.0])
    dac = DAC(plant, 0, saturation=1.0, resolution=0.25)
    dac.write(0, 0.6)  # -> 0.5
    dac.write(1 * S, 5.0)  # -> 1.0 (saturated)
    assert plant.inputs[0] == 1.0
    # x(2 s) = 0.5 * 1 + 1.0 * 1
    assert plant.output(2 * S)[0] == pytest.approx(1.5, rel=1e-14)


def test_bad_channel_parameters_are_reported():
    plant = _integrator()
    with pytest.raises(ConfigError, match="saturation"):
        ADC(plant, 0, saturation=(1.0, -1.0))
    with pytest.raises(ConfigError, match="quant_step"):
        ADC(plant, 0, quant_step=-0.1)
    with pytest.raises(ConfigError, match="no output 'z'"):
        ADC(plant, "z")
    with pytest.raises(ConfigError, match="resolution"):
        DAC(plant, 0, resolution=0.0)
    with pytest.raises(ConfigError, match="noise needs an rng"):
        ADC(plant, 0, noise_std=1.0).read(0)


def test_exact_dac_holds_the_value_as_written_and_rejects_non_finite_values():
    from netsim.errors import SimulationError

    plant = _integrator(x0=[0.0])
    dac = DAC(plant, 0)  # no saturation, no resolution: the written value itself
    dac.write(0, 0.1 + 0.2)
    assert plant.inputs[0] == 0.1 + 0.2 == dac.last == dac.convert(0.1 + 0.2)
    with pytest.raises(SimulationError, match="non-finite"):
        dac.write(1 * MS, float("nan"))


def test_adc_read_equals_the_plant_output_at_each_instant():
    # an ADC without noise, saturation or quantization returns the plant output itself, also when several
    # reads fall on one instant and the input changes in between
    plant = LTIPlant([[-1.0]], [[1.0]], [[2.0]], [[0.5]], x0=[1.0])
    adc = ADC(plant, 0)
    for k, u in enumerate([0.0, 1.0, -3.0, 2.5]):
        t = k * 100 * MS
        assert adc.read(t) == adc.read(t) == float(plant.output(t)[0])
        plant.set_input(0, u, t)
        # after the write at t: 2 x(t) + 0.5 u, recomputed from the state
        assert adc.read(t) == pytest.approx(2.0 * plant.state(t)[0] + 0.5 * u, rel=1e-15)
