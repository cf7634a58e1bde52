"""Generic control algorithms as plain numeric objects (no simpy, kernel or network inside).

Event-triggered multi-rate control of Cuenca, Zheng, Tomizuka, Sanchez:

* :mod:`~netsim.control.triggers` -- sensor triggers: PET mixed mechanism eq (6), TT safety eq (7),
  reference change eq (8), time-triggered and send-on-delta baselines, :class:`AnyOf` combinations;
* :mod:`~netsim.control.controller_trigger` -- controller-side condition eq (22);
* :mod:`~netsim.control.numre` -- the non-uniform multi-rate Kalman filter, eqs (9)-(15);
* :mod:`~netsim.control.packets` -- control packets with future actions and the actuator playout buffer;
* :mod:`~netsim.control.mrci` -- the multi-rate controller with interlacing, eqs (19)-(20);
* :mod:`~netsim.control.dob` -- the H-infinity disturbance observer, eqs (16)-(18);
* :mod:`~netsim.control.cascade` -- the whole control side (NUMRE + MRCI + DOB + eq 22);
* :mod:`~netsim.control.reference_loop` -- a plain-numpy closed loop of the scheme;
* :mod:`~netsim.control.kalman` -- discrete Kalman helpers.

The task and handler programs that run these objects inside kernels live in :mod:`netsim.programs`.
"""

from __future__ import annotations

from netsim.control.cascade import ControlSide, Decision
from netsim.control.controller_trigger import ControllerTrigger
from netsim.control.dob import DisturbanceObserver, DobDesign, design_dob
from netsim.control.mrci import MrciController, MrciDesign, Section, computation_saving, decompose
from netsim.control.numre import Numre, lifted_noise_cov
from netsim.control.packets import ControlPacket, PlayoutBuffer
from netsim.control.reference_loop import LoopTrace, simulate_loop
from netsim.control.triggers import (
    AnyOf,
    MaxIntervalTrigger,
    MixedTrigger,
    ReferenceChangeTrigger,
    SendOnDelta,
    TimeTriggered,
    mtm_fires,
)

__all__ = [
    "AnyOf",
    "ControlPacket",
    "ControlSide",
    "ControllerTrigger",
    "Decision",
    "DisturbanceObserver",
    "DobDesign",
    "LoopTrace",
    "MaxIntervalTrigger",
    "MixedTrigger",
    "MrciController",
    "MrciDesign",
    "Numre",
    "PlayoutBuffer",
    "ReferenceChangeTrigger",
    "Section",
    "SendOnDelta",
    "TimeTriggered",
    "computation_saving",
    "decompose",
    "design_dob",
    "lifted_noise_cov",
    "mtm_fires",
    "simulate_loop",
]
