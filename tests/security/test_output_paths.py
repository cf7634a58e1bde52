"""Only the user chooses where files go; a scenario's output.dir and name stay below reports/ (issue 14 A)."""

from __future__ import annotations

import pytest

from netsim.scenario import check_scenario


def _errors(raw):
    return {p.path: p.message for p in check_scenario(raw) if p.is_error}


@pytest.mark.parametrize("folder", ["/tmp/elsewhere", "../outside", "runs/../../outside", "~/runs", "C:/runs",
                                    "runs\\..\\x", ""])
def test_output_dir_cannot_leave_the_output_root(scenario, folder):
    raw = scenario()
    raw["output"] = {"dir": folder}
    errors = _errors(raw)
    assert "output.dir" in errors, errors
    assert "--out" in errors["output.dir"]


@pytest.mark.parametrize("name", ["x" * 101, "x" * 1_000_000])  # '/' and '..' were refused already
def test_a_name_that_cannot_be_a_folder_name_is_refused_at_validate(scenario, name):
    raw = scenario()
    raw["name"] = name
    errors = _errors(raw)
    assert "name" in errors, errors
    assert len(errors["name"]) < 300  # a 10^6-character name is not echoed


def test_run_writes_only_below_reports(tmp_path, monkeypatch, scenario, snapshot):
    from netsim.runner import run

    monkeypatch.chdir(tmp_path)
    raw = scenario()
    raw["output"] = {"dir": "mine/case1"}
    run(raw)
    written = snapshot(tmp_path)
    assert written and all(p.startswith(str(tmp_path / "reports" / "mine" / "case1") + "/") for p in written)


def test_a_symlink_under_reports_does_not_lead_out(tmp_path, monkeypatch, scenario, snapshot):
    from netsim.errors import ConfigError
    from netsim.runner import run

    outside = tmp_path / "outside"
    outside.mkdir()
    (tmp_path / "work" / "reports").mkdir(parents=True)
    (tmp_path / "work" / "reports" / "link").symlink_to(outside)
    monkeypatch.chdir(tmp_path / "work")
    raw = scenario()
    raw["output"] = {"dir": "link/case1"}
    with pytest.raises(ConfigError, match="resolves outside reports"):
        run(raw)
    assert snapshot(outside) == {} and not (outside / "case1").exists()


def test_planted_symlinks_in_the_run_folder_are_replaced_not_followed(tmp_path, scenario):
    # a guard: netsim.safe_write already replaced planted links before issue 14's changes (this passed before)
    from netsim.runner import run

    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    folder = tmp_path / "run"
    folder.mkdir()
    for name in ("signals.csv", "meta.json", "jobs.csv", "metrics.csv", "scenario.yaml"):
        (folder / name).symlink_to(victim)
    run(scenario(), out=folder)
    assert victim.read_text() == "keep me"
    assert not (folder / "meta.json").is_symlink() and (folder / "meta.json").stat().st_size > 0


def test_a_sweep_name_that_cannot_be_a_folder_name_is_refused(tmp_path):
    from netsim.errors import ConfigError
    from netsim.sweep.spec import load_sweep

    with pytest.raises(ConfigError) as info:
        load_sweep({"sweep": "s" * 1_000_000, "base": "b.yaml", "factors": {"sd": {"paths": ["seed"], "values": [1]}}},
                   base={"name": "b", "duration": "1 s"})
    assert "100" in str(info.value) and len(str(info.value)) < 400
