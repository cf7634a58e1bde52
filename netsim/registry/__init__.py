"""A small registry of named building blocks that scenario files refer to.

The engine never imports ``models/``; case-study modules register their plants, controllers, task
programs and the like under a *kind* and a name, and a scenario names them (``plant: {model: hdd}``) or
gives an import path (``"netsim.models.hdd:HddPlant"``). ``netsim list`` prints the registry, ``netsim list KIND
NAME`` one plugin's parameters (:mod:`netsim.registry.params`).

Where registered things come from (issue 14: a scenario file is data, it cannot name arbitrary code):

* netsim's own plugin modules (:data:`PLUGIN_MODULES`): every module of each listed package (``netsim.network``,
  ``models``, ...), so a new medium, program or case study is one file plus its ``@register`` line; no
  ``__init__`` has to import it. ``tests/test_registry.py`` reads every module of ``netsim/`` and ``models/``
  and fails when one that registers something is not covered by the list. They are loaded **lazily**
  (issue 19): :func:`lookup` reads the index of their ``@register("kind", "name")`` lines
  (:mod:`netsim.registry.index`, built from the sources without importing them and cached) and imports only
  the modules that declare the name asked for; :func:`load_plugins` (``netsim list``, ``netsim docs``,
  :func:`entries`) imports them all. ``tests/test_registry_index.py`` checks that both register the same;
* installed packages that declare a ``netsim.plugins`` entry point (each entry point names a module,
  imported by :func:`load_plugins`, or by a lookup of a name no netsim module declares; installing a package
  is the user's decision);
* plugin files, loaded by :func:`load_plugin_file` only when the scenario's ``plugins:`` list names them and
  the user allowed it (:mod:`netsim.trust`).

A module that fails to import is never skipped silently: :func:`plugin_failures` (and :func:`load_plugins`)
return it with its error (``netsim validate`` and ``netsim list`` print it as a warning), and a lookup of a
name that module declares says so. A name registered twice for two different
objects is an error (a plugin cannot shadow a built-in by accident).

A ``"module:attr"`` path (:func:`resolve`) is only another way to name a registered object: it must resolve
to an object registered under the kind, or to a subclass of the kind's base class (:data:`KIND_BASES`, e.g.
:class:`netsim.plant.Plant`). ``"os:system"`` or ``"subprocess:Popen"`` is refused without being called, and a
module that is not already imported is imported only when it is one of netsim's own (``netsim.*``,
``netsim.models.*``) or a ``netsim.plugins`` entry point.

Kinds (:data:`KINDS`), each looked up where a scenario names it:

``plant``
    ``plant: {model: NAME}``.
``controller``
    control designs a program builds by name (``et_controller``'s ``design:``; issue 16's control laws).
``estimator``
    state estimators (:class:`netsim.control.interface.StateEstimator`: ``correct``, ``predict``, ``x_hat``)
    that a controller program names as ``estimator: {type: NAME, ...}`` (issue 16: Kalman, Luenberger, EKF).
    Algorithms built only inside one case study (the cart's event estimators, the HDD's DOB) are not
    registered: no scenario can name them.
``network``, ``policy``, ``program``, ``signal``, ``metric``
    ``networks: {x: {type: NAME}}``, a node's ``policy:``, a task's ``program:``, ``signals: {x: {type: NAME}}``,
    ``metrics: [{type: NAME}]``.
``path_loss``
    a radio network's ``path_loss: {type: NAME, ...}`` (:mod:`netsim.network.path_loss`: TrueTime's user
    path-loss function).
``report``
    ``netsim report NAME`` (case-study report generators).

Each plugin describes its parameters with a nested pydantic ``Params`` model; ``netsim validate`` checks a
scenario's parameters with it and ``netsim list KIND NAME`` prints it. A field states its unit with
``Field(..., json_schema_extra={"unit": "rad/s"})``; time and bit-rate fields (:mod:`netsim.units`) carry theirs.

Examples
--------
>>> @register("plant", "double_integrator", "p'' = u")
... def make_double_integrator(params): ...
"""

