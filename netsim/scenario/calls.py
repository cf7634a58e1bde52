"""How ``build`` calls each kind of plugin, and a check that a plugin can be called that way.

A scenario may name a plugin by a ``"module:Class"`` path (``"netsim.plant.lti:LTIPlant"``); since issue 14 the
path must lead to a registered object of the kind or a subclass of the kind's base class
(:func:`netsim.registry.resolve`), never an arbitrary callable. ``build`` calls it with the arguments of its
kind; a class whose constructor needs other arguments would fail only when the run starts, so
``netsim validate`` compares the signature of an object named by such a path with the call
(``inspect.signature``, nothing is run). Registered plugins are registered for exactly this call and are
not checked.

========== ===================================== ================================================
kind       build calls                           where
========== ===================================== ================================================
plant      ``factory(params)``                   :func:`netsim.build.builder.make_plant`
signal     ``cls(params)``                       ``builder._make_signals``
program    ``cls(ctx, params)``                  ``builder._program``
network    ``cls(env, name, params)``            :func:`netsim.network.make_network`
========== ===================================== ================================================
"""

from __future__ import annotations

import inspect
from typing import Any

__all__ = ["BUILD_CALLS", "call_problem"]

#: The arguments ``build`` passes to a plugin of each kind.
BUILD_CALLS: dict[str, tuple[str, ...]] = {
    "plant": ("params",),
    "signal": ("params",),
    "program": ("ctx", "params"),
    "network": ("env", "name", "params"),
}


def call_problem(kind: str, name: str, obj: Any) -> str | None:
    """Why ``build`` cannot call ``obj`` (the plugin ``name`` of ``kind``) with its arguments; None if it can.

    Objects whose signature Python cannot inspect (some builtins) are given the benefit of the doubt.
    """
    args = BUILD_CALLS.get(kind)
    if args is None:
        return None
    call = f"{_short(name)}({', '.join(args)})"
    if not callable(obj):
        return f"{kind} '{name}' is a {type(obj).__name__}, not something build can call as {call}"
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return None
    try:
        sig.bind(*args)
    except TypeError:
        required = [p.name for p in sig.parameters.values()
                    if p.default is inspect.Parameter.empty
                    and p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
        wants = f"({', '.join(required)})" if required else str(sig)
        return (f"{kind} '{name}' cannot be built from a scenario: build calls {call}, but it takes {wants}; "
                f"name a {kind} whose constructor takes exactly ({', '.join(args)}) (see `netsim list {kind}s`)")
    return None


def _short(name: str) -> str:
    return name.rpartition(":")[2].rpartition(".")[2] or name
