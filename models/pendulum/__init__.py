"""The rotary inverted (Furuta) pendulum of seed 002: observers (finite differences, Luenberger, Kalman) under
LQR and MPC, on a real-time node.

Modules: :mod:`~netsim.models.pendulum.model` (plant ``furuta_pendulum``, its linearisation and every choice of the
study), :mod:`~netsim.models.pendulum.estimators` (estimators ``pendulum_fd`` and ``luenberger_printed``),
:mod:`~netsim.models.pendulum.design` (the slides' designs and the analytic hold-still noise),
:mod:`~netsim.models.pendulum.analysis` (the loop's expected cost under delay, from :mod:`netsim.analysis.lqg`),
:mod:`~netsim.models.pendulum.metrics` (metric ``pendulum``), :mod:`~netsim.models.pendulum.report` (report ``pendulum``) with
:mod:`~netsim.models.pendulum.report_sweeps` (the shipped sweep files it runs, and their tables).
"""

from __future__ import annotations

from netsim.models.pendulum import design, estimators, model

__all__ = ["design", "estimators", "model"]
