"""The HDD benchmark model (eqs 30-33, Table 2) and the readings documented in models/hdd.py."""

import numpy as np
import pytest

from netsim.models.hdd import T_HDD, closed_loop_radius, hdd_model


def test_plant_is_tenth_order_and_has_the_expected_dc_gain():
    m = hdd_model()
    assert m.Ap.shape == (10, 10)
    # independent DC gain: rigid body 7.153e6/1.011e6, unit resonances, notches at z=1 (swapped notch 1,
    # identity notch 2)
    w1 = 2 * np.pi * 5000 * T_HDD
    notch1 = (1 - 2 * 0.975 * np.cos(w1) + 0.975**2) / (1 - 2 * 0.965 * np.cos(w1) + 0.965**2)
    dc = (m.Cp @ np.linalg.solve(np.eye(10) - m.Ap, m.Bp))[0, 0]
    assert dc == pytest.approx(7.153e6 / 1.011e6 * notch1, rel=1e-6)


def test_controller_eq33_stabilizes_the_plant():
    assert closed_loop_radius(hdd_model()) < 1.0


def test_disturbance_model_is_a_60hz_oscillator():
    m = hdd_model()
    lam = np.linalg.eigvals(m.Ad)
    f = abs(np.angle(lam[0])) / (2 * np.pi * T_HDD)
    assert f == pytest.approx(60.0, abs=0.05)  # 2.8419 = (2 pi 60)^2 * 20e-6 (to 4 digits)
    assert hdd_model(ad12=0.0).Ad[0, 1] == 0.0  # the print itself stays available


def test_augmented_model_follows_eq3():
    m = hdd_model()
    A = m.A
    assert A.shape == (12, 12)
    assert A[:10, 10:] == pytest.approx(m.Bp @ m.Cd)
    assert m.Cbar[0, 10:] == pytest.approx(m.Cd[0])


def test_notch_gain_at_5khz_quoted_in_the_docstring():
    # independent: |N1(e^{jwT})| of eq (31) at w = 2 pi 5 kHz, zeros alpha_1 = 0.965, poles beta_1 = 0.975
    import re

    import netsim.models.hdd

    z = np.exp(1j * 2 * np.pi * 5000 * T_HDD)
    c = np.cos(2 * np.pi * 5000 * T_HDD)
    gain_db = 20 * np.log10(abs((z * z - 2 * 0.965 * c * z + 0.965**2) / (z * z - 2 * 0.975 * c * z + 0.975**2)))
    quoted = [float(x) for x in re.findall(r"([+-][0-9.]+) dB \*peak\* at 5 kHz", netsim.models.hdd.__doc__)]
    assert quoted == [pytest.approx(gain_db, abs=0.005)]
    assert f"-{gain_db:.2f} dB notch at 5 kHz" in " ".join(netsim.models.hdd.__doc__.split())
