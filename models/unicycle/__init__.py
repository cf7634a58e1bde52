"""The two-wheel-drive cart of seed 001 (a course report on EKF and LQR for a 2WD cart with IR wall sensors).

Modules: :mod:`~netsim.models.unicycle.model` (kinematics eqs 1-3, exact arcs, sensors eqs 4-9, Jacobians eqs
12-17, the report's constants and our choices), :mod:`~netsim.models.unicycle.design` (trajectory, EKF, cart-frame
LQR eqs 24-27), :mod:`~netsim.models.unicycle.ekf` (the same EKF on plain floats, used by the programs and the
numpy loop), :mod:`~netsim.models.unicycle.plant` (plant ``unicycle``), :mod:`~netsim.models.unicycle.programs`
(programs ``ir_sensor``, ``unicycle_ekf``, ``wheel_drive``), :mod:`~netsim.models.unicycle.reference` (a plain numpy
loop of the same filter and law, for Monte-Carlo studies and the benchmark) and :mod:`~netsim.models.unicycle.report`
(``netsim report unicycle``, with :mod:`~netsim.models.unicycle.readme`, :mod:`~netsim.models.unicycle.readme_net` and
:mod:`~netsim.models.unicycle.quoting`).
"""

from __future__ import annotations

from netsim.models.unicycle import design, metrics, model, plant, programs

__all__ = ["design", "metrics", "model", "plant", "programs"]