from __future__ import annotations

import difflib
import hashlib
import importlib
import importlib.util
import inspect
import logging
import pkgutil
import re
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, TypeVar

from netsim.errors import ConfigError
from netsim.registry.params import TIME_UNIT, ParamRow, param_rows, params_model

__all__ = ["Entry", "KINDS", "KIND_BASES", "PLUGIN_MODULES", "ParamRow", "TIME_UNIT", "register", "lookup", "entries", "kinds",
           "load_plugins", "plugin_failures", "load_plugin_file", "plugin_file_loaded", "resolve", "is_builtin", "is_plugin_module",
           "params_model", "param_rows", "ENTRY_POINT_GROUP"]

KINDS = (
    "plant",
    "controller",
    "estimator",
    "network",
    "path_loss",
    "policy",
    "server",
    "program",
    "signal",
    "metric",
    "report",
)

T = TypeVar("T")

#: The base class (module, class name) a ``module:attr`` path of a kind may name besides registered objects.
KIND_BASES: dict[str, tuple[str, str]] = {
    "plant": ("netsim.plant", "Plant"),
    "signal": ("netsim.io.signals", "Signal"),
    "network": ("netsim.network.pipeline", "Network"),
    "policy": ("netsim.kernel.policies", "Policy"),
    "path_loss": ("netsim.network.path_loss", "PathLoss"),
}

#: Entry-point group of installed packages that bring netsim plugins (each entry point names a module).
ENTRY_POINT_GROUP = "netsim.plugins"

_DOTTED = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")


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

#: Modules imported from installed packages' ``netsim.plugins`` entry points (filled by :func:`_load_entry_points`).
_ENTRY_POINT_MODULES: list[str] = []
#: Plugin modules a lazy lookup failed to import: not tried again (the failure is in _PLUGIN_FAILURES).
_TRIED: set[str] = set()
#: Plugin files already executed: resolved path -> module name.
_PLUGIN_FILES: dict[str, str] = {}


#: netsim's own plugin modules and packages. :func:`load_plugins` imports each, and every module below a
#: listed package (a new file in ``netsim/network/`` or ``models/`` (``netsim.models``) registers without being imported anywhere).
#: The application layer (CLI, scenario loading, runner, sweeps, plots) is not listed: it uses plugins and
#: defines none, and ``tests/test_registry.py`` fails when a module outside these registers something. A lookup
#: imports only the modules that declare the name (:mod:`netsim.registry.index`); ``netsim list`` and ``netsim
#: docs`` import them all, so a module there imports heavy libraries (python-control, solvers, matplotlib)
#: inside the functions that use them.
PLUGIN_MODULES: list[str] = [
    "netsim.kernel",
    "netsim.network",
    "netsim.control",
    "netsim.metrics",
    "netsim.io.signals",
    "netsim.programs",
    "netsim.plant.described",
    "netsim.plant.fmu",
    "netsim.models",
]


def _origin(obj: Any) -> str:
    """``module:qualname`` of ``obj`` (what a duplicate-name error names)."""
    module = getattr(obj, "__module__", None) or "?"
    return f"{module}:{getattr(obj, '__qualname__', None) or type(obj).__name__}"


def register(kind: str, name: str, summary: str = "") -> Callable[[T], T]:
    """Decorator registering ``obj`` under ``kind``/``name`` with a one-line ``summary``.

    Raises
    ------
    ValueError
        For an unknown kind, or a name already registered for another object (another ``module:qualname``;
        the same definition imported again replaces its entry).
    """
    if kind not in _REGISTRY:
        raise ValueError(f"unknown registry kind {kind!r}; known: {', '.join(KINDS)}")

    def deco(obj: T) -> T:
        old = _REGISTRY[kind].get(name)
        if old is not None and old.obj is not obj and _origin(old.obj) != _origin(obj):
            raise ValueError(f"{kind} '{name}' is already registered by {_origin(old.obj)}; register "
                             f"{_origin(obj)} under another name")
        doc_lines = (getattr(obj, "__doc__", None) or "").strip().splitlines()
        text = summary or (doc_lines[0] if doc_lines else "")
        _REGISTRY[kind][name] = Entry(kind, name, text, obj)
        return obj

    return deco


