"""Malformed input of issue 31 (the classes an independent set of malformed scenarios still found): each is
refused at its YAML path, with its line and a fix, by ``netsim validate`` and ``netsim run`` alike."""

from __future__ import annotations

import copy
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from netsim.scenario import check_scenario
from netsim.scenario.loader import read_yaml
from netsim.scenario.safe_yaml import dump_text

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "scenarios"


def _raw(name: str = "dc_servo_ideal.yaml") -> dict[str, Any]:
    raw, _ = read_yaml(SCENARIOS / name)
    return copy.deepcopy(raw)


def _errors(raw: dict[str, Any]) -> dict[str, str]:
    return {p.path: p.message for p in check_scenario(raw) if p.severity == "error"}


def _cli(*args: str, cwd: Path, timeout: float = 120.0) -> subprocess.CompletedProcess[str]:
    """``netsim ARGS`` in a fresh process, importing netsim from this checkout (not whichever one is installed)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    return subprocess.run([sys.executable, "-m", "netsim", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, env=env)


# ------------------------------------------------------------------------------- a task without period or release
TASK = "nodes.sensor.tasks[0]"


def test_a_task_without_period_or_release_is_refused_by_validate_and_run(tmp_path: Path) -> None:
    """The deleted period used to warn only: the loop never sampled and the run said 'ok'."""
    raw = _raw("dc_servo_can.yaml")
    del raw["nodes"]["sensor"]["tasks"][0]["period"]
    errors = _errors(raw)
    assert TASK in errors and "release: aperiodic" in errors[TASK] and "period: " in errors[TASK]
    f = tmp_path / "s.yaml"
    f.write_text(dump_text(raw))
    line = next(i for i, t in enumerate(f.read_text().splitlines(), 1) if "- name: sample" in t)
    for cmd in (["validate", str(f)], ["run", str(f), "--out", str(tmp_path / "out")]):
        done = _cli(*cmd, cwd=tmp_path)
        assert done.returncode != 0, done.stdout + done.stderr
        assert f"{f.name}:{line}: {TASK}" in done.stdout + done.stderr, done.stdout + done.stderr


def test_release_aperiodic_says_the_task_is_released_by_triggers_or_messages() -> None:
    raw = _raw("dc_servo_can.yaml")
    task = raw["nodes"]["sensor"]["tasks"][0]
    del task["period"]
    task["release"] = "aperiodic"
    assert TASK not in _errors(raw)


def test_every_shipped_scenario_still_validates() -> None:
    for path in sorted(SCENARIOS.glob("*.yaml")):
        raw, _ = read_yaml(path)
        if "nodes" not in raw:  # sweep files
            continue
        assert not [p for p in check_scenario(raw) if p.severity == "error" and "no period" in p.message], path


# ------------------------------------------------------------------------------------------- over-long numbers
@pytest.mark.parametrize("tail", [" s", ""])
def test_a_number_of_tens_of_thousands_of_digits_is_refused_quickly_with_its_line(tmp_path: Path, tail: str) -> None:
    """50000 digits took well over 30 s to validate before (the YAML resolver's integer pattern backtracked
    quadratically on the digit run); the lexer now refuses it in one linear pass. 20 s is generous: the refusal
    itself takes milliseconds, the rest is the CLI starting."""
    text = (SCENARIOS / "dc_servo_ideal.yaml").read_text()
    f = tmp_path / "long.yaml"
    f.write_text(text.replace("duration: 2 s", "duration: " + "1" * 50_000 + tail))
    line = next(i for i, t in enumerate(text.splitlines(), 1) if t.startswith("duration:"))
    done = _cli("validate", str(f), cwd=tmp_path, timeout=20.0)
    assert done.returncode != 0
    assert f"long.yaml:{line}: duration: a number written with 50000 digits" in done.stdout + done.stderr
    assert "write a smaller value" in done.stdout + done.stderr


def test_a_long_digit_run_below_the_lexer_limit_loads_in_linear_time() -> None:
    """9000 digits followed by a unit: the integer pattern's backtracking cost about 1 s here before."""
    import time

    from netsim.scenario.safe_yaml import load_text

    start = time.perf_counter()
    assert load_text("a: " + "1" * 9000 + " s\n") == {"a": "1" * 9000 + " s"}
    assert time.perf_counter() - start < 0.5


