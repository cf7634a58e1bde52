"""The control side computes its h-step cascade lazily: the results must equal those of full evaluation."""

import numpy as np
import pytest

from netsim.control import ControllerTrigger, ControlSide, MixedTrigger, MrciController, Numre, decompose
from netsim.control.cascade import CascadeActions
from netsim.control.packets import ControlPacket, PlayoutBuffer

# a lightly damped 2nd-order plant at the fast rate and a PI-like controller with a lead (as in test_control_side)
AP = np.array([[1.0, 0.01], [-0.05, 0.97]])
BP = np.array([[0.0], [0.01]])
CP = np.array([[1.0, 0.0]])
CNUM = np.polymul([2.0, -1.9], [1.0, -0.5])
CDEN = np.polymul([1.0, -1.0], [1.0, 0.2])


def _trace(force: bool, h: int, sigma_c: float, n: int = 400):
    """Closed loop with the ideal timing of reference_loop; ``force`` evaluates every packet in full at once."""
    ctrl = MrciController(decompose(CNUM, CDEN, m=1, n_slow=1))
    est = Numre(AP, BP, CP, BP, [[1e-4]], [[1e-4]], h=h)
    side = ControlSide(ctrl, lambda k: 1.0 if k < 200 else -0.5, estimator=est,
                       trigger=ControllerTrigger(sigma_c, sigma_c))
    sensor = MixedTrigger(0.0, 2e-3)
    act = PlayoutBuffer()
    x = np.zeros(2)
    out = []
    for k in range(n):
        y = float(CP[0] @ x)
        if sensor.should_send(k, y):
            dec = side.on_measurement(k, y)
            full = tuple(dec.packet.values) if force else None
            if dec.send:
                act.receive(dec.packet)
            out.append((k, dec.N, dec.send, dec.y_hat, dec.d_hat, dec.packet.values[0], full))
        u = act.value(k)
        out.append(("u", k, u))
        x = AP @ x + BP[:, 0] * u
    return out, side


@pytest.mark.parametrize("h,sigma_c", [(50, 0.0), (50, 0.05), (3, 0.02)])
def test_lazy_cascade_gives_the_same_loop_as_full_evaluation(h, sigma_c):
    lazy, side_l = _trace(False, h, sigma_c)
    eager, side_e = _trace(True, h, sigma_c)
    strip = [tuple(e[:-1]) if e[0] != "u" else e for e in eager]
    assert [tuple(e[:-1]) if e[0] != "u" else e for e in lazy] == strip  # bit-identical floats
    assert side_l.horizon_violations == side_e.horizon_violations
    assert side_l.N_max == side_e.N_max
    assert any(not e[2] for e in eager if e[0] != "u") == (sigma_c > 0)  # held-back packets were exercised


def test_cascade_actions_behave_like_the_tuple_of_values():
    ctrl = MrciController(decompose(CNUM, CDEN, m=1, n_slow=1))
    est = Numre(AP, BP, CP, BP, [[1e-4]], [[1e-4]], h=5)
    side = ControlSide(ctrl, lambda k: 1.0, estimator=est)
    vals = side.on_measurement(0, 0.0).packet.values
    assert isinstance(vals, CascadeActions)
    assert len(vals) == 6
    as_tuple = tuple(vals)
    assert vals == as_tuple and hash(vals) == hash(as_tuple)
    assert vals[-1] == as_tuple[5] and vals[1:3] == as_tuple[1:3]
    with pytest.raises(IndexError):
        vals[6]
    assert ControlPacket(0, vals).value_at(100) == as_tuple[-1]  # held last value past the horizon
