"""Build a network by its registered type name from a parameter mapping (what the scenario builder calls)."""

from __future__ import annotations

from typing import Any, Mapping

from pydantic import BaseModel, ValidationError

from netsim.env import SimEnv
from netsim.errors import ConfigError
from netsim.network.pipeline import Network
from netsim.registry import lookup

__all__ = ["make_network", "network_class", "format_validation_error"]


def format_validation_error(exc: ValidationError) -> str:
    """All problems of a pydantic error on one line each: ``field.path: message``."""
    lines = []
    for err in exc.errors():
        loc = ".".join(f"[{p}]" if isinstance(p, int) else str(p) for p in err["loc"]).replace(".[", "[")
        msg = err["msg"].removeprefix("Value error, ")
        lines.append(f"{loc}: {msg}" if loc else msg)
    return "; ".join(lines)


def network_class(type_name: str) -> type[Network]:
    """The network class registered as ``type_name`` (ConfigError with a suggestion if unknown)."""
    cls = lookup("network", type_name)
    if not (isinstance(cls, type) and issubclass(cls, Network)):
        raise ConfigError(f"'{type_name}' is not a network type (it resolves to {cls!r})")
    return cls


def make_network(env: SimEnv, name: str, type_name: str, params: Mapping[str, Any] | BaseModel | None) -> Network:
    """Create the network ``name`` of type ``type_name`` (e.g. ``"can"``) on ``env``.

    Parameters
    ----------
    env
        The simulation environment.
    name
        The network's name (scenario key; names its random streams ``network.<name>.*``).
    type_name
        A registered network type (``link``, ``ideal``, ``can``, ``tdma``, ``csma_cd``, ``ethernet``,
        ``round_robin``, ``fdma``, ``flexray``, ``ieee802154``, ``ieee80211b``) or a ``"module:Class"`` path.
    params
        The type's parameters: a mapping (validated against ``cls.Params``; a ``type`` key equal to
        ``type_name`` is ignored) or an already validated ``Params`` instance.

    Raises
    ------
    ConfigError
        Unknown type, or invalid parameters (every problem listed, with path ``networks.<name>``).
    """
    cls = network_class(type_name)
    if isinstance(params, cls.Params):
        p = params
    else:
        if isinstance(params, BaseModel):
            raw: dict[str, Any] = params.model_dump(mode="json", exclude_unset=True)
        else:
            raw = dict(params or {})
        if raw.get("type") in (type_name, None):
            raw.pop("type", None)
        try:
            p = cls.Params.model_validate(raw)
        except ValidationError as exc:
            raise ConfigError(
                f"network '{name}' ({type_name}): {format_validation_error(exc)}", path=f"networks.{name}"
            ) from None
    return cls(env, name, p)