# ------------------------------------------------------------------------------------ true/false for a number
@pytest.mark.parametrize(("where", "value", "path"), [
    (("plant", "params", "gain"), True, "plant.params.gain"),               # a float parameter (was 1.0)
    (("nodes", "sensor", "tasks", 0, "params", "bits"), False, "nodes.sensor.tasks[0].params.bits"),  # an int
    (("networks", "can", "bitrate"), True, "networks.can.bitrate"),
])
def test_true_or_false_is_refused_where_a_number_is_wanted(where: tuple[Any, ...], value: bool, path: str) -> None:
    raw = _raw("dc_servo_can.yaml")
    node = raw
    for part in where[:-1]:
        node = node[part]
    node[where[-1]] = value
    errors = _errors(raw)
    assert path in errors, errors
    assert "true" in errors[path] or "false" in errors[path]


def test_an_integer_stays_a_valid_float() -> None:
    from netsim.units import StrictModel

    class P(StrictModel):
        gain: float = 0.0
        x0: list[float] = []
        on: bool = False

    p = P(gain=3, x0=[1, 2], on=True)
    assert (p.gain, p.x0, p.on) == (3.0, [1.0, 2.0], True)
    with pytest.raises(ValueError, match="true"):
        P(x0=[1, True])


# ----------------------------------------------------------------------------------- empty lists that need a value
def test_an_empty_latency_chain_is_refused_at_its_path() -> None:
    """It was accepted and the latency metric reported 'worst -'."""
    raw = _raw("dc_servo_can.yaml")
    (i,) = [i for i, m in enumerate(raw["metrics"]) if m["type"] == "latency"]
    raw["metrics"][i]["params"]["chain"] = []
    errors = _errors(raw)
    assert "is empty" in errors[f"metrics[{i}].params.chain"] and "node.task" in errors[f"metrics[{i}].params.chain"]


@pytest.mark.parametrize(("name", "where", "path"), [
    ("dc_servo_can.yaml", ("networks", "can", "nodes"), "networks.can.nodes"),
    ("pendulum_network.yaml", ("nodes", "controller", "tasks", 0, "params", "measurements"),
     "nodes.controller.tasks[0].params.measurements"),
])
def test_an_empty_list_that_needs_an_entry_says_so_in_words(name: str, where: tuple[Any, ...], path: str) -> None:
    """Refused before too, as pydantic's 'list should have at least 1 item after validation, not 0'."""
    raw = _raw(name)
    node = raw
    for part in where[:-1]:
        node = node[part]
    node[where[-1]] = []
    assert _errors(raw)[path] == f"'{where[-1]}' is empty; give at least 1 entry"


# ------------------------------------------------------------------------------------------ NaN in a waypoint
def test_a_nan_in_a_mobility_waypoint_has_a_path_with_a_line(tmp_path: Path) -> None:
    """The path was 'networks.bus.mobility.sensor.path.8 s[0]' (a space: no line could be found for it)."""
    raw = _raw("wireless_battery.yaml")
    raw["networks"]["bus"]["mobility"]["sensor"]["path"] = {"1 s": [0, 0], "8 s": [float("nan"), 0]}
    f = tmp_path / "nan.yaml"
    f.write_text(dump_text(raw))
    line = next(i for i, t in enumerate(f.read_text().splitlines(), 1) if t.strip() == "path:")
    done = _cli("validate", str(f), cwd=tmp_path)
    assert done.returncode != 0
    assert f"nan.yaml:{line}: networks.bus.mobility.sensor.path: at '8 s'[0]: NaN" in done.stdout, done.stdout


# --------------------------------------------------------------------------------- sweep files: file:line: path
def test_sweep_file_errors_are_one_per_line_with_file_line_and_path(tmp_path: Path) -> None:
    """Before: 'FILE: factors.period: ... FILE: replicates: ...' on one line, without any line number."""
    from netsim.sweep.check import check_sweep

    sweep = tmp_path / "bad.yaml"
    sweep.write_text(f"sweep: bad\nbase: {SCENARIOS / 'dc_servo_ideal.yaml'}\nfactors:\n"
                     "  period:\n"                                          # line 4
                     "    paths: [nodes.computer.tasks[0].period]\n"
                     "    values: [5 ms, 7 ms]\n"
                     "    linspace: {start: 1, stop: 2, num: 3}\n"
                     "replicates: 0\n")                                     # line 8
    shown = [str(p) for p in check_sweep(sweep)]
    assert shown == [f"{sweep}:4: factors.period: give only one of values/linspace/logspace, got values, linspace",
                     f"{sweep}:8: replicates: Input should be greater than or equal to 1"]


