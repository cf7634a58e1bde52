"""README's node examples for servers, schedule tables, cores and CPU speed (issue 30) are valid scenarios: each
YAML block of that paragraph, put as the ``nodes`` of README's "Writing a scenario" loop (``name: my_loop``), passes
``netsim validate`` and runs, and its jobs take the times the prose says (worked out by hand below)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from netsim import run
from netsim.cli import main

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text(encoding="utf-8")
_START = "Servers, time-triggered tables, cores and CPU speed (issue 30)"


def _blocks() -> list[str]:
    """The YAML blocks from the paragraph that introduces the examples up to the next heading."""
    assert _START in README, "README lost the servers/timetable/cores/speed paragraph"
    part = README[README.index(_START):]
    part = part[: part.index("\n### ")]
    return re.findall(r"```yaml\n(.*?)```", part, flags=re.S)


def _base() -> dict:
    text = next(b for b in re.findall(r"```yaml\n(.*?)```", README, flags=re.S) if b.startswith("name: my_loop"))
    return yaml.safe_load(text)


BLOCKS = _blocks()
NAMES = ["server", "timetable", "cores", "speed"]


def _scenario(index: int) -> dict:
    scenario = _base()
    scenario["nodes"] = yaml.safe_load(BLOCKS[index])["nodes"]
    scenario["name"] = f"readme_{NAMES[index]}"
    scenario["duration"] = "100 ms"
    return scenario


def test_the_paragraph_has_one_example_per_feature():
    assert len(BLOCKS) == len(NAMES)
    keys = [set(yaml.safe_load(block)["nodes"]["cpu"]) for block in BLOCKS]
    assert "servers" in keys[0] and "timetable" in keys[1] and "cores" in keys[2] and "speed" in keys[3]


@pytest.mark.parametrize("index", range(len(NAMES)), ids=NAMES)
def test_each_example_passes_netsim_validate(index: int, tmp_path, capsys):
    path = tmp_path / f"{NAMES[index]}.yaml"
    path.write_text(yaml.safe_dump(_scenario(index)), encoding="utf-8")
    assert main(["validate", str(path)]) == 0, capsys.readouterr()


def test_validate_would_refuse_a_broken_example(tmp_path, capsys):
    # the check above can fail: a task naming a server its node does not declare is refused at its path
    scenario = _scenario(0)
    scenario["nodes"]["cpu"]["tasks"][0]["server"] = "nowhere"
    path = tmp_path / "broken.yaml"
    path.write_text(yaml.safe_dump(scenario), encoding="utf-8")
    assert main(["validate", str(path)]) == 1
    assert "nodes.cpu.tasks[0].server" in capsys.readouterr().out


def _responses_ms(index: int, task: str) -> list[float]:
    result = run(_scenario(index), write=False)
    assert result.meta["status"] == "ok"
    jobs = result.jobs[(result.jobs["task"] == task) & result.jobs["response_s"].notna()]
    return [round(r * 1e3, 6) for r in jobs["response_s"]]


def test_the_timetable_example_gives_the_pid_exactly_its_execution_time():
    # the table activates pid at 0 ms of each 10 ms cycle, alone on the node: 1 ms of execution, response 1 ms
    assert set(_responses_ms(1, "pid")) == {1.0}


def test_the_partitioned_example_runs_each_task_alone_on_its_core():
    # pid on core 0 and load on core 1 never meet: responses are their execution times, 2 ms and 10 ms
    assert set(_responses_ms(2, "pid")) == {2.0}
    assert set(_responses_ms(2, "load")) == {10.0}


def test_the_speed_example_stretches_jobs_by_one_over_the_speed():
    # the governor's job 0 (0 ms) sets speed 1, its job 1 (50 ms) sets 0.5: pid jobs at 0..40 ms take 2 ms,
    # those at 50..90 ms take 2 / 0.5 = 4 ms
    assert _responses_ms(3, "pid") == [2.0] * 5 + [4.0] * 5
