"""Overrides (``netsim run --set``, ``overrides=`` from Python, ``baseline.overrides``) and the ones a scenario
shadows.

An override writes a value at a dotted path of the raw scenario before the one validation
(:func:`apply_overrides`). Most fields act by their own value, but a *preset-like* field acts only through the
defaults it gives its siblings: the cart friction's ``model: modes6`` sets ``wavelength``, ``speedup``, ``modes``
and ``spread`` unless they are given. When the scenario spells those siblings out, an override of the preset
alone would change nothing. :func:`shadowed_overrides` finds such overrides once the scenario has validated,
for any parameter model, by asking the model itself: with the siblings left out, do their defaults differ
between the old and the new value of the field?

* A sibling the scenario gives with the *old* value's default (the preset spelled out, as ``scenarios/cart.yaml``
  does) follows the override: it is removed from the raw data, so the new preset fills it.
* A sibling the scenario gives with a value of its own shadows the override: the override is refused, with a
  message naming those siblings, the values the override would give them, and what to do.

A field counts as preset-like when its value is a name (text) and it changes the defaults of its siblings. A
field that is a value in its own right keeps the plain rule (a task's ``period`` moves the *default* deadline;
an explicit ``deadline`` stays as given).
"""

from __future__ import annotations

import enum
import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Mapping

from pydantic import BaseModel

from netsim.errors import ConfigError
from netsim.scenario.paths import PathPart, format_path, get_path, parse_path, set_path
from netsim.scenario.problems import Problem
from netsim.scenario.python_values import plain_values
from netsim.scenario.schema import PluginSpec

if TYPE_CHECKING:
    from netsim.scenario.schema import Scenario

__all__ = ["Applied", "apply_overrides", "shadowed_overrides"]

log = logging.getLogger(__name__)


class _Missing:
    def __repr__(self) -> str:
        return "<missing>"


#: The value before an override of a key the scenario did not have.
MISSING: Any = _Missing()


@dataclass(frozen=True)
class Applied:
    """One override written into the raw scenario: its key, path parts, the value before (or
    :data:`MISSING`) and the value written."""

    key: str
    parts: tuple[PathPart, ...]
    before: Any
    value: Any


def apply_overrides(raw: dict[str, Any], overrides: Mapping[str, Any] | None) -> tuple[list[Applied], list[Problem]]:
    """Write ``{"dotted.path": value}`` into ``raw`` (in place); values from Python are made plain first
    (:func:`~netsim.scenario.python_values.plain_values`).

    Returns
    -------
    applied
        The overrides written, in order (for :func:`shadowed_overrides`).
    problems
        One per override that could not be written (a misspelt key, an index out of range ...), at its key.
    """
    applied: list[Applied] = []
    problems: list[Problem] = []
    for key, value in (overrides or {}).items():
        try:
            parts = parse_path(key)
            plain, refused = plain_values(value, parts, raw)
            if refused:
                problems += refused
                continue
            try:
                before = get_path(raw, parts)
            except ConfigError:
                before = MISSING
            set_path(raw, key, plain)
        except ConfigError as exc:
            problems.append(Problem(str(key), f"cannot apply override: {exc.message}"))
            continue
        applied.append(Applied(str(key), tuple(parts), before, plain))
    return applied, problems


def shadowed_overrides(raw: dict[str, Any], scenario: Scenario, applied: list[Applied]) -> tuple[list[Problem], bool]:
    """The overrides of preset-like fields that siblings given in the scenario hide (see the module docstring).

    Parameters
    ----------
    raw
        The raw scenario the overrides were applied to; siblings that only spell out the old preset are removed
        from it.
    scenario
        ``raw`` validated (a :class:`~netsim.scenario.schema.Scenario`): where the parameter models are found.
    applied
        What :func:`apply_overrides` wrote.

    Returns
    -------
    problems
        One error per refused override, at its key.
    changed
        True when ``raw`` was changed: it must be validated again.
    """
    problems: list[Problem] = []
    changed = False
    given = {a.parts for a in applied}
    for item in applied:
        if not item.parts or not isinstance(item.parts[-1], str) or isinstance(item.value, (dict, list)):
            continue
        parent, field = item.parts[:-1], item.parts[-1]
        model = _model_at(scenario, parent)
        if isinstance(model, PluginSpec) and field not in type(model).model_fields:
            model = model._validated  # a parameter written inline (plant: {type: NAME, preset: ...})
        if not isinstance(model, BaseModel) or field not in type(model).model_fields:
            continue
        try:
            siblings = get_path(raw, parent)
        except ConfigError:  # not reachable (set_path made it): nothing there can hide the override
            continue
        if not isinstance(siblings, dict):
            continue
        found = _shadowing(model, siblings, field, item, given)
        if found is None:
            continue
        spelled, own, new = found
        if own:
            problems.append(Problem(item.key, _message(item, parent, own, new, model)))
            continue
        for name in spelled:
            del siblings[name]
        changed = True
        log.info("override %s=%r: %s follow it (the scenario gave the previous value's defaults)", item.key,
                 item.value, ", ".join(spelled))
    return problems, changed


