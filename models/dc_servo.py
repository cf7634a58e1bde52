"""TrueTime's classic DC servo, G(s) = gain / (s (s + a)) with gain = 1000, a = 1.

Registered as plant ``dc_servo``. With ``count > 1`` the plant is ``count`` independent servos in one
block-diagonal LTI system (as in TrueTime's "three servos on one CPU" example), with inputs ``u1..un`` and
outputs ``y1..yn``; with ``count = 1`` the input is ``u`` and the output ``y``.

States per servo, in this order: angle ``theta`` (the output) and angular velocity ``omega``::

    theta' = omega
    omega' = -a omega + gain u
    y      = theta

which is a minimal realisation of ``gain / (s (s + a))`` (``tests/models/test_dc_servo.py`` checks it
against python-control's transfer function).

Examples
--------
>>> plant = dc_servo(DcServoParams())               # doctest: +SKIP
"""

from __future__ import annotations

import numpy as np

from netsim.registry import register
from netsim.units import StrictModel

__all__ = ["DcServoParams", "dc_servo", "dc_servo_matrices"]


class DcServoParams(StrictModel):
    """Parameters of the DC servo plant."""

    gain: float = 1000.0
    a: float = 1.0
    count: int = 1


def dc_servo_matrices(gain: float = 1000.0, a: float = 1.0, count: int = 1) -> tuple[np.ndarray, ...]:
    """State-space matrices ``(A, B, C, D)`` of ``count`` independent servos ``gain / (s (s + a))``."""
    if count < 1:
        raise ValueError(f"count must be >= 1, got {count}")
    a1 = np.array([[0.0, 1.0], [0.0, -float(a)]])
    b1 = np.array([[0.0], [float(gain)]])
    c1 = np.array([[1.0, 0.0]])
    A = np.kron(np.eye(count), a1)
    B = np.kron(np.eye(count), b1)
    C = np.kron(np.eye(count), c1)
    D = np.zeros((count, count))
    return A, B, C, D


@register("plant", "dc_servo", "TrueTime's DC servo gain/(s(s+a)), 1000/(s(s+1)) by default; count servos")
def dc_servo(params: DcServoParams | None = None, **kwargs: object):  # -> netsim.plant.LTIPlant
    """Build the DC servo plant (an :class:`netsim.plant.LTIPlant`) from its parameters."""
    from netsim.plant import LTIPlant

    p = params if params is not None else DcServoParams.model_validate(kwargs)
    A, B, C, D = dc_servo_matrices(p.gain, p.a, p.count)
    if p.count == 1:
        inputs, outputs, states = ["u"], ["y"], ["theta", "omega"]
    else:
        inputs = [f"u{i + 1}" for i in range(p.count)]
        outputs = [f"y{i + 1}" for i in range(p.count)]
        states = [name for i in range(p.count) for name in (f"theta{i + 1}", f"omega{i + 1}")]
    return LTIPlant(
        A,
        B,
        C,
        D,
        input_names=inputs,
        output_names=outputs,
        state_names=states,
        name="dc_servo",
    )


dc_servo.Params = DcServoParams  # type: ignore[attr-defined]
