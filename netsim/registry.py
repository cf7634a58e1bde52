"""A small registry of named building blocks that scenario files refer to.

The engine never imports ``models/``; case-study modules register their plants, controllers, task
programs and the like under a *kind* and a name, and a scenario names them (``plant: {model: hdd}``) or
gives an import path (``"models.hdd:HddPlant"``). ``netsim list`` prints the registry.

Kinds used by netsim: ``plant``, ``controller``, ``estimator``, ``trigger``, ``network``, ``policy``,
``program`` (task/handler bodies that scenario tasks run), ``signal`` (reference/disturbance shapes),
``metric`` (functions computing a run's metrics from its tables),
``report`` (case-study report generators).

Examples
--------
>>> @register("plant", "double_integrator", "p'' = u")
... def make_double_integrator(params): ...
"""

from __future__ import annotations

import difflib
import importlib
import logging
from dataclasses import dataclass
from typing import Any, Callable, TypeVar

from netsim.errors import ConfigError

__all__ = ["Entry", "register", "lookup", "entries", "kinds", "load_plugins", "resolve", "is_builtin"]

KINDS = (
    "plant",
    "controller",
    "estimator",
    "trigger",
    "network",
    "policy",
    "program",
    "signal",
    "metric",
    "report",
)

T = TypeVar("T")


@dataclass(frozen=True)
class Entry:
    """One registered object: its kind, name, one-line summary and the object itself."""

    kind: str
    name: str
    summary: str
    obj: Any


_REGISTRY: dict[str, dict[str, Entry]] = {k: {} for k in KINDS}
_PLUGINS_LOADED = False
_PLUGIN_FAILURES: list[tuple[str, str]] = []
_log = logging.getLogger(__name__)

#: Modules imported by :func:`load_plugins` so their ``register`` calls run.
PLUGIN_MODULES: list[str] = [
    "netsim.kernel",
    "netsim.network",
    "netsim.control",
    "netsim.metrics",
    "netsim.runtime_metrics",
    "netsim.signals",
    "netsim.programs",
    "models",
]


def register(kind: str, name: str, summary: str = "") -> Callable[[T], T]:
    """Decorator registering ``obj`` under ``kind``/``name`` with a one-line ``summary``."""
    if kind not in _REGISTRY:
        raise ValueError(f"unknown registry kind {kind!r}; known: {', '.join(KINDS)}")

    def deco(obj: T) -> T:
        doc_lines = (getattr(obj, "__doc__", None) or "").strip().splitlines()
        text = summary or (doc_lines[0] if doc_lines else "")
        _REGISTRY[kind][name] = Entry(kind, name, text, obj)
        return obj

    return deco


def load_plugins() -> list[tuple[str, str]]:
    """Import the modules that register things (idempotent).

    Each module is imported on its own: one that is missing or broken does not stop the others. Returns the
    ``(module, error)`` pairs of the modules that failed (also logged), so callers can report them.
    """
    global _PLUGINS_LOADED
    if _PLUGINS_LOADED:
        return list(_PLUGIN_FAILURES)
    _PLUGINS_LOADED = True
    for mod in PLUGIN_MODULES:
        try:
            importlib.import_module(mod)
        except ModuleNotFoundError as exc:
            if exc.name is not None and mod.startswith(exc.name):
                continue  # an optional plugin package that is not there
            _PLUGIN_FAILURES.append((mod, f"{type(exc).__name__}: {exc}"))
            _log.warning("could not load plugin module %s: %s", mod, exc)
        except Exception as exc:  # a broken plugin must not hide the others
            _PLUGIN_FAILURES.append((mod, f"{type(exc).__name__}: {exc}"))
            _log.warning("could not load plugin module %s: %s", mod, exc)
    return list(_PLUGIN_FAILURES)


def entries(kind: str) -> list[Entry]:
    """Registered entries of ``kind``, sorted by name."""
    load_plugins()
    return sorted(_REGISTRY[kind].values(), key=lambda e: e.name)


def kinds() -> tuple[str, ...]:
    """All registry kinds."""
    return KINDS


def lookup(kind: str, name: str) -> Any:
    """The object registered as ``kind``/``name``, or one loaded from a ``"module:attr"`` path.

    Raises
    ------
    ConfigError
        When the name is unknown (with the closest registered name) or the path cannot be imported.
    """
    if ":" in name:
        return resolve(name)
    load_plugins()
    table = _REGISTRY[kind]
    if name in table:
        return table[name].obj
    close = difflib.get_close_matches(name, list(table), n=1)
    hint = f"; did you mean '{close[0]}'?" if close else f" (known: {', '.join(sorted(table)) or 'none'})"
    raise ConfigError(f"unknown {kind} '{name}'{hint}")


def is_builtin(obj: Any) -> bool:
    """True when ``obj`` comes from one of netsim's own plugin modules (:data:`PLUGIN_MODULES` and below).

    ``netsim validate`` constructs such plugins (a plant, a network) to run build's own checks; it never calls
    code from anywhere else (a scenario's ``module:attr`` path, a user's plugin module, a test double).
    """
    module = getattr(obj, "__module__", None)
    if not isinstance(module, str):
        return False
    return any(module == m or module.startswith(m + ".") for m in PLUGIN_MODULES)


def resolve(path: str) -> Any:
    """Import ``"package.module:attribute"`` and return the attribute."""
    module_name, _, attr = path.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise ConfigError(f"cannot import module '{module_name}' from '{path}': {exc}") from None
    try:
        obj: Any = module
        for part in attr.split("."):
            obj = getattr(obj, part)
    except AttributeError:
        raise ConfigError(f"module '{module_name}' has no attribute '{attr}'") from None
    return obj