def test_a_bad_factor_path_and_a_bad_level_name_their_lines(tmp_path: Path) -> None:
    from netsim.sweep.check import check_sweep

    sweep = tmp_path / "bad.yaml"
    head = f"sweep: bad\nbase: {SCENARIOS / 'dc_servo_ideal.yaml'}\nfactors:\n  gain:\n"
    sweep.write_text(head + "    paths: [plant.params.gainx]\n    values: [1, 2]\n")
    (p,) = check_sweep(sweep)
    assert (p.line, p.path) == (5, "factors.gain.paths[0]") and "did you mean 'gain'" in p.message
    sweep.write_text(head + "    paths: [plant.params.gain]\n    values: [1, .nan]\n")
    (p,) = check_sweep(sweep)
    assert p.line == 4 and p.path.startswith("point (gain=nan): plant.params.gain")  # line 4: the factor


# --------------------------------------------------------------------------------------- File too large: a fix
def test_a_run_stopped_by_the_file_size_limit_says_how_to_write_less(tmp_path: Path) -> None:
    """'cannot write X: File too large' said nothing about what to do."""
    import resource

    def small_files() -> None:  # 20 kB: scenario.yaml fits, signals.csv (2000 rows x 4 columns) does not
        resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))

    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, "-m", "netsim", "run", str(SCENARIOS / "dc_servo_ideal.yaml"), "--out",
                           str(tmp_path / "out")], cwd=tmp_path, capture_output=True, text=True, timeout=120,
                          env=env, preexec_fn=small_files)
    assert done.returncode != 0 and "Traceback" not in done.stderr
    (line,) = [t for t in done.stderr.splitlines() if "File too large" in t]
    assert "cannot write" in line and "ulimit -f" in line and "output: {jobs: summary" in line


# --------------------------------------------------------------------------- report on a folder still being written
def test_report_on_a_folder_with_only_scenario_yaml_says_the_run_is_incomplete(tmp_path: Path) -> None:
    """A run killed right after writing scenario.yaml (or still running): was 'not a run folder'."""
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "scenario.yaml").write_text((SCENARIOS / "dc_servo_ideal.yaml").read_text())
    done = _cli("report", str(folder), cwd=tmp_path)
    assert done.returncode != 0 and "Traceback" not in done.stderr
    assert "incomplete run folder" in done.stderr and "still running" in done.stderr
    assert f"netsim run {folder / 'scenario.yaml'}" in done.stderr


# ------------------------------------------------------------------- a sweep level of a preset-like field (cart friction)
def _friction_sweep(tmp_path: Path, base: Path) -> Path:
    sweep = tmp_path / "friction.yaml"
    sweep.write_text(f"sweep: friction\nbase: {base}\nfactors:\n"
                     "  friction:\n"                                        # line 4
                     "    paths: [plant.params.friction.model]\n"
                     "    values: [inband, modes6]\n"
                     "  duration:\n    paths: [duration]\n    values: [20 ms, 30 ms]\n")
    return sweep


def test_a_sweep_level_of_a_preset_takes_effect_over_siblings_that_spell_out_the_old_preset(tmp_path: Path) -> None:
    """cart.yaml spells out the inband preset; the modes6 level used to keep inband's wavelength 3.3 etc.
    (Sweep.point_raw wrote the value directly, so the override shadow check never ran)."""
    from netsim.scenario import load_scenario
    from netsim.sweep.spec import load_sweep

    sweep = load_sweep(_friction_sweep(tmp_path, SCENARIOS / "cart.yaml"))
    modes6 = [p for p in sweep.points if p.values["friction"] == "modes6"]
    for point in modes6:
        friction = load_scenario(sweep.point_raw(point)).plant.validated_params().friction
        # modes6 as models/cart/friction.py's docstring states it (tests/scenario/test_shadowed_overrides.py)
        assert (friction.wavelength, friction.speedup, friction.modes, friction.spread) == (0.1, 3.0, 6, 0.5)
        assert friction.coulomb == 2.0  # not a preset field: as the base gives it
    for point in sweep.points:
        sweep.point_raw(point)
    assert len(sweep._shadow) == 2  # one check per friction level, not one per point (4)


