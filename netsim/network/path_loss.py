"""Path-loss models of the radio media: the power a receiver gets from a transmitter (TrueTime's path-loss function).

A wireless network names its model as ``path_loss: {type: NAME, ...parameters}``; without ``path_loss`` it uses the
``exponent`` model with the network's ``path_loss_exponent`` and ``reference_distance`` (TrueTime's default
``1/d^a``). The built-in models (kind ``path_loss`` of the registry, ``netsim list path_loss``):

``exponent``
    ``P_rx = P_tx - 10 a log10(max(d, d0) / d0)`` dBm: no loss closer than ``d0``.
``log_distance``
    ``P_rx = P_tx - PL0 - 10 a log10(max(d, d0) / d0)`` dBm, ``PL0`` the loss at ``d0`` (measured, or the free-space
    loss at ``d0``).
``free_space``
    Friis: ``P_rx = P_tx + G_tx + G_rx - 20 log10(4 pi max(d, d_min) f / c)`` dBm.

A user's model (TrueTime's ``ttSetNetworkParameter('pathloss', ...)``) is a :class:`PathLoss` subclass with a
nested ``Params`` model, registered under ``path_loss`` in a plugin file the scenario's ``plugins:`` lists; such
a file runs only with the user's permission (``--allow-plugins``, :mod:`netsim.trust`), as every plugin file::

    from netsim.network.path_loss import PathLoss
    from netsim.registry import register
    from netsim.units import StrictModel

    @register("path_loss", "wall", "exponent model plus 10 dB through a wall at x = 5 m")
    class Wall(PathLoss):
        class Params(StrictModel):
            wall_db: float = 10.0

        def received_dbm(self, tx_dbm, distance_m, sender, receiver, positions):
            (xa, _), (xb, _) = positions
            through = (xa - 5.0) * (xb - 5.0) < 0
            return tx_dbm - 20.0 * math.log10(max(distance_m, 1.0)) - (self.params.wall_db if through else 0.0)

The medium calls :meth:`PathLoss.received_dbm` once per (sender, receiver) pair while neither moves, so a model
may be as slow as it likes; it must be deterministic (a run is reproducible).
"""

from __future__ import annotations

import math
from typing import Any

from pydantic import BaseModel, Field

from netsim.registry import register
from netsim.units import StrictModel

__all__ = ["PathLoss", "ExponentPathLoss", "LogDistancePathLoss", "FreeSpacePathLoss", "exponent_dbm",
           "make_path_loss", "path_loss_class"]

#: Speed of light (m/s), for the free-space loss.
C_M_PER_S = 299_792_458.0


def exponent_dbm(tx_dbm: float, distance_m: float, exponent: float, d0: float = 1.0) -> float:
    """Power (dBm) received at ``distance_m`` from a transmitter of ``tx_dbm``: log-distance path loss.

    >>> exponent_dbm(0.0, 10.0, 2.0)
    -20.0
    """
    return tx_dbm - 10.0 * exponent * math.log10(max(distance_m, d0) / d0)


class PathLoss:
    """Base of the path-loss models: ``received_dbm`` of a transmission, given the distance and the nodes.

    Parameters
    ----------
    params
        The model's validated ``Params`` (an empty model when it declares none).
    """

    class Params(StrictModel):
        """No parameters."""

    def __init__(self, params: Any) -> None:
        self.params = params

    def loss_db(self, distance_m: float) -> float:
        """Path loss (dB) over ``distance_m`` metres (subclasses override this or :meth:`received_dbm`)."""
        raise NotImplementedError(f"{type(self).__name__} defines neither loss_db nor received_dbm")

    def received_dbm(self, tx_dbm: float, distance_m: float, sender: str, receiver: str,
                     positions: tuple[tuple[float, float], tuple[float, float]]) -> float:
        """Power (dBm) ``receiver`` gets from ``sender`` transmitting ``tx_dbm``; ``positions`` are theirs (m).

        The default is ``tx_dbm - loss_db(distance_m)``.
        """
        return tx_dbm - self.loss_db(distance_m)


