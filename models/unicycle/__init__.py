"""The two-wheel-drive cart of seed 001 (a course report on EKF and LQR for a 2WD cart with IR wall sensors).

Modules: :mod:`~models.unicycle.model` (kinematics eqs 1-3, exact arcs, sensors eqs 4-9, Jacobians eqs
12-17, the report's constants and our choices), :mod:`~models.unicycle.design` (trajectory, EKF, cart-frame
LQR eqs 24-27), :mod:`~models.unicycle.ekf` (the same EKF on plain floats, used by the programs and the
numpy loop), :mod:`~models.unicycle.plant` (plant ``unicycle``), :mod:`~models.unicycle.programs`
(programs ``ir_sensor``, ``unicycle_ekf``, ``wheel_drive``), :mod:`~models.unicycle.reference` (a plain numpy
loop of the same filter and law, for Monte-Carlo studies and the benchmark) and :mod:`~models.unicycle.report`
(``netsim report unicycle``, with :mod:`~models.unicycle.readme`, :mod:`~models.unicycle.readme_net` and
:mod:`~models.unicycle.quoting`).
"""

from __future__ import annotations

from models.unicycle import design, metrics, model, plant, programs

__all__ = ["design", "metrics", "model", "plant", "programs"]
