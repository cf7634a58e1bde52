"""Position-dependent Coulomb friction of the cart track.

The paper only says that the friction is appreciable, varies along the track and "varies faster at the
far end of the track". We model the friction *level* as

    F(p) = F0 * max(floor, 1 + a * g(phi(p))),     phi(p) = (p + gamma p^2 / 2) / lambda0,

where ``g`` is a sum of ``n_modes`` cosines of the warped coordinate ``phi`` with random relative
spatial frequencies in [0.5, 1.5], amplitudes in [0.5, 1] and phases, normalised to unit RMS. The local
wavelength is ``lambda0 / (1 + gamma p)``: with the defaults (``lambda0 = 0.1 m``, ``gamma = 3``) it
shrinks from 10 cm at the start to 2.5 cm at 1 m, so at 0.8 m/s the disturbance moves from ~8 Hz to
~30 Hz -- beyond the fastest loop's crossover (80 rad/s = 12.7 Hz) at the far end.

The friction acceleration opposes the motion: ``-F(p) sign(v)``; at rest the cart stays put while
``|u| <= stiction * F(p)``. A realization (the modes) is drawn from the named random stream
``plant.cart.friction`` of the scenario seed, or of ``realization`` when that is given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydantic import Field

from netsim.env import stream_seed
from netsim.units import StrictModel

__all__ = ["FrictionParams", "Friction", "FRICTION_STREAM"]

#: Name of the random stream the friction realization is drawn from.
FRICTION_STREAM = "plant.cart.friction"


class FrictionParams(StrictModel):
    """Parameters of the friction model (accelerations in m/s^2, lengths in m)."""

    coulomb: float = Field(2.0, ge=0.0, description="mean Coulomb friction level F0 in m/s^2")
    variation: float = Field(0.3, ge=0.0, description="relative RMS variation a of the level along the track")
    wavelength: float = Field(0.1, gt=0.0, description="typical spatial wavelength lambda0 at p = 0, m")
    speedup: float = Field(3.0, ge=0.0, description="gamma: the local wavenumber grows as (1 + gamma p)")
    modes: int = Field(6, ge=1, le=64, description="number of cosine modes")
    stiction: float = Field(1.0, ge=0.0, description="breakaway level at rest, relative to F(p)")
    floor: float = Field(0.1, ge=0.0, description="lower bound of the level relative to F0")
    realization: int | None = Field(None, description="draw the modes from this seed instead of the scenario's")


@dataclass(frozen=True)
class Friction:
    """One realization of the friction model: :meth:`level` ``F(p)`` and the breakaway level.

    Build with :meth:`draw`; :meth:`none` gives a frictionless track.
    """

    params: FrictionParams
    freqs: np.ndarray
    amps: np.ndarray
    phases: np.ndarray

    @classmethod
    def draw(cls, params: FrictionParams, seed: int = 0) -> "Friction":
        """Draw a realization from the stream ``plant.cart.friction`` of ``seed`` (or ``params.realization``)."""
        s = params.realization if params.realization is not None else seed
        return cls.from_rng(params, np.random.Generator(np.random.PCG64(stream_seed(int(s), FRICTION_STREAM))))

    @classmethod
    def from_rng(cls, params: FrictionParams, rng: np.random.Generator) -> "Friction":
        """Draw a realization from ``rng`` (in a simulation: ``env.rng("plant.cart.friction")``, which gives the
        same realization as :meth:`draw` with the scenario seed)."""
        n = params.modes
        freqs = rng.uniform(0.5, 1.5, n)
        amps = rng.uniform(0.5, 1.0, n)
        phases = rng.uniform(0.0, 2.0 * math.pi, n)
        amps = amps / math.sqrt(0.5 * float(np.sum(amps**2)))  # unit RMS of g
        return cls(params, freqs, amps, phases)

    @classmethod
    def none(cls) -> "Friction":
        """No friction at all."""
        return cls(FrictionParams(coulomb=0.0, variation=0.0), np.zeros(1), np.zeros(1), np.zeros(1))

    def phase(self, p: float) -> float:
        """Warped track coordinate ``phi(p)`` (in wavelengths)."""
        pr = self.params
        return (p + 0.5 * pr.speedup * p * p) / pr.wavelength

    def level(self, p: float) -> float:
        """Coulomb friction level ``F(p) >= 0`` in m/s^2."""
        pr = self.params
        if pr.coulomb == 0.0:
            return 0.0
        if pr.variation == 0.0:
            return pr.coulomb
        g = float(np.dot(self.amps, np.cos(2.0 * math.pi * self.freqs * self.phase(p) + self.phases)))
        return pr.coulomb * max(pr.floor, 1.0 + pr.variation * g)

    def levels(self, p: np.ndarray) -> np.ndarray:
        """Vectorized :meth:`level`."""
        pr = self.params
        p = np.asarray(p, dtype=float)
        if pr.coulomb == 0.0:
            return np.zeros_like(p)
        phi = (p + 0.5 * pr.speedup * p * p) / pr.wavelength
        g = np.cos(2.0 * math.pi * np.multiply.outer(phi, self.freqs) + self.phases) @ self.amps
        return pr.coulomb * np.maximum(pr.floor, 1.0 + pr.variation * g)

    def breakaway(self, p: float) -> float:
        """Command magnitude needed to start moving from rest at ``p`` (m/s^2)."""
        return self.params.stiction * self.level(p)

    def accel(self, p: float, v: float, u: float) -> float:
        """Friction acceleration at state ``(p, v)`` under command ``u`` (rest: cancels ``u`` up to breakaway)."""
        f = self.level(p)
        if v > 0.0:
            return -f
        if v < 0.0:
            return f
        if abs(u) <= self.params.stiction * f:
            return -u
        return -math.copysign(f, u)
