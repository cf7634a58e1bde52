"""The JSON Schema of scenario and sweep files (``netsim schema``), for editors with a YAML language server.

Built from the pydantic models (:class:`~netsim.scenario.schema.Scenario`, :class:`~netsim.sweep.spec.SweepSpec`)
and every registered plugin's ``Params`` model, then tightened towards what ``netsim validate`` refuses without
looking at other parts of the file:

- two roots: a file with a ``sweep`` key is checked as a sweep file, any other as a scenario (``if``/``then``/
  ``else``), so a scenario's mistake is never also reported as a sweep's missing keys;
- the names of registered plugins as enums (plant models and types, programs, policies, network, signal and
  metric types, the state estimators and control laws of a program's ``estimator``/``law``), a ``module:attr``
  path also accepted;
- each plugin's parameters as its own subschema selected by its name (``if: {type: can} then: ...``), refusing
  unknown keys, inline (networks, signals, ``plant: {type: ...}``) or under ``params``;
- times, bit rates, powers and energies as text with the same grammar the parsers read (:mod:`netsim.timebase`,
  :mod:`netsim.quantities`): a pattern, and a bare number only where the parser takes one (a time only as 0);
- matrices read by :func:`netsim.plant.described._matrix` also as a number or a 1-D list (``B: [0, 1000]``).

A scenario with its own ``plugins:`` (files that register further names) is checked at its top level only: the
schema cannot know the names those files register. What needs a cross-reference (a task naming a network that
the file does not declare, a matrix whose shape must match another) is left to ``netsim validate``.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from pydantic import BaseModel

__all__ = ["json_schema"]

#: Where each plugin kind is named in a file: (spec definition, the key naming the plugin, its parameters are
#: inline beside that key rather than under ``params``).
_PLUGIN_SLOTS: tuple[tuple[str, str, str, bool], ...] = (
    ("network", "NetworkSpec", "type", True),
    ("signal", "SignalSpec", "type", True),
    ("plant", "PlantSpec", "type", True),
    ("plant", "PlantSpec", "model", False),
    ("program", "TaskSpec", "program", False),
    ("program", "HandlerSpec", "program", False),
    ("metric", "MetricSpec", "type", False),
)

#: Fields of a program's parameters that hold another plugin, written ``{type: NAME, its parameters}``.
_NESTED_PLUGINS: dict[str, str] = {"estimator": "estimator", "law": "controller"}
#: Fields of a program's parameters that name another plugin (text).
_NAMED_PLUGINS: dict[str, str] = {"design": "controller"}

#: A ``package.module:attribute`` path, the other way to name a plugin (:func:`netsim.registry.lookup`).
_PATH_PATTERN = r"^[A-Za-z_][A-Za-z0-9_.]*:[A-Za-z_][A-Za-z0-9_.]*$"


def _reachable_models(roots: list[type[BaseModel]]) -> list[type[BaseModel]]:
    """The pydantic models reachable from ``roots`` through field annotations (dict, list, union, nested)."""
    from netsim.cli.model_fields import models_in as _models_in

    out: list[type[BaseModel]] = []
    todo = list(roots)
    while todo:
        model = todo.pop(0)
        if model in out:
            continue
        out.append(model)
        for field in model.model_fields.values():
            todo += [m for _, m in _models_in(field.annotation) if m not in out]
    return out


def _name_choice(names: list[str], node: dict[str, Any]) -> dict[str, Any]:
    """``node`` (a text field naming a plugin) limited to ``names`` or a ``module:attr`` path."""
    keep = {k: v for k, v in node.items() if k in ("title", "default", "description")}
    return {**keep, "anyOf": [{"enum": sorted(names)}, {"type": "string", "pattern": _PATH_PATTERN}]}


def _text_form(kind: str) -> list[dict[str, Any]]:
    """The alternatives a unit field accepts: its text pattern, and the bare number the parser takes."""
    from netsim.units import BITRATE_PATTERN, SIGNED_TIME_PATTERN, TIME_PATTERN

    if kind == "bit rate":
        return [{"type": "number", "exclusiveMinimum": 0},
                {"type": "string", "pattern": BITRATE_PATTERN, "description": "a bit rate: 80 kbit/s, 1 Mbit/s"}]
    pattern = SIGNED_TIME_PATTERN if kind == "signed time" else TIME_PATTERN
    text = {"type": "string", "pattern": pattern, "description": "a time with its unit: 20 us, 1.5 ms, 2 s"}
    return [text] if kind == "duration" else [{"const": 0}, text]


def _accept_text(node: Any, kind: str) -> Any:
    """``node`` with the alternatives pydantic derives for a ``kind`` value replaced by its text forms: an integer
    for a time (integer ns), a number for a bit rate. Other numbers in the field stay (``path: {TIME: [x, y]}``)."""
    if isinstance(node, list):
        return [_accept_text(n, kind) for n in node]
    if not isinstance(node, dict):
        return node
    node = {k: _accept_text(v, kind) for k, v in node.items()}
    if node.get("type") == ("number" if kind == "bit rate" else "integer"):
        keep = {k: v for k, v in node.items() if k in ("title", "default", "description")}
        return {**keep, "anyOf": _text_form(kind)}
    return node


def _is_matrix(node: Any) -> bool:
    return (isinstance(node, dict) and node.get("type") == "array" and isinstance(node.get("items"), dict)
            and node["items"].get("type") == "array" and node["items"].get("items", {}).get("type") == "number")


def _widen_matrix(node: Any) -> Any:
    """A 2-D number array node also accepting a number and a 1-D list (what ``_matrix`` reads)."""
    if isinstance(node, list):
        return [_widen_matrix(n) for n in node]
    if not isinstance(node, dict):
        return node
    if _is_matrix(node):
        keep = {k: v for k, v in node.items() if k in ("title", "default", "description")}
        bare = {k: v for k, v in node.items() if k not in keep}
        return {**keep, "anyOf": [bare, {"type": "array", "items": {"type": "number"}}, {"type": "number"}]}
    return {k: _widen_matrix(v) for k, v in node.items()}


def _before_fields(model: type[BaseModel]) -> set[str]:
    """Fields of ``model`` with a ``mode="before"`` field validator (they read more than the annotation says)."""
    out: set[str] = set()
    for dec in model.__pydantic_decorators__.field_validators.values():
        if dec.info.mode == "before":
            out |= set(dec.info.fields)
    return out


def _def_of(defs: dict[str, Any], refs: dict[Any, Any], model: type[BaseModel]) -> dict[str, Any] | None:
    ref = refs.get((model, "validation"))
    name = ref["$ref"].rsplit("/", 1)[1] if ref else model.__name__
    return defs.get(name)


def _tighten_fields(defs: dict[str, Any], refs: dict[Any, Any], models: list[type[BaseModel]]) -> None:
    """Unit fields take their text forms; matrices their 1-D and scalar forms."""
    from netsim.registry import param_rows

    for model in models:
        target = _def_of(defs, refs, model)
        if target is None or "properties" not in target:
            continue
        props = target["properties"]
        for row in param_rows(model):
            if "." in row.name or row.name not in props:
                continue
            kind = next((k for k in ("bit rate", "signed time", "duration", "time") if k in row.type), None)
            if kind is not None:
                props[row.name] = _accept_text(props[row.name], kind)
        for name in _before_fields(model):
            field = model.model_fields.get(name)
            shown = (field.alias or name) if field is not None else name
            if shown in props:
                props[shown] = _widen_matrix(props[shown])


def _inline_rule(spec: dict[str, Any], key: str, name: str, own: dict[str, Any]) -> dict[str, Any]:
    """``if <key> is NAME then`` the spec's own keys and the plugin's parameters, nothing else."""
    fixed = {k: v for k, v in spec.get("properties", {}).items() if k not in ("params", "model")}
    props = {**own.get("properties", {}), **fixed, key: {"const": name},
             "params": {"type": "object", "description": "parameters (also allowed beside the type)"}}
    then: dict[str, Any] = {"properties": props, "additionalProperties": False}
    required = [r for r in own.get("required", []) if r not in fixed]
    if required:  # the parameters may also come under params
        then["allOf"] = [{"anyOf": [{"required": required}, {"required": ["params"]}]}]
    return {"if": {"properties": {key: {"const": name}}, "required": [key]}, "then": then}


def _plugin_rules(defs: dict[str, Any], refs: dict[Any, Any], names: dict[str, list[str]],
                  params_of: dict[str, dict[str, type]]) -> None:
    """Per plugin slot: the name field as an enum, and per registered plugin its own parameters."""
    for kind, spec_name, key, inline in _PLUGIN_SLOTS:
        spec = defs.get(spec_name)
        if spec is None:
            continue
        props = spec.setdefault("properties", {})
        props[key] = _name_choice(names.get(kind, []), props.get(key, {"type": "string"}))
        rules = spec.setdefault("allOf", [])
        for name, model in sorted(params_of.get(kind, {}).items()):
            ref = refs[(model, "validation")]
            if inline:
                rules.append(_inline_rule(spec, key, name, defs[ref["$ref"].rsplit("/", 1)[1]]))
            else:
                rules.append({"if": {"properties": {key: {"const": name}}, "required": [key]},
                              "then": {"properties": {"params": ref}}})
    plant = defs.get("PlantSpec")
    if plant is not None:  # {model: NAME, params: {...}}: the plant section's own keys only
        own = {k: v for k, v in plant["properties"].items() if k != "type"}
        plant["allOf"].append({"if": {"properties": {"model": {"type": "string"}}, "required": ["model"]},
                               "then": {"properties": own, "additionalProperties": False}})


def _nested_rules(defs: dict[str, Any], refs: dict[Any, Any], names: dict[str, list[str]],
                  params_of: dict[str, dict[str, type]]) -> None:
    """A program parameter holding a state estimator or control law (``estimator: {type: kalman, Q: ...}``): its
    type as an enum and its parameters by type; a parameter naming a controller design as an enum."""
    for model in params_of.get("program", {}).values():
        target = _def_of(defs, refs, model)
        if target is None:
            continue
        props = target.get("properties", {})
        for field, kind in _NESTED_PLUGINS.items():
            node = props.get(field)
            if not (isinstance(node, dict) and node.get("type") == "object" and "properties" not in node):
                continue
            node["properties"] = {"type": _name_choice(names.get(kind, []), {"type": "string"})}
            rules = []
            for name, sub in sorted(params_of.get(kind, {}).items()):
                own = defs[refs[(sub, "validation")]["$ref"].rsplit("/", 1)[1]]
                rules.append(_inline_rule({"properties": {}}, "type", name, own))
            node["allOf"] = rules
        for field, kind in _NAMED_PLUGINS.items():
            node = props.get(field)
            if isinstance(node, dict) and node.get("type") == "string":
                props[field] = _name_choice(names.get(kind, []), node)


def _inline_sections(defs: dict[str, Any]) -> None:
    """Sections that take their plugin's parameters beside the name (networks, signals, ``plant: {type: ...}``: a
    model validator gathers them into ``params`` before validation) accept other keys (the plugin's rule limits
    them), and their ``params`` may be left out."""
    for spec_name in dict.fromkeys(spec for _, spec, _, inline in _PLUGIN_SLOTS if inline):
        target = defs.get(spec_name)
        if target is None or "params" not in target.get("properties", {}):
            continue
        target["additionalProperties"] = True
        target["required"] = [r for r in target.get("required", []) if r == "type" and "model" not in
                              target["properties"]]
        if not target["required"]:
            del target["required"]


def _registered() -> tuple[dict[str, list[str]], dict[str, dict[str, type]]]:
    """The registered names per kind and the ``Params`` model of each (kinds a file can name)."""
    from netsim import registry

    kinds = ("plant", "program", "policy", "network", "signal", "metric", "estimator", "controller")
    names: dict[str, list[str]] = {}
    params_of: dict[str, dict[str, type]] = {}
    for kind in kinds:
        for entry in registry.entries(kind):
            names.setdefault(kind, []).append(entry.name)
            model = registry.params_model(entry.obj)
            if model is not None:
                params_of.setdefault(kind, {})[entry.name] = model
    return names, params_of


def json_schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of scenario and sweep files (see the module docstring)."""
    from pydantic.json_schema import models_json_schema

    from netsim.scenario.schema import Scenario
    from netsim.sweep.spec import SweepSpec

    names, params_of = _registered()
    plugin_models = list(dict.fromkeys(m for by_name in params_of.values() for m in by_name.values()))
    refs, schema = models_json_schema([(Scenario, "validation"), (SweepSpec, "validation"),
                                       *((m, "validation") for m in plugin_models)],
                                      ref_template="#/$defs/{model}")
    models = _reachable_models([Scenario, SweepSpec, *plugin_models])
    defs = schema.get("$defs", {})
    _tighten_fields(defs, refs, models)
    _inline_sections(defs)
    _plugin_rules(defs, refs, names, params_of)
    _nested_rules(defs, refs, names, params_of)
    node = defs.get("NodeSpec", {}).get("properties", {})
    if "policy" in node:
        node["policy"] = _name_choice(names.get("policy", []), node["policy"])
    scenario_ref, sweep_ref = refs[(Scenario, "validation")], refs[(SweepSpec, "validation")]
    scenario_def = defs[scenario_ref["$ref"].rsplit("/", 1)[1]]
    own_plugins = {  # a scenario that loads its own plugin files: its top level only
        "type": "object", "properties": {k: {} for k in scenario_def.get("properties", {})},
        "additionalProperties": False, "required": list(scenario_def.get("required", []))}
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "netsim scenario or sweep file",
        "description": "A netsim scenario (name, duration, plant, nodes, ...) or, with a 'sweep' key, a sweep file "
                       "(sweep, base, factors). Generated by `netsim schema`.",
        "if": {"type": "object", "properties": {"sweep": {}}, "required": ["sweep"]},
        "then": copy.deepcopy(sweep_ref),
        "else": {"if": {"type": "object", "required": ["plugins"], "properties": {"plugins": {"minItems": 1}}},
                 "then": own_plugins, "else": copy.deepcopy(scenario_ref)},
        "$defs": defs,
    }
