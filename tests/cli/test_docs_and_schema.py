"""``netsim docs`` (the scenario reference, committed as docs/scenario-reference.md and never stale) and
``netsim schema`` (a JSON Schema that accepts every shipped scenario and sweep file and flags a misspelt key)."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _netsim(*args: str) -> str:
    # a fresh process: the tests' own plugins (zzc_...) registered in this one stay out of the reference
    env = {**os.environ, "NETSIM_ALLOW_PLUGINS": "0"}
    done = subprocess.run([sys.executable, "-m", "netsim", *args], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=120, check=True)
    return done.stdout


@pytest.fixture(scope="module")
def reference() -> str:
    return _netsim("docs")


@pytest.fixture(scope="module")
def schema() -> dict[str, Any]:
    return json.loads(_netsim("schema"))


def test_the_committed_reference_is_what_netsim_docs_prints(reference):
    committed = (ROOT / "docs" / "scenario-reference.md").read_text(encoding="utf-8")
    assert committed == reference, "docs/scenario-reference.md is stale: run `netsim docs > docs/scenario-reference.md`"


def test_reference_lists_every_key_and_every_registered_plugin(reference):
    from netsim import registry

    for key in ("`duration` | duration | required | ns\\|us\\|ms\\|s", "`nodes.<name>.tasks[].period`",
                "`io.<name>.saturation`", "`factors.<name>.logspace.num`"):
        assert key in reference
    for kind in ("plant", "program", "network", "policy", "signal", "metric"):
        for entry in registry.entries(kind):
            if entry.obj.__module__.startswith(("netsim", "models")):
                assert f"`{entry.name}`" in reference, (kind, entry.name)
    # a plugin parameter with its type, default and unit (network can: the bit rate)
    can = reference[reference.index("### `can`"):]
    assert "| `bitrate` | bit rate |" in can.split("### ", 2)[1]


def _resolve(node: dict, root: dict) -> dict:
    while "$ref" in node:
        node = root["$defs"][node["$ref"].rsplit("/", 1)[1]]
    return node


_JSON_TYPES = {"string": str, "integer": int, "number": (int, float), "boolean": bool, "null": type(None),
               "object": dict, "array": list}


def _is(value: Any, kind: str) -> bool:
    if isinstance(value, bool) and kind in ("integer", "number"):
        return False
    return isinstance(value, _JSON_TYPES[kind])


def _problems(data: Any, node: dict, root: dict, path: str = "") -> list[str]:
    """Keys the schema does not allow, required keys that are missing, and values of the wrong JSON type (a
    minimal JSON Schema check: no jsonschema dependency)."""
    node = _resolve(node, root)
    if "if" in node and "properties" not in node:  # the root: a sweep file or a scenario
        branch = node["then"] if not _problems(data, node["if"], root, path) else node.get("else", {})
        return _problems(data, branch, root, path)
    for key in ("anyOf", "oneOf"):
        if key in node:
            options = [_problems(data, alt, root, path) for alt in node[key]]
            return [] if any(not o for o in options) else min(options, key=len)
    out: list[str] = []
    if "const" in node and data != node["const"]:
        return [f"{path}: expected {node['const']!r}"]
    for rule in node.get("allOf", []):  # if/then rules: a plugin's own parameters
        rule = _resolve(rule, root)
        if "if" in rule and not _problems(data, rule["if"], root, path):
            out += _problems(data, rule["then"], root, path)
        elif "if" not in rule:
            out += _problems(data, rule, root, path)
    wanted = node.get("type")
    if wanted is not None:
        kinds = wanted if isinstance(wanted, list) else [wanted]
        if not any(_is(data, k) for k in kinds):
            return [f"{path}: expected {' or '.join(kinds)}, got {type(data).__name__}"]
    if isinstance(data, dict) and ("properties" in node or "patternProperties" in node):
        props, extra = node.get("properties", {}), node.get("additionalProperties", True)
        if "allOf" in node:  # keys a rule's "then" lists are allowed too
            extra = True if extra is False and any(k not in props for k in data) and _allowed_by_rules(
                data, node, root) else extra
        patterns = node.get("patternProperties", {})
        for k, v in data.items():
            if k in props:
                out += _problems(v, props[k], root, f"{path}.{k}")
            elif patterns:
                matched = [p for p in patterns if re.search(p, str(k))]
                out += _problems(v, patterns[matched[0]], root, f"{path}.{k}") if matched else \
                    [f"{path}.{k}: name not allowed"]
            elif extra is False:
                out.append(f"{path}.{k}: not allowed")
            elif isinstance(extra, dict):
                out += _problems(v, extra, root, f"{path}.{k}")
        out += [f"{path}.{r}: missing" for r in node.get("required", []) if r not in data]
    elif isinstance(data, list) and isinstance(node.get("items"), dict):
        for i, v in enumerate(data):
            out += _problems(v, node["items"], root, f"{path}[{i}]")
    return out


def _allowed_by_rules(data: dict, node: dict, root: dict) -> bool:
    names: set[str] = set()
    for rule in node["allOf"]:
        if "if" in rule and not _problems(data, rule["if"], root):
            names |= set(rule["then"].get("properties", {}))
    return all(k in node.get("properties", {}) or k in names for k in data)


def test_schema_accepts_every_shipped_scenario_and_sweep_file(schema):
    from netsim.scenario.loader import read_yaml

    files = sorted((ROOT / "scenarios").glob("*.yaml"))
    assert len(files) >= 15
    for path in files:
        data = read_yaml(path)[0]
        assert _problems(data, schema, schema) == [], path.name


def test_schema_flags_a_misspelt_key_and_a_missing_one(schema):
    from netsim.scenario.loader import read_yaml

    data = read_yaml(ROOT / "scenarios" / "dc_servo_can.yaml")[0]
    data["duraton"] = data.pop("duration")
    data["nodes"]["sensor"]["tasks"][0]["perid"] = "10 ms"
    problems = _problems(data, schema, schema)
    assert ".duraton: not allowed" in problems and ".duration: missing" in problems
    assert ".nodes.sensor.tasks[0].perid: not allowed" in problems
    data["duration"] = [2]  # the wrong type for a time
    assert any(p.startswith(".duration: expected") and p.endswith("got list") for p in _problems(data, schema, schema))


def test_a_plugin_s_own_parameters_are_completed_and_checked(schema):
    from netsim.scenario.loader import read_yaml

    data = read_yaml(ROOT / "scenarios" / "dc_servo_can.yaml")[0]
    assert _problems(data, schema, schema) == []
    data["nodes"]["controller"]["tasks"][0]["params"]["Kp"] = 1.0  # the controller program's gain is K
    data["networks"]["can"]["bitrate"] = [80]  # the CAN bus's bit rate: a number or text with its unit
    problems = _problems(data, schema, schema)
    assert ".nodes.controller.tasks[0].params.Kp: not allowed" in problems
    assert any(p.startswith(".networks.can.bitrate: expected") for p in problems)
    defs = schema["$defs"]
    can_rule = next(r for r in defs["NetworkSpec"]["allOf"] if r["if"]["properties"]["type"]["const"] == "can")
    assert "min_frame_bits" in can_rule["then"]["properties"]  # what an editor offers after 'type: can'


def test_times_and_bit_rates_may_be_written_with_their_unit(schema):
    # pydantic derives "integer" for a time (integer ns) and "number" for a bit rate: an editor would flag the
    # "2 s" and "80 kbit/s" every scenario uses
    scenario = {"name": "x", "duration": "2 s", "networks": {"can": {"type": "can", "nodes": ["a"]}},
                "nodes": {"a": {"context_switch": "10 us", "tasks": [{"name": "t", "program": "idle",
                                                                       "period": "10 ms", "offset": 0}]}}}
    assert _problems(scenario, schema, schema) == []
