"""``netsim validate`` refuses what ``netsim run`` refuses (issue 13 C), with the YAML path, line and user units.

One scenario per item of the issue; before the fix ``validate`` printed "valid" (exit 0) for each, and ``run``
then failed in ``build`` (or, for the sweep, after running every point).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from netsim.cli import main

BASE = """\
name: c13
duration: 100 ms
plant:
  model: dc_servo
  params: {gain: 1000, a: 1}
io:
  y: {type: adc, output: 0}
  u: {type: dac, input: 0}
nodes:
  n:
    policy: fp
    handlers:
      - {name: h, program: idle}
    tasks:
      - name: t
        program: sampler
        params: {channel: y, network: can, to: m, bits: 80}
        period: 100 ms
        priority: 1
        execution: 1 ms
  m:
    policy: fp
    tasks:
      - name: r
        program: actuator
        params: {network: can, channel: u}
        release: on_message:can
        priority: 1
        execution: 1 ms
networks:
  can: {type: can, nodes: [n, m], bitrate: 1 Mbit/s}
"""

TASK = "nodes.n.tasks[0]"

# (id, edits of BASE (old, new), YAML path, text on the problem's line, words of the message)
CASES = [
    ("rm_deadline_longer_than_period",
     [("policy: fp\n    handlers", "policy: rm\n    handlers"), ("execution: 1 ms\n  m:", "execution: 1 ms\n        deadline: 120 ms\n  m:")],
     f"{TASK}.deadline", "deadline: 120 ms", "120 ms exceeds the period 100 ms, which policy 'rm' does not allow"),
    ("dm_deadline_longer_than_period",
     [("policy: fp\n    handlers", "policy: dm\n    handlers"), ("execution: 1 ms\n  m:", "execution: 1 ms\n        deadline: 120 ms\n  m:")],
     f"{TASK}.deadline", "deadline: 120 ms", "120 ms exceeds the period 100 ms, which policy 'dm' does not allow"),
    ("wcet_handler_without_wcet",
     [("priority: 1\n        execution: 1 ms\n  m:", "priority: 1\n        execution: 1 ms\n        wcet_handler: h\n  m:")],
     f"{TASK}.wcet_handler", "wcet_handler: h", "needs a 'wcet' budget"),
    ("np_fp_without_priority",
     [("policy: fp\n    handlers", "policy: np_fp\n    handlers"), ("period: 100 ms\n        priority: 1\n", "period: 100 ms\n")],
     f"{TASK}.priority", "- name: t", "is required under policy 'np_fp'"),
    ("adc_output_beyond_the_plant",
     [("y: {type: adc, output: 0}", "y: {type: adc, output: 3}")],
     "io.y.output", "output: 3", "plant output index 3 out of range: the plant has 1 output"),
    ("plugin_path_whose_constructor_needs_other_arguments",
     [("model: dc_servo", 'model: "netsim.plant.lti:LTIPlant"')],
     "plant.model", "LTIPlant", "cannot be built from a scenario: build calls LTIPlant(params), but it takes (A, B, C)"),
    ("time_as_a_bare_number",
     [("period: 100 ms", "period: 5")],
     f"{TASK}.period", "period: 5", "add a unit, e.g. '5 ms'"),
    ("a_check_build_makes_with_its_runtime_objects",  # Kernel.create_periodic_load: at most one per node
     [("      - {name: h, program: idle}\n", "      - {name: h, program: idle, execution: 1 us, trigger: {periodic_load: {period: 10 us}}}\n"
       "      - {name: h2, program: idle, execution: 1 us, trigger: {periodic_load: {period: 20 us}}}\n")],
     "nodes.n.handlers[1].trigger", "name: h2", "node already has the periodic load 'h'; at most one per node"),
    ("plant_state_of_the_wrong_size",  # LTIPlant.set_state, called by build after the plant is made
     [("  params: {gain: 1000, a: 1}\n", "  params: {gain: 1000, a: 1}\n  x0: [0, 0, 0]\n")],
     "plant.x0", "x0: [0, 0, 0]", "state must have 2 entries, got 3"),
    ("pid_in_a_task_without_a_period_and_without_h",  # PID.from_params: "PID needs a sampling period"
     [("program: actuator\n        params: {network: can, channel: u}",
       "program: controller\n        params: {channel: y, output_channel: u, K: 1.0}")],
     "nodes.m.tasks[0].params", "params: {channel: y, output_channel: u", "has no sampling period; add 'h: 10 ms'"),
    ("controller_sending_a_negative_number_of_bits",  # run: "send bits must be a non-negative int"
     [("program: actuator\n        params: {network: can, channel: u}",
       "program: controller\n        params: {channel: y, output_channel: u, K: 1.0, h: 100 ms, network: can, to: n, "
       "bits: -81}")],
     "nodes.m.tasks[0].params.bits", "bits: -81", "greater than or equal to 1"),
    ("network_task_without_to",
     [("network: can, to: m, bits: 80", "network: can, bits: 80")],
     f"{TASK}.params.to", "network: can, bits: 80", "'to' is missing"),
]


def _line(path: Path, text: str) -> int:
    """1-based line of the first line of ``path`` containing ``text`` (computed from the file, not by netsim)."""
    for i, line in enumerate(path.read_text().splitlines(), start=1):
        if text in line:
            return i
    raise AssertionError(f"{text!r} not in {path}")


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_the_base_scenario_is_valid(tmp_path, capsys):
    path = _write(tmp_path, "base.yaml", BASE)
    assert main(["validate", str(path)]) == 0, capsys.readouterr().out


@pytest.mark.parametrize(("edits", "where", "marker", "words"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_validate_reports_it_with_path_line_and_user_units(tmp_path, capsys, edits, where, marker, words):
    text = BASE
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    path = _write(tmp_path, "bad.yaml", text)
    code = main(["validate", str(path)])
    out = capsys.readouterr().out
    assert code >= 1, out
    lines = [line for line in out.splitlines() if f": {where}: " in line and "warning:" not in line]
    assert lines, out
    assert lines[0].startswith(f"{path}:{_line(path, marker)}: {where}: "), out
    assert words in lines[0], out
    assert not re.search(r"\d{4,} ns\b", out), out  # user units, never raw nanoseconds


def test_a_surface_over_a_non_numeric_factor_is_refused_before_any_point_runs(tmp_path, capsys):
    _write(tmp_path, "base.yaml", BASE)
    sweep = _write(tmp_path, "sweep.yaml", (
        "sweep: c13sw\nbase: base.yaml\nfactors:\n"
        "  policy: {paths: [nodes.n.policy], values: [fp, edf]}\n"
        "  gain: {paths: [plant.params.gain], values: [500, 1000]}\n"
        "surface: {x: policy, y: gain, z: net.can.utilization}\n"))
    assert main(["validate", str(sweep)]) == 1
    out = capsys.readouterr().out
    assert out.startswith(f"{sweep}:{_line(sweep, 'surface:')}: surface.x: factor 'policy' has non-numeric values "
                          "('fp', 'edf')"), out
    assert main(["sweep", str(sweep), "--out", str(tmp_path / "out")]) != 0
    assert not (tmp_path / "out" / "points").exists()  # nothing ran


def test_interference_reaching_a_consumer_is_a_warning_with_its_path(tmp_path, capsys):
    text = BASE.replace("networks:", (
        "  i:\n    policy: fp\n    tasks:\n"
        "      - {name: noise, program: interference, params: {network: can, to: all}, period: 1 ms, priority: 1}\n"
        "networks:")).replace("nodes: [n, m]", "nodes: [n, m, i]")
    path = _write(tmp_path, "noise.yaml", text)
    assert main(["validate", str(path)]) == 0  # a warning: the run is possible, the result probably not meant
    out = capsys.readouterr().out
    assert f"{path}:{_line(path, 'name: noise')}: warning: nodes.i.tasks[0].params.to: interfering frames on 'can' " \
           "reach 'm' (nodes.m.tasks[0])" in out, out
    fixed = _write(tmp_path, "quiet.yaml", text.replace("network: can, to: all}", "network: can, to: i}"))
    assert main(["validate", str(fixed)]) == 0
    assert "warning" not in capsys.readouterr().out


def test_a_metric_reading_a_signal_that_record_leaves_out_is_refused_by_validate_as_run_would(tmp_path, capsys):
    # found by the fuzz figures (issue 14 B): unicycle_lqr without 'theta' in record: validated, then the run
    # failed in its metric; the metric now declares the signals it reads (reads_signals) and validate checks them
    root = Path(__file__).resolve().parents[2]
    text = (root / "scenarios" / "unicycle_lqr.yaml").read_text(encoding="utf-8")
    assert "record: [x, y, theta," in text
    path = tmp_path / "unicycle_lqr.yaml"
    path.write_text(text.replace("record: [x, y, theta,", "record: [x, y,"), encoding="utf-8")
    assert main(["validate", str(path)]) == 1
    err = capsys.readouterr()
    out = err.out + err.err
    assert "metrics[0].type: metric 'unicycle' reads the signals theta" in out and "add them to 'record:'" in out
    assert main(["run", str(path), "--out", str(tmp_path / "run")]) == 2   # run refuses it too, before running