def _shadowing(model: BaseModel, siblings: dict[str, Any], field: str, item: Applied,
               given: set[tuple[PathPart, ...]]) -> tuple[list[str], list[str], BaseModel] | None:
    """``(spelled, own, new)``: the siblings that hide the override of ``field``, split into those given with
    the old value's default and those given with values of their own, and the model validated with the new value
    and those siblings left out; None when nothing hides it (or ``field`` is not preset-like)."""
    cls = type(model)
    fields = cls.model_fields
    value = getattr(model, field)
    if not isinstance(value, (str, enum.Enum)):
        return None  # a value in its own right, not a name that picks defaults
    before = item.before
    if before is MISSING:
        default = fields[field].get_default(call_default_factory=True)
        if default is None and fields[field].is_required():
            return None
        before = default
    if before == item.value:
        return None
    parent = item.parts[:-1]
    candidates = [k for k in siblings if k != field and k in fields and not fields[k].is_required()
                  and (*parent, k) not in given]
    if not candidates:
        return None
    kept = {k: v for k, v in siblings.items() if k in fields and k not in candidates}
    try:
        new = cls.model_validate({**kept, field: item.value})
        old = cls.model_validate({**kept, field: before})
    except Exception:  # noqa: BLE001 - without its siblings the model may not validate: nothing to compare
        return None
    moved = [k for k in candidates if getattr(new, k) != getattr(old, k)]
    hiding = [k for k in moved if getattr(model, k) != getattr(new, k)]
    if not hiding:
        return None
    spelled = [k for k in hiding if getattr(model, k) == getattr(old, k)]
    own = [k for k in hiding if k not in spelled]
    return spelled, own, new


def _message(item: Applied, parent: tuple[PathPart, ...], own: list[str], new: BaseModel, model: BaseModel) -> str:
    field = item.parts[-1]
    it = "it" if len(own) == 1 else "them"
    given = ", ".join(f"{k}: {_show(getattr(model, k))}" for k in own)
    sets = ", ".join(f"{format_path([*parent, k])}={_show(getattr(new, k))}" for k in own)
    return (f"override {field}={_show(item.value)} is shadowed: {field} '{_show(item.value)}' only gives defaults, and "
            f"the scenario sets {given} explicitly, which wins; override {it} too ({sets}) or remove {it} from the "
            "scenario")


def _show(value: Any) -> str:
    if isinstance(value, enum.Enum):
        value = value.value
    return repr(value) if isinstance(value, str) and (" " in value or not value) else str(value)


def _model_at(scenario: Scenario, parts: tuple[PathPart, ...]) -> BaseModel | None:
    """The validated parameter model at the raw path ``parts`` of ``scenario`` (None when there is none)."""
    node: Any = scenario
    for part in parts:
        node = _child(node, part)
        if node is None:
            return None
    return node if isinstance(node, BaseModel) else None


def _child(node: Any, part: PathPart) -> Any:
    if isinstance(node, PluginSpec):
        if part != "params" and isinstance(part, str) and part in type(node).model_fields:
            return getattr(node, part)
        params = node._validated
        if part == "params":
            return params
        node = params  # a parameter written inline (plant: {type: ss, A: ...}, networks, signals)
    if isinstance(node, BaseModel):
        if not isinstance(part, str) or part not in type(node).model_fields:
            return None
        value = getattr(node, part)
        if isinstance(value, dict):
            return _nested(node, part) or value
        return value
    if isinstance(node, dict):
        return node.get(part)
    if isinstance(node, (list, tuple)) and isinstance(part, int) and 0 <= part < len(node):
        return node[part]
    return None


def _nested(model: BaseModel, field: str) -> BaseModel | None:
    """The parameters a model hands to another plugin (``nested_params()``), validated, for ``field``."""
    hook = getattr(model, "nested_params", None)
    if not callable(hook):
        return None
    try:
        for name, cls, raw in hook():
            if name == field and isinstance(cls, type) and issubclass(cls, BaseModel):
                return cls.model_validate(raw)
    except Exception:  # noqa: BLE001 - the loader has reported what does not validate
        return None
    return None
