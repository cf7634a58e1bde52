"""Continuous and discrete plants co-simulated with the kernels and networks.

A plant holds its state at an integer-nanosecond instant and is advanced **lazily**: whenever anything
samples it (:meth:`Plant.output`, an ADC, an encoder) or actuates it (:meth:`Plant.set_input`, a DAC) it is
first propagated to that instant under the inputs held since the last change (zero-order hold).

Three plant types share the :class:`Plant` interface:

:class:`~netsim.plant.lti.LTIPlant`
    continuous LTI, propagated exactly (one matrix exponential per distinct step length, cached), process
    noise with the exact (Van Loan) discrete covariance.
:class:`~netsim.plant.nonlinear.NonlinearPlant`
    ``f(t, x, u, params)``, ``h(t, x, u, params)`` integrated by :func:`scipy.integrate.solve_ivp` (or, chosen by
    ``plant.integrator``, by fixed-step RK4: :mod:`netsim.plant.integrator`), with event-detected mode switches
    for state-dependent discontinuities (stick-slip friction).
:class:`~netsim.plant.discrete.DiscretePlant`
    ``x[k+1] = Ad x[k] + Bd u[k]`` updated at multiples of ``dt_ns``, outputs held in between.

Disturbances
------------
:meth:`Plant.add_disturbance` adds a signal to one input (the plant sees ``held input + disturbances``).
Piecewise-constant signals (:mod:`netsim.io.signals` constant/step/square/table, plain numbers) switch
exactly at their jump instants: the plant splits its propagation there. A sinusoid is exact on an LTI plant
(a harmonic oscillator is appended to the state). An :class:`LTIDisturbance` is a disturbance model of its
own (eq. (2) of Cuenca et al.): continuous ones are appended to the state of an LTI plant, discrete ones
(``dt_ns``) update their state at multiples of ``dt_ns`` and hold their output in between. Any other
callable ``t_ns -> value`` is sampled at each propagation instant and held (an approximation).

Random disturbances given in a scenario (``plant.process_noise`` entries, :mod:`netsim.plant.noise`): white noise
held per sample on inputs (:meth:`Plant.add_input_noise`, a :class:`~netsim.plant.noise.HeldNoise` discrete
disturbance model, so exact propagation stays exact) and random-walk increments on any state of any plant
(:meth:`Plant.add_state_noise`, jumps at the sample instants between the plant's own integration steps), or
held random rates on the states' derivatives (LTI and nonlinear plants).

Listeners
---------
:meth:`Plant.on_input_change` registers ``callback(t_ns)`` called whenever the future trajectory stops being
the one predicted from the current state and held inputs: an input change, a noisy propagation step (the
noise enters as a jump at the step instant), a stochastic disturbance update. Exact encoders use it.

Modules
-------
``base`` (:class:`Plant`, the lazy-advance machinery), ``lti`` (:class:`LTIPlant`), ``discrete`` (:class:`DiscretePlant`),
``nonlinear`` (:class:`NonlinearPlant`, :class:`Mode`, :class:`Guard`), ``modes`` (hybrid modes, stick-slip friction), ``integrator`` (the RK4 steps and their interpolant), ``disturbance`` (:class:`LTIDisturbance`
and the classification of disturbances), ``noise`` (:class:`~netsim.plant.noise.HeldNoise`, the ``process_noise``
entries), ``shared`` (matrix validation helpers, ``NEVER``). The concrete plants
are imported on first use (``scipy.integrate`` is not needed to build an LTI plant).
"""

from __future__ import annotations

from netsim.lazy_import import lazy_exports
from netsim.plant.base import Plant
from netsim.plant.disturbance import LTIDisturbance
from netsim.plant.shared import NEVER, as_matrix, matvec

__all__ = [
    "Plant",
    "LTIPlant",
    "NonlinearPlant",
    "DiscretePlant",
    "LTIDisturbance",
    "HeldNoise",
    "Mode",
    "Guard",
    "NEVER",
    "as_matrix",
    "matvec",
]

_LAZY = {
    "LTIPlant": "netsim.plant.lti",
    "DiscretePlant": "netsim.plant.discrete",
    "NonlinearPlant": "netsim.plant.nonlinear",
    "Mode": "netsim.plant.nonlinear",
    "Guard": "netsim.plant.nonlinear",
    "HeldNoise": "netsim.plant.noise",
}


__getattr__, __dir__ = lazy_exports(__name__, _LAZY)
