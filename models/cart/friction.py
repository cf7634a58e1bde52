"""Position-dependent Coulomb friction of the cart track.

The paper only says that the friction is appreciable, varies along the track and (caption of Fig. 1, at
wc = 20 rad/s, vref = 0.8 m/s) "varies faster at the far end of the track, degrading the velocity tracking
in the later half". It gives no friction numbers. We model the friction *level* as

    F(p) = F0 * max(floor, 1 + a * g(phi(p))),     phi(p) = (p + gamma p^2 / 2) / lambda0,

where ``g`` is a sum of ``modes`` cosines of the warped coordinate ``phi`` with random relative spatial
frequencies in ``[1 - spread, 1 + spread]``, amplitudes in [0.5, 1] and phases, normalised to unit RMS. The
local wavelength is ``lambda0 / (1 + gamma p)``, so at speed ``v`` a mode of relative frequency ``f`` varies
at ``omega(p) = 2 pi v f (1 + gamma p) / lambda0`` rad/s (:meth:`Friction.omega_range`).

``model`` selects one of three presets; any field given explicitly overrides the preset:

``inband`` (default; tuned to the consequence the caption of the paper's Fig. 1 states)
    ``lambda0 = 3.3 m``, ``gamma = 9``, one mode, ``spread = 0.1``: at 0.8 m/s the level varies at 5.1-6.2
    rad/s at 0.3 m and 14-17 rad/s at 1 m, inside the bandwidth of every loop with wc >= 20. The velocity
    error a friction variation of frequency w leaves in a PI loop on the double integrator is
    ``|S(iw)/(iw)|`` times its amplitude, which for wc = 20 rises from 5 rad/s to its maximum near 14 rad/s
    (0.7 wc), so the wc = 20 loops track worse in the later half, as the caption of the paper's Fig. 1 says.
    The range was chosen for that purpose: the later-half degradation is built in, not predicted. (A variation at
    10-20 rad/s, e.g. ``lambda0 = 1 m, gamma = 3``, sits on the flat top of that curve and does not degrade
    the later half; one mode rather than several keeps the amplitude the same along the track, so the
    property does not depend on where a beat of several modes happens to fall.)
``modes6`` (the earlier model, kept as an option)
    ``lambda0 = 0.1 m``, ``gamma = 3``, 6 modes, ``spread = 0.5``: 48 rad/s at 0.3 m to 300 rad/s at 1 m, above
    every crossover tested, so the loops hardly reject it and the LTI controllers' quantization noise, not
    the friction, sets the tracking error.
``constant``
    Coulomb friction ``F0`` without variation (``a = 0``); nothing is drawn.

All presets share ``F0 = 2 m/s^2``, ``a = 0.3`` (relative RMS), ``floor = 0.1`` and ``stiction = 1``.

The friction acceleration opposes the motion: ``-F(p) sign(v)``; at rest the cart stays put while
``|u| <= stiction * F(p)``. A realization (the modes) is drawn from the named random stream
``plant.cart.friction`` of the scenario seed, or of ``realization`` when that is given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from pydantic import Field, model_validator

from netsim.env import stream_seed
from netsim.units import StrictModel

__all__ = ["FrictionParams", "Friction", "FRICTION_STREAM", "FRICTION_MODELS"]

#: Name of the random stream the friction realization is drawn from.
FRICTION_STREAM = "plant.cart.friction"

#: The presets of :class:`FrictionParams` by ``model`` (fields not given explicitly take these values).
FRICTION_MODELS: dict[str, dict[str, float]] = {
    "inband": {"variation": 0.3, "wavelength": 3.3, "speedup": 9.0, "modes": 1, "spread": 0.1},
    "modes6": {"variation": 0.3, "wavelength": 0.1, "speedup": 3.0, "modes": 6, "spread": 0.5},
    "constant": {"variation": 0.0, "wavelength": 1.0, "speedup": 0.0, "modes": 1, "spread": 0.0},
}


class FrictionParams(StrictModel):
    """Parameters of the friction model (accelerations in m/s^2, lengths in m); see the module docs."""

    model: Literal["inband", "modes6", "constant"] = Field(
        "inband", description="preset: inband (default, tuned to the consequence the paper's Fig. 1 caption "
        "states) | modes6 (earlier model) | constant")
    coulomb: float = Field(2.0, ge=0.0, description="mean Coulomb friction level F0 in m/s^2")
    variation: float = Field(0.3, ge=0.0, description="relative RMS variation a of the level along the track")
    wavelength: float = Field(3.3, gt=0.0, description="typical spatial wavelength lambda0 at p = 0, m")
    speedup: float = Field(9.0, ge=0.0, description="gamma: the local wavenumber grows as (1 + gamma p)")
    modes: int = Field(1, ge=1, le=64, description="number of cosine modes")
    spread: float = Field(0.1, ge=0.0, lt=1.0, description="relative mode frequencies in [1 - spread, 1 + spread]")
    stiction: float = Field(1.0, ge=0.0, description="breakaway level at rest, relative to F(p)")
    floor: float = Field(0.1, ge=0.0, description="lower bound of the level relative to F0")
    realization: int | None = Field(None, description="draw the modes from this seed instead of the scenario's")

    @model_validator(mode="before")
    @classmethod
    def _preset(cls, data: Any) -> Any:
        """Fill the fields not given explicitly from the preset named by ``model``."""
        if not isinstance(data, dict):
            return data
        preset = FRICTION_MODELS.get(str(data.get("model", "inband")))
        if preset is None:
            return data  # the Literal check names the allowed models
        return {**preset, **data}


@dataclass(frozen=True)
class Friction:
    """One realization of the friction model: :meth:`level` ``F(p)`` and the breakaway level.

    Build with :meth:`draw`; :meth:`none` gives a frictionless track.
    """

    params: FrictionParams
    freqs: np.ndarray
    amps: np.ndarray
    phases: np.ndarray
    if TYPE_CHECKING:  # set by __post_init__; at run time no field (out of __init__, repr and comparisons)
        _one: tuple[float, ...] | None = field(init=False, default=None)

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
        if params.variation == 0.0:
            return cls(params, np.ones(1), np.zeros(1), np.zeros(1))  # nothing varies: nothing drawn
        freqs = rng.uniform(1.0 - params.spread, 1.0 + params.spread, n)
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

    def __post_init__(self) -> None:
        # one mode (the default preset): the level in plain floats, the same IEEE operations as the array form
        # (2 pi f phi + phase, cos from the same libm, a one-term dot product is the product), issue 19's
        # per-event cost of the cart (about a third of the level's time was numpy call overhead)
        # (the parameters are read once here too: a realization's params are not changed after it is drawn)
        one = None
        pr = self.params
        if self.freqs.shape == (1,) and pr.variation != 0.0 and pr.coulomb != 0.0:
            one = (2.0 * math.pi * float(self.freqs[0]), float(self.phases[0]), float(self.amps[0]),
                   0.5 * pr.speedup, pr.wavelength, pr.coulomb, pr.floor, pr.variation)
        object.__setattr__(self, "_one", one)

    def level(self, p: float) -> float:
        """Coulomb friction level ``F(p) >= 0`` in m/s^2."""
        one = self._one
        if one is not None:  # `0.5 * speedup * p * p` multiplies left to right: hs = 0.5 * speedup is its first step
            w, ph, amp, hs, wl, c, fl, var = one
            r = 1.0 + var * (amp * math.cos(w * ((p + hs * p * p) / wl) + ph))
            return c * (r if r > fl else fl)  # max(floor, r)
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

    def omega_range(self, speed: float, p0: float, p1: float) -> tuple[float, float]:
        """Lowest and highest angular frequency (rad/s) of the level's variation seen at ``speed`` (m/s)
        over ``p0 <= p <= p1``: ``2 pi speed f (1 + gamma p) / lambda0`` over the drawn mode frequencies ``f``
        (``(0, 0)`` without variation)."""
        pr = self.params
        if pr.variation == 0.0 or pr.coulomb == 0.0:
            return 0.0, 0.0
        k = 2.0 * math.pi * speed / pr.wavelength
        return (k * float(np.min(self.freqs)) * (1.0 + pr.speedup * p0),
                k * float(np.max(self.freqs)) * (1.0 + pr.speedup * p1))

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
