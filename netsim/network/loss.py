"""Loss models drawn after each transmission: Bernoulli and Gilbert-Elliott (two-state Markov) burst loss.

Both are plain numeric objects on a :class:`numpy.random.Generator`; the network gives them its
``network.<name>.loss`` stream. The Gilbert-Elliott chain is kept per (sender, receiver) pair and steps once
per copy: first the state moves (good -> bad with ``p_good_to_bad``, bad -> good with ``p_bad_to_good``),
then the copy is lost with the state's loss probability.

Its long-run values: ``pi_bad = p_gb / (p_gb + p_bg)``; loss rate ``(1 - pi_bad) * loss_good + pi_bad *
loss_bad``; with ``loss_good = 0, loss_bad = 1`` a loss burst is a stay in the bad state, of mean length
``1 / p_bg``.
"""

from __future__ import annotations

import abc

from typing import Annotated, Literal, Union

import numpy as np
from pydantic import Field

from netsim.units import StrictModel

__all__ = [
    "BernoulliLossSpec",
    "GilbertElliottLossSpec",
    "LossSpec",
    "LossModel",
    "BernoulliLoss",
    "GilbertElliottLoss",
    "make_loss",
]

Probability = Annotated[float, Field(ge=0.0, le=1.0)]


class BernoulliLossSpec(StrictModel):
    """Independent loss of each copy with probability ``p``."""

    model: Literal["bernoulli"] = "bernoulli"
    p: Probability


class GilbertElliottLossSpec(StrictModel):
    """Two-state burst loss (see the module docstring)."""

    model: Literal["gilbert_elliott"] = "gilbert_elliott"
    p_good_to_bad: Probability
    p_bad_to_good: Probability
    loss_good: Probability = 0.0
    loss_bad: Probability = 1.0


#: A loss model in a network's parameters (``loss: {model: gilbert_elliott, ...}``).
LossSpec = Annotated[Union[BernoulliLossSpec, GilbertElliottLossSpec], Field(discriminator="model")]


class LossModel(abc.ABC):
    """Interface: ``lost(pair) -> bool`` for one copy travelling on ``pair = (sender, receiver)``."""

    @abc.abstractmethod
    def lost(self, pair: tuple[str, str]) -> bool:
        """Draw whether this copy is lost."""


class BernoulliLoss(LossModel):
    """Each copy is lost independently with probability ``p``."""

    def __init__(self, p: float, rng: np.random.Generator) -> None:
        self.p = float(p)
        self._random = rng.random

    def lost(self, pair: tuple[str, str]) -> bool:
        return self._random() < self.p


class GilbertElliottLoss(LossModel):
    """Gilbert-Elliott channel per (sender, receiver) pair, starting in the good state."""

    def __init__(
        self, p_good_to_bad: float, p_bad_to_good: float, loss_good: float, loss_bad: float, rng: np.random.Generator
    ) -> None:
        self.p_gb = float(p_good_to_bad)
        self.p_bg = float(p_bad_to_good)
        self.loss_good = float(loss_good)
        self.loss_bad = float(loss_bad)
        self._random = rng.random
        self._bad: dict[tuple[str, str], bool] = {}

    def lost(self, pair: tuple[str, str]) -> bool:
        r = self._random
        bad = self._bad.get(pair, False)
        if bad:
            if r() < self.p_bg:
                bad = False
        elif r() < self.p_gb:
            bad = True
        self._bad[pair] = bad
        h = self.loss_bad if bad else self.loss_good
        if h >= 1.0:
            return True
        if h <= 0.0:
            return False
        return r() < h

    @property
    def stationary_bad(self) -> float:
        """Long-run fraction of copies that see the bad state."""
        total = self.p_gb + self.p_bg
        return self.p_gb / total if total > 0 else 0.0


def make_loss(
    spec: BernoulliLossSpec | GilbertElliottLossSpec | None, loss_probability: float, rng: np.random.Generator
) -> LossModel | None:
    """The runtime loss model for a network's ``loss`` / ``loss_probability`` parameters (None: lossless)."""
    if spec is None:
        return BernoulliLoss(loss_probability, rng) if loss_probability > 0 else None
    if isinstance(spec, BernoulliLossSpec):
        return BernoulliLoss(spec.p, rng) if spec.p > 0 else None
    return GilbertElliottLoss(spec.p_good_to_bad, spec.p_bad_to_good, spec.loss_good, spec.loss_bad, rng)
