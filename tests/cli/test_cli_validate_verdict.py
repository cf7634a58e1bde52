"""``verdict.signals`` and ``verdict.bound`` name signals the run judges after it ends: ``netsim validate`` refuses
one the run would not record, at its YAML path (before, the run only warned "nothing recorded ... it was not
judged" and validate said valid)."""

from __future__ import annotations

from cli_files import write

from netsim.cli import main


def _validate(tmp_path, capsys, text: str) -> tuple[int, str]:
    code = main(["validate", str(write(tmp_path, "s.yaml", text))])
    return code, capsys.readouterr().out


def test_recorded_verdict_signals_are_valid(tmp_path, capsys, good):
    text = good.replace("plant: {model: zzc_plant, x0: [0]}", "plant: {model: zzc_plant, x0: [0], record_grid: 1 ms}")
    code, out = _validate(tmp_path, capsys, text + "record: [y]\nverdict: {signals: [y], bound: {y: 2.0}}\n")
    assert code == 0, out


def test_verdict_signal_left_out_of_record_is_refused_at_its_path(tmp_path, capsys, good):
    code, out = _validate(tmp_path, capsys, good + "record: [u]\nverdict: {signals: [r], bound: {theta: 1.0}}\n")
    assert code == 1
    assert "verdict.signals[0]: the verdict judges signal 'r', which 'record:' leaves out (record: [u])" in out
    assert "verdict.bound.theta: the verdict judges signal 'theta', which 'record:' leaves out" in out


def test_verdict_on_a_plant_output_without_record_grid_is_refused(tmp_path, capsys, good):
    # zzc_plant's output 'y' is recorded under its name only on plant.record_grid, which `good` does not set
    code, out = _validate(tmp_path, capsys, good + "verdict: {bound: {y: 2.0}}\n")
    assert code == 1
    assert "verdict.bound.y: the verdict reads the plant output 'y'" in out
    assert "add e.g. 'record_grid: 1 ms' under 'plant:'" in out
