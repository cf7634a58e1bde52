"""Tuning rules of the cart controllers (Henningsson & Cervin, section III and VII-B).

The process seen by every controller is the double integrator ``Gp(s) = 1/s^2`` (the ``1/Td`` term is
neglected for crossover frequencies ``wc >= 5 rad/s``). The Pure PI controller (eqs 2-3) has, from ``-y``
to ``u``, the lead filter

    Gc(s) = (K/Ti) (s Ti + 1) / (s Tfilter + 1),

whose zero and pole sit at equal logarithmic distance on either side of ``wc``:
``Tfilter = 1/(r wc)``, ``Ti = r/wc`` (``r = 3``, phase margin ``atan(r) - atan(1/r) = 53.1 deg``).

Crossover gain (derivation)
---------------------------
At ``s = i wc`` we have ``wc Ti = r`` and ``wc Tfilter = 1/r``, so

    |L(i wc)| = (K/Ti) * sqrt(1 + r^2) / sqrt(1 + 1/r^2) / wc^2 = (K/Ti) * r / wc^2 = K / wc,

and ``|L(i wc)| = 1`` gives **K = wc** (units 1/s: a velocity error in m/s gives an acceleration in
m/s^2). The test suite checks this against a frequency sweep of the loop gain.

Observer-based PI and Full Event controllers use a faster integral time ``Ti' = Ti/4`` (or the
measurement-noise variant ``Ti' = Ti/2, Tfilter' = 2 Tfilter``), lower bounded, as in section VII-B, by
the Pure PI's ``Ti`` at ``wc = 80 rad/s`` (``3/80 s``) to avoid instability.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from netsim.errors import ConfigError

__all__ = [
    "R_DEFAULT",
    "TI_FLOOR_WC",
    "Tuning",
    "pure_pi_tuning",
    "observer_tuning",
    "phase_margin_deg",
]

#: Pole/zero spread of the lead filter (paper: r = 3 gives about 50 deg phase margin).
R_DEFAULT = 3.0
#: Crossover frequency whose Pure PI integral time lower-bounds the reduced Ti (section VII-B).
TI_FLOOR_WC = 80.0


@dataclass(frozen=True)
class Tuning:
    """Gains of one cart controller.

    Attributes
    ----------
    wc : float
        Design crossover frequency in rad/s.
    K : float
        Proportional gain in 1/s (velocity error in m/s -> acceleration command in m/s^2).
    Ti : float
        Integral time in s (after any lower bound).
    Tfilter : float
        Velocity filter time constant in s; also the ``dt`` lower limit and the LTI-mode time constant of
        the event estimators.
    beta : float
        Reference weight in ``u = K(beta vref - v_hat) - u_bias_hat``.
    """

    wc: float
    K: float
    Ti: float
    Tfilter: float
    beta: float

    @property
    def timeout(self) -> float:
        """LTI-mode timeout ``2 Tfilter`` of the Full Event estimator (section V-C.1), in s."""
        return 2.0 * self.Tfilter


def _check_wc(wc: float, r: float) -> None:
    if not (isinstance(wc, (int, float)) and math.isfinite(wc) and wc > 0):
        raise ConfigError(f"crossover frequency wc must be a positive number of rad/s, got {wc!r}")
    if not (math.isfinite(r) and r > 1):
        raise ConfigError(f"pole/zero spread r must be > 1 (paper: 3), got {r!r}")


def pure_pi_tuning(wc: float, r: float = R_DEFAULT, beta: float = 0.5) -> Tuning:
    """Pure PI tuning (section III-A): ``Tfilter = 1/(r wc)``, ``Ti = r/wc``, ``K = wc``, ``beta = 0.5``."""
    _check_wc(wc, r)
    return Tuning(wc=float(wc), K=float(wc), Ti=r / wc, Tfilter=1.0 / (r * wc), beta=beta)


def observer_tuning(
    wc: float,
    r: float = R_DEFAULT,
    variant: str = "ti4",
    ti_floor: float | None = R_DEFAULT / TI_FLOOR_WC,
    beta: float = 1.0,
) -> Tuning:
    """Tuning of the observer-based controllers (Observer PI, Full Event; sections III-B, VI-B.5, VII-B).

    Parameters
    ----------
    wc
        Crossover frequency in rad/s.
    r
        Pole/zero spread.
    variant
        ``"ti4"``: ``Ti' = Ti/4`` (disturbance rejection); ``"ti2"``: ``Ti' = Ti/2`` and
        ``Tfilter' = 2 Tfilter`` (measurement noise rejection).
    ti_floor
        Lower bound on ``Ti'`` in s (paper: the Pure PI ``Ti`` at 80 rad/s, ``3/80 s``); ``None`` disables it.
    beta
        Reference weight (1 for the observer-based controllers).
    """
    base = pure_pi_tuning(wc, r)
    if variant == "ti4":
        ti, tf = base.Ti / 4.0, base.Tfilter
    elif variant == "ti2":
        ti, tf = base.Ti / 2.0, 2.0 * base.Tfilter
    else:
        raise ConfigError(f"observer tuning variant must be 'ti4' or 'ti2', got {variant!r}")
    if ti_floor is not None:
        ti = max(ti, float(ti_floor))
    return Tuning(wc=base.wc, K=base.K, Ti=ti, Tfilter=tf, beta=beta)


def phase_margin_deg(r: float = R_DEFAULT) -> float:
    """Phase margin of the Pure PI loop at its crossover: ``atan(r) - atan(1/r)`` in degrees."""
    return math.degrees(math.atan(r) - math.atan(1.0 / r))
