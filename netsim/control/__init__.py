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

from netsim.lazy_import import lazy_exports

#: Exported name -> the module that defines it, imported at first use (issue 19: importing one medium or one
#: control law must not import them all; the registry imports a plugin's own module).
_EXPORTS = {
    "ControlSide": "netsim.control.cascade",
    "Decision": "netsim.control.cascade",
    "ControllerTrigger": "netsim.control.controller_trigger",
    "DisturbanceObserver": "netsim.control.dob",
    "DobDesign": "netsim.control.dob",
    "design_dob": "netsim.control.dob",
    "MrciController": "netsim.control.mrci",
    "MrciDesign": "netsim.control.mrci",
    "Section": "netsim.control.mrci",
    "computation_saving": "netsim.control.mrci",
    "decompose": "netsim.control.mrci",
    "Numre": "netsim.control.numre",
    "lifted_noise_cov": "netsim.control.numre",
    "ControlPacket": "netsim.control.packets",
    "PlayoutBuffer": "netsim.control.packets",
    "FiniteDifferenceVelocity": "netsim.control.baselines",
    "ExtendedKalmanFilter": "netsim.control.ekf",
    "MeasurementSource": "netsim.control.ekf",
    "ControlLaw": "netsim.control.interface",
    "OutputFeedback": "netsim.control.interface",
    "StateEstimator": "netsim.control.interface",
    "sample_index": "netsim.control.interface",
    "KalmanFilter": "netsim.control.kalman",
    "LQR": "netsim.control.lqr",
    "StateFeedback": "netsim.control.lqr",
    "trajectory_feedforward": "netsim.control.lqr",
    "LuenbergerObserver": "netsim.control.luenberger",
    "LinearMPC": "netsim.control.mpc",
    "PID": "netsim.control.pid",
    "PIDLaw": "netsim.control.pid",
    "LoopTrace": "netsim.control.reference_loop",
    "simulate_loop": "netsim.control.reference_loop",
    "AnyOf": "netsim.control.triggers",
    "MaxIntervalTrigger": "netsim.control.triggers",
    "MixedTrigger": "netsim.control.triggers",
    "ReferenceChangeTrigger": "netsim.control.triggers",
    "SendOnDelta": "netsim.control.triggers",
    "TimeTriggered": "netsim.control.triggers",
    "mtm_fires": "netsim.control.triggers",
}

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


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
