"""docs/truetime-mapping.md cannot go stale: every TrueTime call issue 27 names has a row, every Python example runs
(and passes its own asserts), every YAML example merged into the page's first (whole) scenario loads and runs,
and every netsim name the tables cite exists (``job.``/``kernel.``/``result.`` attributes, ``netsim.`` dotted
names, ``nodes.<n>.`` keys of the scenario file, and ``program:``/``policy:``/``type:`` registered names)."""

from __future__ import annotations

import copy
import importlib
import re
from pathlib import Path
from typing import Any

import pytest
import yaml

import netsim
from netsim import registry

PAGE = Path(__file__).resolve().parents[2] / "docs" / "truetime-mapping.md"
TEXT = PAGE.read_text(encoding="utf-8")
BLOCKS = re.findall(r"^```(\w+)\n(.*?)^```", TEXT, flags=re.S | re.M)
PYTHON = [code for lang, code in BLOCKS if lang == "python"]
YAML = [yaml.safe_load(code) for lang, code in BLOCKS if lang == "yaml"]

# the calls issue 27 (s3) asks the page to place, beside the ones it gives as examples
ISSUE_CALLS = [
    "ttCreatePeriodicTask", "ttSendMsg", "ttGetMsg", "ttAnalogIn", "ttAnalogOut", "ttCreateMonitor", "ttSetPeriod",
    "ttInitKernel", "ttCreateTask", "ttCreateHandler", "ttAttachTriggerHandler", "ttCreateTimer", "ttCurrentTime",
    "ttSleep", "ttWait", "ttEnterMonitor", "ttExitMonitor", "ttSetDeadline", "ttSetPriority", "ttCreateMailbox",
    "ttTryPost", "ttTryFetch", "ttCallBlockSystem", "ttSetKernelParameter", "ttInitNetwork",
]


def _table_rows() -> list[list[str]]:
    rows = []
    for line in TEXT.splitlines():
        if line.startswith("| ") and not line.startswith("| TrueTime") and not line.startswith("|---"):
            rows.append([cell.strip() for cell in re.split(r"(?<!\\)\|", line.strip())[1:-1]])
    return rows


def _spans() -> list[str]:
    """Every inline code span in the tables' netsim columns (YAML and Python)."""
    return [span for row in _table_rows() for cell in row[1:] for span in re.findall(r"`([^`]+)`", cell)]


def _merge(base: dict[str, Any], part: dict[str, Any]) -> dict[str, Any]:
    out = copy.deepcopy(base)
    for key, value in part.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def test_every_truetime_call_of_the_issue_has_a_row():
    first_cells = " ".join(row[0] for row in _table_rows())
    missing = [call for call in ISSUE_CALLS if f"`{call}" not in first_cells]
    assert not missing, f"no row for {missing}"


def test_the_page_has_examples_in_both_languages():
    assert len(PYTHON) >= 4 and len(YAML) >= 4 and "name" in YAML[0]


@pytest.mark.parametrize("index", range(len(PYTHON)))
def test_each_python_example_runs_and_its_asserts_hold(index: int):
    import ast

    tree = ast.parse(PYTHON[index])
    # the example checks itself (times worked out by hand on the page): without an assert it would prove nothing
    assert any(isinstance(node, ast.Assert) for node in ast.walk(tree)), f"python block {index + 1} asserts nothing"
    exec(compile(tree, f"{PAGE.name} python block {index + 1}", "exec"), {"__name__": "__example__"})  # its asserts


@pytest.mark.parametrize("index", range(1, len(YAML)))
def test_each_yaml_example_loads_and_runs_in_the_first_one(index: int):
    scenario = _merge(YAML[0], YAML[index])
    scenario["duration"] = "0.1 s"
    result = netsim.run(scenario)
    assert result.status == "ok"
    assert len(result.jobs) > 0  # the part added tasks that ran


def test_the_first_yaml_example_is_a_whole_scenario():
    assert netsim.run({**YAML[0], "duration": "0.05 s"}).status == "ok"


@pytest.fixture(scope="module")
def live() -> dict[str, Any]:
    """A real kernel, a job of it and a run result, whose attributes the page cites."""
    from netsim.env import SimEnv
    from netsim.kernel import Kernel

    env = SimEnv(seed=1)
    kernel = Kernel(env, "n", policy="fp")
    jobs: list[Any] = []

    def body(job: Any) -> Any:
        jobs.append(job)
        yield job.execute(1)

    kernel.create_task("t", body, period=1000, priority=1)
    env.run(10)
    result = netsim.run({**YAML[0], "duration": "0.01 s"})
    return {"job": jobs[0], "kernel": kernel, "kernel.sync": kernel.sync, "result": result}


def test_every_cited_job_kernel_and_result_attribute_exists(live: dict[str, Any]):
    cited = set()
    for span in _spans() + [code for _, code in BLOCKS]:
        for owner, name in re.findall(r"(?<![\w.])(job|kernel\.sync|kernel|result)\.(\w+)", span):
            cited.add((owner, name))
    assert ("job", "analog_in") in cited and ("kernel", "set_period") in cited  # the scan finds them
    missing = sorted(f"{owner}.{name}" for owner, name in cited if not hasattr(live[owner], name))
    assert not missing, f"the page cites names that do not exist: {missing}"


def _resolve(dotted: str) -> Any:
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for attr in parts[cut:]:
            obj = getattr(obj, attr)
        return obj
    raise ImportError(dotted)


def test_every_cited_netsim_dotted_name_resolves():
    names = {m for span in _spans() for m in re.findall(r"\bnetsim(?:\.\w+)+", span)}
    assert "netsim.network.make_network" in names
    bad = []
    for name in sorted(names):
        try:
            _resolve(name)
        except (ImportError, AttributeError):
            bad.append(name)
    assert not bad, f"the page cites netsim names that do not resolve: {bad}"


def _scenario_keys() -> set[str]:
    from netsim.cli.docs import scenario_reference

    section = scenario_reference().split("## Scenario file", 1)[1].split("\n## ", 1)[0]
    return set(re.findall(r"^\| `([^`]+)` \|", section, flags=re.M))


def test_every_cited_scenario_key_exists():
    keys = _scenario_keys()
    cited = set()
    for span in _spans():
        match = re.match(r"((?:nodes|networks)\.<n>\.[\w.\[\]]+|output\.\w+)", span)
        if match:
            cited.add(match.group(1).replace("<n>", "<name>").rstrip("."))
    assert "nodes.<name>.tasks[].period" in cited
    missing = sorted(key for key in cited if key not in keys)
    assert not missing, f"the page cites scenario keys that do not exist: {missing}"


def test_every_cited_registered_name_exists():
    io_types = {"adc", "dac", "encoder"}
    cited = {(kind, name) for span in _spans() for kind, name in re.findall(r"\b(program|policy|type): (\w+)", span)}
    assert ("program", "critical_section") in cited and ("type", "flexray") in cited
    unknown = []
    for kind, name in sorted(cited):
        if kind == "type":
            if name in io_types or any(name in {e.name for e in registry.entries(k)} for k in registry.kinds()):
                continue
            if name.startswith("my_"):  # the page's placeholder for a user's plugin
                continue
            unknown.append(f"type: {name}")
        elif name not in {e.name for e in registry.entries(kind)}:
            unknown.append(f"{kind}: {name}")
    assert not unknown, f"the page cites names no plugin registers: {unknown}"