def is_plugin_module(module_name: str) -> bool:
    """True when :func:`load_plugins` imports ``module_name`` (it is, or is below, a :data:`PLUGIN_MODULES` entry)."""
    return any(module_name == m or module_name.startswith(m + ".") for m in PLUGIN_MODULES)


def _failed(module_name: str, exc: BaseException, where: str = "") -> None:
    if any(m == module_name for m, _ in _PLUGIN_FAILURES):  # tried again by load_plugins after a lookup
        return
    _PLUGIN_FAILURES.append((module_name, f"{type(exc).__name__}: {exc}"))
    _log.warning("could not load plugin module %s%s: %s", module_name, where, exc)


def plugin_failures() -> list[tuple[str, str]]:
    """The ``(module, error)`` pairs of the plugin modules that failed to import so far in this process."""
    return list(_PLUGIN_FAILURES)


def _import_tree(module_name: str) -> None:
    """Import ``module_name`` and, for a package, every module below it (sorted; ``__main__`` excepted).

    A module that fails to import is recorded in ``_PLUGIN_FAILURES`` and its siblings are still imported.
    """
    try:
        module = importlib.import_module(module_name)
    except Exception as exc:  # noqa: BLE001 - recorded and reported (a broken module must not hide the others)
        _failed(module_name, exc)
        return
    path = getattr(module, "__path__", None)
    if path is None:
        return
    for info in sorted(pkgutil.iter_modules(path), key=lambda i: i.name):
        if info.name != "__main__":
            _import_tree(f"{module_name}.{info.name}")


def load_plugins() -> list[tuple[str, str]]:
    """Import netsim's plugin modules (:data:`PLUGIN_MODULES`, packages walked) and the entry points (idempotent).

    Each module is imported on its own: one that is missing or broken does not stop the others, and none is
    skipped silently. Returns the ``(module, error)`` pairs of the modules that failed (also logged), so
    callers can report them.
    """
    global _PLUGINS_LOADED
    if _PLUGINS_LOADED:
        return list(_PLUGIN_FAILURES)
    _PLUGINS_LOADED = True
    for mod in PLUGIN_MODULES:
        _import_tree(mod)
    _load_entry_points()
    return list(_PLUGIN_FAILURES)


def _load_entry_points() -> None:
    """Import the modules of the installed packages' ``netsim.plugins`` entry points not imported yet.

    Called by :func:`load_plugins` and by a lookup of a name no netsim module declares (each such miss reads
    the installed packages' metadata again: a few ms, on the path that ends in "unknown name" or imports a
    package installed since)."""
    for mod in _entry_point_modules():
        if mod in _ENTRY_POINT_MODULES or mod in _TRIED:
            continue
        try:
            importlib.import_module(mod)
            _ENTRY_POINT_MODULES.append(mod)
        except Exception as exc:  # noqa: BLE001 - an installed plugin package that is broken: reported
            _TRIED.add(mod)
            _failed(mod, exc, f" (entry point {ENTRY_POINT_GROUP})")


def _index(refresh: bool = False) -> Any:
    """The declarations of the plugin modules (:mod:`netsim.registry.index`), for the current PLUGIN_MODULES
    (``refresh``: look at the files again, for a module written since this process built the index)."""
    from netsim.registry.index import plugin_index

    return plugin_index(PLUGIN_MODULES, KINDS, refresh=refresh)


def _import_once(module_name: str) -> None:
    """Import one plugin module for a lookup; a failure is recorded, not raised, and not tried again.

    A module already imported costs a dictionary lookup; one that another thread is importing is waited for
    (the import system's per-module lock), so concurrent first lookups (a threaded sweep) find the name.
    """
    if module_name in _TRIED:
        return
    try:
        importlib.import_module(module_name)
    except Exception as exc:  # noqa: BLE001 - recorded and reported (a broken module must not hide the others)
        _TRIED.add(module_name)
        _failed(module_name, exc)


