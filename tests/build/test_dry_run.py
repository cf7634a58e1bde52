"""``netsim validate`` is the run's own build on a dry-run environment, made once (issue 28, the build room).

Before: validate ran a separate static dry run (netsim/scenario/static_build.py) that wired the kernels with
placeholder bodies and never built a program, and reached the control design through a side path
(``check_design``); what a program's constructor refused was found only by ``run``. Its problems' messages were
recovered by cutting the kernel's ``node '..', task '..', field '..': `` lead off the message text.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from netsim.build import builder
from netsim.build.builder import DryRunEnv, build
from netsim.build.wiring import located
from netsim.cli import main
from netsim.errors import BuildError, ConfigError
from netsim.registry import register
from netsim.scenario import Scenario, check_scenario, load_scenario
from netsim.scenario.loader import read_yaml

ROOT = Path(__file__).resolve().parents[2]

#: A state_feedback loop on a one-input plant whose output_channels name two DACs: the program's constructor
#: refuses it (one DAC per model input) after the design; the parameters, the cross references and the design
#: alone are all fine, so only building the program finds it.
TWO_DACS = """\
name: two_dacs
duration: 50 ms
plant:
  type: ss
  A: [[0, 1], [0, -1]]
  B: [0, 1000]
  C: [1, 0]
  inputs: [u]
  outputs: [y]
io:
  y: {type: adc, output: y}
  u: {type: dac, input: u}
  u2: {type: dac, input: u}
nodes:
  c:
    tasks:
      - name: control
        program: state_feedback
        period: 10 ms
        priority: 1
        params:
          measurements: [{channel: y}]
          estimator: {type: kalman, Q: [0, 0.01], R: 1.0e-6}
          law: {type: lqr, Q: [1, 0], R: 0.1}
          output_channels: [u, u2]
"""

WHERE = "nodes.c.tasks[0].params.output_channels"
WHAT = "output_channels must name 1 DAC channels (one per input), got 2"


def _line_of(text: str, marker: str) -> int:
    """1-based line of ``marker`` in ``text`` (found here, not by netsim)."""
    return next(i for i, line in enumerate(text.splitlines(), start=1) if marker in line)


def test_validate_refuses_what_only_building_the_program_finds(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                                               ) -> None:
    # the old static dry run never built programs: validate printed "valid" and run refused the scenario
    path = tmp_path / "two_dacs.yaml"
    path.write_text(TWO_DACS)
    assert main(["validate", str(path)]) == 1
    out = capsys.readouterr().out
    errors = [line for line in out.splitlines() if line.startswith(f"{path}:") and "warning:" not in line]
    assert errors == [f"{path}:{_line_of(TWO_DACS, 'output_channels:')}: {WHERE}: {WHAT}"], out
    assert main(["run", str(path), "--out", str(tmp_path / "run")]) != 0  # run refuses it too


def test_validate_and_the_run_build_refuse_it_at_the_same_path_with_the_same_message(tmp_path: Path) -> None:
    path = tmp_path / "two_dacs.yaml"
    path.write_text(TWO_DACS)
    (problem,) = [p for p in check_scenario(path) if p.is_error]
    raw = read_yaml(path)[0]
    with pytest.raises(ConfigError) as refused:  # the run's build of the schema-valid scenario, without the loader
        build(Scenario.model_validate(raw))
    assert (problem.path, problem.message) == (refused.value.path, refused.value.message) == (WHERE, WHAT)


def test_validate_builds_once_with_the_runs_own_build_on_a_dry_run_environment(monkeypatch: pytest.MonkeyPatch
                                                                               ) -> None:
    calls: list[bool] = []
    envs: list[type] = []
    real = builder.build

    def counted(scenario: Any, *, dry_run: bool = False) -> Any:
        calls.append(dry_run)
        sim = real(scenario, dry_run=dry_run)
        envs.append(type(sim.env))
        return sim

    monkeypatch.setattr(builder, "build", counted)
    assert [p for p in check_scenario(ROOT / "scenarios" / "dc_servo_can.yaml") if p.is_error] == []
    assert calls == [True] and envs == [DryRunEnv]


#: The tasks and handlers of scenarios/dc_servo_can.yaml (read from the file).
PROGRAMS = ["actuator.actuate", "controller.control", "interference.traffic", "sensor.sample"]


def test_a_dry_runs_simulation_cannot_be_run() -> None:
    sim = build(load_scenario(ROOT / "scenarios" / "dc_servo_can.yaml"), dry_run=True)
    assert isinstance(sim.env, DryRunEnv)
    assert sorted(sim.programs) == PROGRAMS  # netsim's own programs are built
    with pytest.raises(RuntimeError, match="never run"):
        sim.run()


@register("program", "zzb_refuses_in_its_constructor", "build-room test: a user's program that raises when made")
class _RefusesWhenMade:
    def __init__(self, ctx: Any, params: Any) -> None:
        raise ConfigError("this program was built")


def test_a_dry_run_does_not_build_a_program_netsim_does_not_own(tmp_path: Path) -> None:
    # validating runs no code a scenario brings along (issue 14): a user's program gets a placeholder body
    raw = {"name": "user_program", "duration": "10 ms",
           "nodes": {"n": {"tasks": [{"name": "t", "program": "zzb_refuses_in_its_constructor", "period": "1 ms",
                                      "priority": 1}]}}}
    assert [p for p in check_scenario(raw) if p.is_error] == []
    with pytest.raises(ConfigError, match="this program was built"):  # the run's build does build it
        build(load_scenario(raw))


def test_a_kernel_error_is_placed_by_its_field_and_shown_by_its_reason_whatever_its_message_says() -> None:
    # the path comes from the error's structured attributes; the message text is never read for it
    err = BuildError("a message in any wording")
    err.field, err.reason = "deadline", "exceeds the period"  # type: ignore[attr-defined]
    placed = located(err, "nodes.n.tasks[2]")
    assert (placed.path, placed.message) == ("nodes.n.tasks[2].deadline", "exceeds the period")
    # a field that is not a key of the entry stays at the entry, with the reason
    err.field = "body"  # type: ignore[attr-defined]
    assert (located(err, "nodes.n.tasks[2]").path, located(err, "nodes.n.tasks[2]").message) == \
        ("nodes.n.tasks[2]", "exceeds the period")
    # inside an entry (a handler's trigger), the reason at that path
    assert (located(err, "nodes.n.handlers[1].trigger").path, located(err, "nodes.n.handlers[1].trigger").message) == \
        ("nodes.n.handlers[1].trigger", "exceeds the period")
    # at a node's path (no entry), the whole message: it names the task
    assert (located(err, "nodes.n").path, located(err, "nodes.n").message) == ("nodes.n", "a message in any wording")
