"""MRCI: partial-fraction decomposition, eq (19) conversion, interlacing, eq (20)."""

import numpy as np
import pytest
import scipy.signal as sps

from netsim.control import MrciController, computation_saving, decompose
from netsim.errors import ConfigError

# eq (33) of Cuenca et al.
NUM = 1.0882 * np.poly([0.9813, 0.9681, -1.0])
DEN = np.poly([1.0, 0.8496, 0.6137])


def test_decomposition_of_eq33_matches_printed_eq34():
    d = decompose(NUM, DEN, m=2)
    (n1, d1), (n2, d2) = d.slow_tf(0), d.slow_tf(1)
    # eq (34): Cs1 = 0.04484/(z^2-1), Cs2 = -1.6365/(z^2-0.7218); printed values carry the rounding of
    # eq (33)'s four-digit roots, so compare within 0.5 %
    assert d1 == pytest.approx([1.0, -1.0], abs=1e-9)
    assert n1[-1] == pytest.approx(0.04484, rel=5e-3)
    assert d2 == pytest.approx([1.0, -0.7218], abs=1e-4)
    assert n2[-1] == pytest.approx(-1.6365, rel=5e-3)
    nf, df = d.fast_tf()  # Cf1 = (1.0882 z + 1.84)/(z - 0.6137)
    assert nf == pytest.approx([1.0882, 1.84], rel=5e-3)
    assert df == pytest.approx([1.0, -0.6137], abs=1e-9)
    assert d.computation_saving == pytest.approx(1 / 3)  # eq (20): (2-1)/(2+1) -> CS = 33 %


def test_eq19_lifts_a_first_order_mode_by_hand():
    # r/(z-p) with m=2 -> r(1+p)/(z^2-p^2)
    d = decompose([3.0], [1.0, -0.5], m=1, n_slow=1)
    lifted = d.slow[0].lifted(2)
    num, den = lifted.tf()
    assert den == pytest.approx([1.0, -0.25])  # in powers of z^m: z^2 - 0.25
    assert num[-1] == pytest.approx(3.0 * 1.5)


def test_mrci_with_ratio_one_reproduces_the_original_controller():
    d = decompose(NUM, DEN, m=1, n_slow=2)
    ctrl = MrciController(d)
    e = np.sin(0.3 * np.arange(60)) + 1.0
    u = [ctrl.step(k, ek) for k, ek in enumerate(e)]
    ref = sps.lfilter(NUM, DEN, e)  # independent: direct-form filtering of C(z)
    assert np.allclose(u, ref, atol=1e-9)


def test_interlaced_slow_modes_update_on_their_phase_only():
    # C(z) = 1/(z-1) + 1/(z-0.5), m=2: mode 1 (pole 1) lifted 2/(z^2-1) updated at even k;
    # mode 2 (pole .5) lifted 1.5/(z^2-.25) updated at odd k; constant e=1. Hand sequence:
    # k0: u=0 (x1->2) ; k1: u=0 (x2->1.5) ; k2: u=2 (x1->4) ; k3: u=2+1.5 ; k4: u=4+1.5
    num = np.polyadd([1.0, -0.5], [1.0, -1.0])
    den = np.polymul([1.0, -1.0], [1.0, -0.5])
    ctrl = MrciController(decompose(num, den, m=2))
    assert [ctrl.step(k, 1.0) for k in range(5)] == pytest.approx([0.0, 0.0, 2.0, 3.5, 5.5])


def test_snapshot_restore_replays_identically():
    ctrl = MrciController(decompose(NUM, DEN, m=2))
    for k in range(7):
        ctrl.step(k, 1.0)
    s = ctrl.snapshot()
    a = [ctrl.step(k, 0.3) for k in range(7, 12)]
    ctrl.restore(s)
    assert [ctrl.step(k, 0.3) for k in range(7, 12)] == a


def test_ratio_not_dividing_the_slow_modes_is_refused():
    with pytest.raises(ConfigError, match="does not divide"):
        decompose(NUM, DEN, m=2, n_slow=3)
    with pytest.raises(ConfigError, match="repeated pole"):
        decompose([1.0], np.poly([0.5, 0.5]), m=1)


def test_computation_saving_formula():
    assert computation_saving(2, 1) == pytest.approx(1 / 3)
    assert computation_saving(3, 2) == pytest.approx(2 / 5)


def _two_first_order_modes():
    # C(z) = 1/(z-1) + 1/(z-0.5), m=2: mode 1 (pole 1) lifted 2/(z^2-1), phase 0 (even k);
    # mode 2 (pole 0.5) lifted 1.5/(z^2-0.25), phase 1 (odd k).
    num = np.polyadd([1.0, -0.5], [1.0, -1.0])
    den = np.polymul([1.0, -1.0], [1.0, -0.5])
    return decompose(num, den, m=2)


def test_delayed_wiring_feeds_mode_two_the_downsampled_error_of_the_even_instant():
    # Section 3.2.3: down-sample e at k = 2j, delay z^-(i-1). Impulse e = [1, 0, 0, 0, 0], by hand:
    # mode 1: k0 out 0, x1 = 2; k2 out 2, x1 = 2 (e2 = 0); k4 out 2.
    # mode 2 (delayed): k1 sees e0 = 1: out 0, x2 = 1.5; k3 sees e2 = 0: out 1.5, x2 = 0.375.
    # u = mode 1 held + mode 2 held = [0, 0, 2, 3.5, 3.5]
    ctrl = MrciController(_two_first_order_modes(), wiring="delayed")
    e = [1.0, 0.0, 0.0, 0.0, 0.0]
    assert [ctrl.step(k, ek) for k, ek in enumerate(e)] == pytest.approx([0.0, 0.0, 2.0, 3.5, 3.5])


def test_own_instant_wiring_feeds_mode_two_its_own_error():
    # same impulse: mode 2 sees e1 = 0 and e3 = 0, so it never moves: u = mode 1 only = [0, 0, 2, 2, 2]
    ctrl = MrciController(_two_first_order_modes(), wiring="own_instant")
    e = [1.0, 0.0, 0.0, 0.0, 0.0]
    assert [ctrl.step(k, ek) for k, ek in enumerate(e)] == pytest.approx([0.0, 0.0, 2.0, 2.0, 2.0])


def test_delayed_wiring_is_the_default_and_unknown_wirings_are_refused():
    assert MrciController(_two_first_order_modes()).wiring == "delayed"
    with pytest.raises(ConfigError, match="wiring must be one of"):
        MrciController(_two_first_order_modes(), wiring="late")