def _ensure(kind: str, name: str) -> None:
    """Import what registers ``kind``/``name`` when it is not registered yet: the modules the index names;
    then, for a name no module declares, the modules the index cannot read and the entry points."""
    if name in _REGISTRY[kind] or _PLUGINS_LOADED:
        return
    index = _index()
    if not index.modules_for(kind, name):
        index = _index(refresh=True)  # a miss: a plugin module may have been written since (a few ms of stat)
    for module in index.modules_for(kind, name):
        _import_once(module)
    if name in _REGISTRY[kind]:
        return
    for module in index.opaque:
        _import_once(module)
    if name not in _REGISTRY[kind]:
        _load_entry_points()


def _known_names(kind: str) -> list[str]:
    """Registered and declared names of ``kind`` (for "did you mean"), without importing anything."""
    names = set(_REGISTRY[kind])
    if not _PLUGINS_LOADED:
        names.update(_index().names(kind))
    return sorted(names)


def _entry_point_modules() -> list[str]:
    """Modules named by the ``netsim.plugins`` entry points of installed packages (``module`` or ``module:x``)."""
    from importlib import metadata

    try:
        points = metadata.entry_points(group=ENTRY_POINT_GROUP)
    except Exception:  # noqa: BLE001 - broken package metadata must not stop netsim
        _log.warning("could not read the %s entry points", ENTRY_POINT_GROUP, exc_info=True)
        return []
    return sorted({ep.value.partition(":")[0].strip() for ep in points})


def plugin_file_loaded(path: str | Path) -> bool:
    """True when the plugin file ``path`` (by resolved path) already ran in this process."""
    return str(Path(path).resolve()) in _PLUGIN_FILES


def load_plugin_file(path: str | Path) -> str:
    """Execute the Python file ``path`` once as a module, so that its ``register`` calls run.

    Only :mod:`netsim.scenario.loader` calls this, for the files a scenario's ``plugins:`` list names and only
    when the user allowed plugins (:mod:`netsim.trust`). The same file (by resolved path) runs once per process.

    Returns
    -------
    str
        The module name the file was loaded as (``netsim_plugin_<stem>_<hash>``, also in ``sys.modules``).

    Raises
    ------
    ConfigError
        When the file is missing or raises while it runs (the error is named, the traceback is logged).
    """
    real = Path(path).resolve()
    key = str(real)
    if key in _PLUGIN_FILES:
        return _PLUGIN_FILES[key]
    if not real.is_file():
        raise ConfigError(f"plugin file not found: {path}; fix the path in the scenario's plugins: list "
                          "(relative to the scenario file)")
    stem = re.sub(r"[^A-Za-z0-9_]", "_", real.stem)[:40]
    name = f"netsim_plugin_{stem}_{hashlib.sha256(key.encode()).hexdigest()[:8]}"
    spec = importlib.util.spec_from_file_location(name, real)
    if spec is None or spec.loader is None:
        raise ConfigError(f"cannot load plugin file {path}: not a Python source file")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # noqa: BLE001 - the user's plugin file may raise anything
        del sys.modules[name]
        _log.debug("plugin file %s failed", path, exc_info=True)
        raise ConfigError(f"plugin file {path} failed to load ({type(exc).__name__}: {exc}); fix the file") from None
    _PLUGIN_FILES[key] = name
    return name


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
        return resolve(name, kind)
    if kind not in _REGISTRY:
        raise ValueError(f"unknown registry kind {kind!r}; known: {', '.join(KINDS)}")
    _ensure(kind, name)
    table = _REGISTRY[kind]
    if name in table:
        return table[name].obj
    broken = [(m, e) for m, e in _PLUGIN_FAILURES if m in _index().modules_for(kind, name)]
    if broken:
        raise ConfigError(f"{kind} '{name}' is unavailable: its module '{broken[0][0]}' failed to import "
                          f"({broken[0][1]}); fix that module")
    known = [n for n in _known_names(kind)]
    close = difflib.get_close_matches(name, known, n=1)
    hint = f"; did you mean '{close[0]}'?" if close else f" (known: {', '.join(known) or 'none'})"
    raise ConfigError(f"unknown {kind} '{name}'{hint}")


