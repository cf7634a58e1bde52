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
* :mod:`~netsim.control.kalman` -- discrete Kalman helpers and the :class:`KalmanFilter` (time-varying or steady-state,
  prediction-only steps, delayed measurements fused at their sample time).

The control toolbox (issue 16), one interface (:mod:`~netsim.control.interface`: ``law.step(z, r) -> u``, an
estimator's ``correct``/``predict``, :class:`OutputFeedback` joining them):

* estimators: :class:`KalmanFilter`, :class:`LuenbergerObserver` (:mod:`~netsim.control.luenberger`, predictor and
  current forms), :class:`ExtendedKalmanFilter` (:mod:`~netsim.control.ekf`), :class:`FiniteDifferenceVelocity`
  (:mod:`~netsim.control.baselines`);
* laws: :class:`LQR` and :class:`StateFeedback` (:mod:`~netsim.control.lqr`), :class:`LinearMPC`
  (:mod:`~netsim.control.mpc`, QP by daqp: :mod:`~netsim.control.qp_backends`), :class:`PID` / :class:`PIDLaw`;
* construction checks with messages naming the parameter: :mod:`~netsim.control.design_checks`.

The task and handler programs that run these objects inside kernels live in :mod:`netsim.programs`.
"""

from __future__ import annotations

from netsim.control.cascade import ControlSide, Decision
from netsim.control.controller_trigger import ControllerTrigger
from netsim.control.dob import DisturbanceObserver, DobDesign, design_dob
from netsim.control.mrci import MrciController, MrciDesign, Section, computation_saving, decompose
from netsim.control.numre import Numre, lifted_noise_cov
from netsim.control.packets import ControlPacket, PlayoutBuffer
from netsim.control.baselines import FiniteDifferenceVelocity
from netsim.control.ekf import ExtendedKalmanFilter, MeasurementSource
from netsim.control.interface import ControlLaw, OutputFeedback, StateEstimator, sample_index
from netsim.control.kalman import KalmanFilter
from netsim.control.lqr import LQR, StateFeedback, trajectory_feedforward
from netsim.control.luenberger import LuenbergerObserver
from netsim.control.mpc import LinearMPC
from netsim.control.pid import PID, PIDLaw
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
    "ControlLaw",
    "StateEstimator",
    "OutputFeedback",
    "sample_index",
    "KalmanFilter",
    "LuenbergerObserver",
    "ExtendedKalmanFilter",
    "MeasurementSource",
    "FiniteDifferenceVelocity",
    "LQR",
    "StateFeedback",
    "trajectory_feedforward",
    "LinearMPC",
    "PID",
    "PIDLaw",
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