@register("path_loss", "exponent", "P_tx - 10 a log10(d / d0): TrueTime's 1/d^a (the default)")
class ExponentPathLoss(PathLoss):
    """TrueTime's ``1/d^a`` path loss: ``P_rx = P_tx - 10 a log10(max(d, d0) / d0)``."""

    class Params(StrictModel):
        """Exponent and reference distance."""

        exponent: float = Field(3.5, gt=0, description="path-loss exponent a (2: free space)")
        reference_distance: float = Field(1.0, gt=0, description="d0 (m): no loss closer than this")

    def received_dbm(self, tx_dbm: float, distance_m: float, sender: str, receiver: str,
                     positions: Any = None) -> float:
        p = self.params
        return exponent_dbm(tx_dbm, distance_m, p.exponent, p.reference_distance)


@register("path_loss", "log_distance", "P_tx - PL0 - 10 a log10(d / d0): a measured loss at d0, then an exponent")
class LogDistancePathLoss(PathLoss):
    """Log-distance path loss with a reference loss: ``P_rx = P_tx - PL0 - 10 a log10(max(d, d0) / d0)``."""

    class Params(StrictModel):
        """Exponent, reference distance and the loss there."""

        exponent: float = Field(3.0, gt=0, description="path-loss exponent a beyond d0")
        reference_distance: float = Field(1.0, gt=0, description="d0 (m)")
        reference_loss_db: float = Field(40.0, ge=0, description="PL0: the loss (dB) at d0 (40 dB: 2.4 GHz at 1 m)")

    def loss_db(self, distance_m: float) -> float:
        p = self.params
        return p.reference_loss_db + 10.0 * p.exponent * math.log10(max(distance_m, p.reference_distance)
                                                                     / p.reference_distance)


@register("path_loss", "free_space", "Friis free-space loss 20 log10(4 pi d f / c), with antenna gains")
class FreeSpacePathLoss(PathLoss):
    """Friis: ``P_rx = P_tx + G_tx + G_rx - 20 log10(4 pi max(d, d_min) f / c)``."""

    class Params(StrictModel):
        """Carrier frequency, antenna gains and the distance below which the loss stops falling."""

        frequency_hz: float = Field(2.4e9, gt=0, description="carrier frequency (Hz)",
                                    json_schema_extra={"unit": "Hz"})
        tx_gain_dbi: float = Field(0.0, description="transmit antenna gain (dBi)")
        rx_gain_dbi: float = Field(0.0, description="receive antenna gain (dBi)")
        min_distance: float = Field(1.0, gt=0, description="d_min (m): the loss at d_min applies closer than this")

    def loss_db(self, distance_m: float) -> float:
        p = self.params
        d = max(distance_m, p.min_distance)
        return 20.0 * math.log10(4.0 * math.pi * d * p.frequency_hz / C_M_PER_S) - p.tx_gain_dbi - p.rx_gain_dbi


def path_loss_class(type_name: str) -> Any:
    """The path-loss model registered as ``type_name`` (ConfigError, with a suggestion, when unknown)."""
    from netsim.errors import ConfigError
    from netsim.registry import lookup

    cls = lookup("path_loss", type_name)
    if not (isinstance(cls, type) and issubclass(cls, PathLoss)):
        raise ConfigError(f"path_loss '{type_name}' is not a path-loss model (a netsim.network.path_loss.PathLoss "
                          "subclass)")
    return cls


def _params_of(cls: Any) -> type[BaseModel]:
    model = getattr(cls, "Params", None)
    return model if isinstance(model, type) and issubclass(model, BaseModel) else PathLoss.Params


def make_path_loss(spec: dict[str, Any]) -> PathLoss:
    """Build the model ``spec`` names (``{type: NAME, ...parameters}``; already validated)."""
    cls = path_loss_class(spec["type"])
    params = _params_of(cls).model_validate({k: v for k, v in spec.items() if k != "type"})
    return cls(params)