def test_a_sweep_level_shadowed_by_the_base_s_own_values_is_refused(tmp_path: Path) -> None:
    from netsim.sweep.check import check_sweep

    base = tmp_path / "cart_own.yaml"
    base.write_text((SCENARIOS / "cart.yaml").read_text().replace("wavelength: 3.3", "wavelength: 2.0"))
    sweep = _friction_sweep(tmp_path, base)
    errors = [p for p in check_sweep(sweep) if p.is_error]
    assert errors and all(p.line == 4 for p in errors)
    assert "point (friction='modes6'" in errors[0].path and "wavelength" in errors[0].message
    assert "shadowed" in errors[0].message


# ------------------------------------------------------------------------------------- memory: budget, MemoryError
_HOG = """name: hog
duration: {duration}
nodes:
  cpu:
    policy: rm
    tasks:
      - {{name: a, program: idle, period: 10 us, execution: 1 us}}
      - {{name: b, program: idle, period: 10 us, execution: 1 us}}
"""


def _limited_run(tmp_path: Path, duration: str, address_space_mib: int, budget: str | None,
                 timeout: float) -> subprocess.CompletedProcess[str]:
    """``netsim run`` of two 10 us idle tasks (jobs rows kept in full) under ``ulimit -v``."""
    import resource

    def limit() -> None:
        size = address_space_mib * 2**20
        resource.setrlimit(resource.RLIMIT_AS, (size, size))

    f = tmp_path / "hog.yaml"
    f.write_text(_HOG.format(duration=duration))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    env.pop("NETSIM_MEMORY_BUDGET", None)
    if budget is not None:
        env["NETSIM_MEMORY_BUDGET"] = budget
    return subprocess.run([sys.executable, "-m", "netsim", "run", str(f), "--out", str(tmp_path / "out")],
                          cwd=tmp_path, capture_output=True, text=True, timeout=timeout, env=env, preexec_fn=limit)


def test_a_run_whose_estimated_memory_exceeds_the_budget_is_refused_before_it_starts(tmp_path: Path) -> None:
    """1000 s of two 10 us tasks: 2e8 jobs rows (at least 100 GB at 600 B each, the measured order), far beyond
    half of a 600 MiB address space. Before: the run started and ended in a MemoryError traceback."""
    done = _limited_run(tmp_path, "1000 s", 600, None, timeout=60)
    assert done.returncode != 0 and "Traceback" not in done.stderr, done.stderr[-2000:]
    (line,) = [t for t in done.stderr.splitlines() if "in memory" in t]
    assert "hog.yaml:2: duration:" in line and "ulimit -v" in line and "output: {jobs: summary" in line
    assert "NETSIM_MEMORY_BUDGET" in line
    assert not (tmp_path / "out" / "meta.json").exists()  # refused before anything ran


@pytest.mark.slow
def test_a_run_out_of_memory_ends_in_one_line_and_marks_its_folder_failed(tmp_path: Path) -> None:
    """The budget lifted (0: no limit), a 480 MiB address space runs out after about 3 s simulated (~20 s here)."""
    import json

    done = _limited_run(tmp_path, "100 s", 480, "0", timeout=300)
    assert done.returncode != 0 and "Traceback" not in done.stderr, done.stderr[-2000:]
    errors = [t for t in done.stderr.splitlines() if t.startswith("netsim: error:")]
    assert len(errors) == 1 and "out of memory" in errors[0] and "output: {jobs: summary" in errors[0], done.stderr
    meta = json.loads((tmp_path / "out" / "meta.json").read_text())
    assert meta["status"] == "error" and meta["error"].startswith("out of memory at t = ")


def test_an_integer_too_large_for_a_float_in_process_noise_is_refused_at_its_path() -> None:
    """Found by the fuzz figures (issue 31 session): OverflowError from the process_noise check, a traceback."""
    raw = _raw("dc_servo_lqr_kalman.yaml")
    raw["plant"]["process_noise"][1] = 10**4299  # what the loader reads for a 5000-digit integer
    errors = _errors(raw)
    assert "write a smaller value" in errors["plant.process_noise[1]"]
