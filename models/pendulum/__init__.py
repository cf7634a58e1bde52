"""The rotary inverted (Furuta) pendulum of seed 002: observers (finite differences, Luenberger, Kalman) under
LQR and MPC, on a real-time node.

Modules: :mod:`~models.pendulum.model` (plant ``furuta_pendulum``, its linearisation and every choice of the
study), :mod:`~models.pendulum.estimators` (estimators ``pendulum_fd`` and ``luenberger_printed``),
:mod:`~models.pendulum.design` (the slides' designs and the analytic hold-still noise),
:mod:`~models.pendulum.analysis` (the loop's expected cost under delay, from :mod:`netsim.analysis.lqg`),
:mod:`~models.pendulum.metrics` (metric ``pendulum``), :mod:`~models.pendulum.report` (report ``pendulum``) with
:mod:`~models.pendulum.report_sweeps` (the shipped sweep files it runs, and their tables).
"""

from __future__ import annotations

from models.pendulum import design, estimators, model

__all__ = ["design", "estimators", "model"]
