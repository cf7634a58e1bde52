"""The H-infinity disturbance observer of Fig. 3 / eqs (16)-(17) (netsim.control.dob) on the HDD model."""

import numpy as np
import pytest

from netsim.control.dob import DisturbanceObserver, DobDesign, design_dob
from netsim.errors import BuildError, ConfigError

T = 20e-6


@pytest.fixture(scope="module")
def hdd():
    from netsim.models.hdd import hdd_model

    return hdd_model()


@pytest.fixture(scope="module")
def dob(hdd):
    return design_dob(hdd.Ap, hdd.Bp, hdd.Cp, hdd.controller_num, hdd.controller_den, hdd.T)


def _plant_dc_gain(m) -> float:
    # independent of the DOB code: G(1) = Cp (I - Ap)^-1 Bp
    return float((m.Cp @ np.linalg.solve(np.eye(m.Ap.shape[0]) - m.Ap, m.Bp))[0, 0])


def _weight_mag(f_hz, bandwidth=1000.0, dc_error=1e-2, peak=2.0) -> float:
    # |Wz(j w)| of the continuous weight (s/peak + wb)/(s + wb dc_error) (the Tustin warp is < 0.1 % here)
    w, wb = 2 * np.pi * f_hz, 2 * np.pi * bandwidth
    return abs((1j * w / peak + wb) / (1j * w + wb * dc_error))


def test_estimator_form_gives_a_stable_filter_and_a_stable_compensated_loop(dob):
    poles = np.abs(np.linalg.eigvals(dob.A))
    assert poles.max() < 1.0
    assert dob.filter_radius == pytest.approx(poles.max())
    assert dob.loop_radius < 1.0
    DisturbanceObserver(dob)  # the runtime check accepts it


def test_low_frequency_gains_are_minus_one_and_the_plant_inverse(dob, hdd):
    # Fig. 3 text: D1 close to -1, D2 close to G^-1. The H-infinity bound ||Wz (1 - D2 G)|| <= gamma
    # with |Wz| = 1/dc_error at DC gives |1 - D2 G| <= gamma * dc_error there.
    D1, D2 = dob.freq(1e-3)
    g0 = _plant_dc_gain(hdd)
    bound = dob.gamma * 1e-2 * 1.01
    assert abs(1.0 - D2 * g0) <= bound
    assert abs(D1 + 1.0) <= bound + 1e-3  # u-leak D1 + D2 G is in the u -> z channel, same bound
    assert dob.gamma < 1.5  # problem (17) solved with a modest gamma


def _simulate_open_loop(m, obs, u, d):
    x = np.zeros(m.Ap.shape[0])
    b, c = m.Bp[:, 0], m.Cp[0]
    dh = np.empty(len(u))
    u_prev = 0.0
    for k in range(len(u)):
        dh[k] = obs.step(u_prev, float(c @ x))
        x = m.Ap @ x + b * (u[k] + d[k])
        u_prev = u[k]
    return dh


def test_dob_estimates_a_step_disturbance_whatever_the_input(dob, hdd):
    n = 800
    rng = np.random.default_rng(3)
    u = 0.2 * np.sin(2 * np.pi * 200 * T * np.arange(n)) + 0.05 * rng.standard_normal(n)
    d = np.where(np.arange(n) >= 100, 0.1, 0.0)
    dh = _simulate_open_loop(hdd, DisturbanceObserver(dob), u, d)
    # before the step d = 0: the estimate must not follow the (arbitrary, broadband) input
    assert np.max(np.abs(dh[50:100])) < 0.02
    # 10 ms after the step: DC error bound gamma*dc_error*0.1 = 1e-3 plus the residual input leak
    assert np.max(np.abs(dh[600:] - 0.1)) < 3e-3


def test_dob_tracks_the_60hz_disturbance_of_eq32_in_closed_loop(dob, hdd):
    import control as ct

    Cz = ct.ss(ct.tf(hdd.controller_num, hdd.controller_den, T))
    Ac, Bc, Cc, Dc = (np.asarray(M, float) for M in (Cz.A, Cz.B, Cz.C, Cz.D))
    n = 3000  # 60 ms: several periods of the disturbance
    t = np.arange(n) * T
    # eq (32) is an oscillator at (2.8419 / T)^0.5 / (2 pi) = 60.0 Hz
    f = np.sqrt(2.8419 / T) / (2 * np.pi)
    d = 0.1 * np.sin(2 * np.pi * f * t)

    def loop(use_dob: bool):
        obs = DisturbanceObserver(dob)
        x, xc = np.zeros(hdd.Ap.shape[0]), np.zeros(Ac.shape[0])
        b, c = hdd.Bp[:, 0], hdd.Cp[0]
        y = np.empty(n)
        dh = np.zeros(n)
        u_prev = 0.0
        for k in range(n):
            y[k] = float(c @ x)
            e = -y[k]  # regulation, r = 0
            uc = float(Cc[0] @ xc + Dc[0, 0] * e)
            xc = Ac @ xc + Bc[:, 0] * e
            if use_dob:
                dh[k] = obs.step(u_prev, y[k])
            u = uc - dh[k]
            x = hdd.Ap @ x + b * (u + d[k])
            u_prev = u
        return y, dh

    y_dob, dh = loop(True)
    y_base, _ = loop(False)
    tail = slice(n // 2, n)
    rel_err = np.sqrt(np.mean((dh[tail] - d[tail]) ** 2) / np.mean(d[tail] ** 2))
    # H-infinity bound at 60 Hz: |1 - D2 G| <= gamma / |Wz(60 Hz)| (~0.062), plus a small u-leak
    assert rel_err < dob.gamma / _weight_mag(f) + 0.01
    # compensating the estimate reduces the output the disturbance causes
    assert np.sqrt(np.mean(y_dob[tail] ** 2)) < 0.5 * np.sqrt(np.mean(y_base[tail] ** 2))


def test_eq18_closed_loop_form_is_refused_because_its_filter_is_unstable(hdd):
    import re

    import netsim.models.hdd
    import netsim.control.dob

    with pytest.raises(BuildError, match="unstable") as err:
        design_dob(hdd.Ap, hdd.Bp, hdd.Cp, hdd.controller_num, hdd.controller_den, hdd.T, form="eq18")
    # the docstrings of models/hdd.py and netsim.control.dob quote the largest pole modulus of the eq (18)
    # filter: it must be the figure the error computes
    printed = re.search(r"largest pole modulus ([0-9.]+)", str(err.value)).group(1)
    for doc in (netsim.models.hdd.__doc__, netsim.control.dob.__doc__):
        assert re.search(r"largest pole modulus\s+([0-9.]+)", doc).group(1) == printed


def test_runtime_observer_refuses_an_unstable_filter():
    bad = DobDesign(np.array([[1.2]]), np.array([[1.0, 0.0]]), np.array([[1.0]]), np.zeros((1, 2)), T, 1.0)
    with pytest.raises(BuildError, match="unstable"):
        DisturbanceObserver(bad)


@pytest.mark.parametrize("kw", [{"dc_error": 1.5}, {"peak": 0.5}, {"bandwidth": 30000.0}, {"eps": 0.0},
                                {"form": "lft"}])
def test_bad_weights_are_config_errors(hdd, kw):
    with pytest.raises(ConfigError):
        design_dob(hdd.Ap, hdd.Bp, hdd.Cp, hdd.controller_num, hdd.controller_den, hdd.T, **kw)