def is_builtin(obj: Any) -> bool:
    """True when ``obj`` comes from one of netsim's own plugin modules (:data:`PLUGIN_MODULES` and below).

    ``netsim validate`` constructs such plugins (a plant, a network) to run build's own checks; it never calls
    code from anywhere else (a scenario's ``module:attr`` path, a user's plugin module, a test double).
    """
    module = getattr(obj, "__module__", None)
    return isinstance(module, str) and is_plugin_module(module)


def _trusted_module(module_name: str) -> bool:
    """Whether ``module_name`` may be imported to resolve a path: netsim's own modules and entry points."""
    def under(roots: list[str]) -> bool:
        return any(module_name == r or module_name.startswith(r + ".") for r in roots)

    if under(["netsim", *PLUGIN_MODULES, *_ENTRY_POINT_MODULES, *_PLUGIN_FILES.values()]):
        return True
    return under(_entry_point_modules())  # an installed plugin package that no lookup has imported yet


def _base(kind: str) -> type | None:
    where = KIND_BASES.get(kind)
    if where is None:
        return None
    return getattr(importlib.import_module(where[0]), where[1])


def _is_registered(kind: str, obj: Any) -> bool:
    return any(entry.obj is obj for entry in _REGISTRY[kind].values())


def resolve(path: str, kind: str) -> Any:
    """The registered plugin of ``kind`` that ``"package.module:attribute"`` names.

    Nothing is called, and a module is imported only when it is already imported or is one of netsim's own,
    a ``netsim.plugins`` entry point or a loaded plugin file; the object must be registered under ``kind``
    or be a subclass of the kind's base class (:data:`KIND_BASES`).

    Raises
    ------
    ConfigError
        For a malformed path, a module that is not trusted and not loaded, a missing attribute, or an
        object that is not a registered ``kind`` (``"os:system"``).
    """
    if kind not in _REGISTRY:
        raise ValueError(f"unknown registry kind {kind!r}; known: {', '.join(KINDS)}")
    module_name, _, attr = path.partition(":")
    shown = path if len(path) <= 80 else path[:80] + "..."
    listing = f"`netsim list {'policies' if kind == 'policy' else kind + 's'}`"
    if not _DOTTED.match(module_name) or not _DOTTED.match(attr) or "__" in path:  # no __main__, __class__
        raise ConfigError(f"'{shown}' is not a plugin path; write a registered {kind} name (see {listing}) or "
                          "'package.module:Class'")
    module = sys.modules.get(module_name)
    if module is None:
        if not _trusted_module(module_name):
            raise ConfigError(
                f"'{shown}' names module '{module_name}', which netsim does not import for a scenario: name a "
                f"registered {kind} (see {listing}), or list the file that registers it in the scenario's "
                "'plugins:' and run with --allow-plugins")
        try:
            module = importlib.import_module(module_name)
        except ImportError as exc:
            raise ConfigError(f"cannot import module '{module_name}' from '{shown}': {exc}") from None
    try:
        obj: Any = module
        for part in attr.split("."):
            obj = getattr(obj, part)
    except AttributeError:
        raise ConfigError(f"module '{module_name}' has no attribute '{attr}'") from None
    base = _base(kind)
    if not _is_registered(kind, obj) and not (base is not None and isinstance(obj, type) and issubclass(obj, base)):
        load_plugins()  # registered elsewhere than where it is defined: known only once everything is imported
    if _is_registered(kind, obj) or (base is not None and isinstance(obj, type) and issubclass(obj, base)):
        if inspect.isabstract(obj):
            raise ConfigError(f"'{shown}' is an abstract base class; name a concrete {kind} (see {listing})")
        return obj
    what = f"a registered {kind}" + (f" or a subclass of {'.'.join(KIND_BASES[kind])}" if base else "")
    raise ConfigError(f"'{shown}' is not {what}; a scenario may name only registered plugins (see {listing})")
