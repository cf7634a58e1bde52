"""The user's plugin permission travels with a Dask task (issue 31 fault 3): a worker of a remote scheduler runs a
scenario's plugin files exactly when the user who submitted the sweep allowed them, whatever the worker's own
environment says. The real cluster case is tests/test_sweep_dask_cluster.py (slow)."""

from __future__ import annotations

from pathlib import Path

import pytest

from netsim.sweep.executor import with_plugin_permission
from netsim.sweep.spec import load_sweep
from netsim.trust import ENV_VAR, plugins_allowed, task_permission


@pytest.mark.parametrize("worker_env", ["0", "1", None])
@pytest.mark.parametrize("carried", [True, False])
def test_the_carried_permission_wins_over_the_worker_environment(monkeypatch, worker_env, carried) -> None:
    if worker_env is None:
        monkeypatch.delenv(ENV_VAR, raising=False)
    else:
        monkeypatch.setenv(ENV_VAR, worker_env)
    assert with_plugin_permission(carried, plugins_allowed) is carried


def test_the_permission_ends_with_the_task_and_an_explicit_choice_still_wins(monkeypatch) -> None:
    monkeypatch.setenv(ENV_VAR, "0")
    with task_permission(True):
        assert plugins_allowed() is True
        assert plugins_allowed(False) is False  # allow_plugins=False in the call refuses, as documented
    assert plugins_allowed() is False  # back to the process's own settings


def test_a_sweep_names_its_plugin_files_by_absolute_path(tmp_path: Path, monkeypatch) -> None:
    """A worker with another working directory finds them (before: 'plugin file not found: <its cwd>/x.py')."""
    (tmp_path / "base.yaml").write_text("name: p\nduration: 1 s\nplugins: [my_plugin.py]\n")
    (tmp_path / "sweep.yaml").write_text("sweep: s\nbase: base.yaml\nfactors:\n  d:\n    paths: [duration]\n"
                                         "    values: [1 s, 2 s]\n")
    monkeypatch.chdir(tmp_path)
    sweep = load_sweep("sweep.yaml")
    assert sweep.base["plugins"] == [str(tmp_path / "my_plugin.py")]
    assert sweep.point_raw(sweep.points[1])["plugins"] == [str(tmp_path / "my_plugin.py")]
