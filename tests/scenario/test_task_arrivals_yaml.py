"""Release jitter, sporadic tasks and abort on deadline miss written in YAML (issue 20): validation with YAML
paths (``netsim validate`` refuses what ``run`` refuses), the jobs table's and the task metrics' columns."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

import netsim
from netsim.errors import NetsimError
from netsim.metrics.runtime import _task_metrics
from netsim.results.files import JOB_TYPES, read_table
from netsim.results.tables import JOB_COLUMNS
from netsim.scenario import check_scenario, load_scenario
from netsim.distributions import Exponential as ExponentialTime
from netsim.distributions import Uniform as UniformTime
from netsim.timebase import MS


def _raw(**task_fields):
    task = {"name": "a", "program": "idle", "priority": 1, "execution": "1 ms", **task_fields}
    return {"name": "arrivals", "duration": "200 ms", "seed": 5,
            "nodes": {"cpu": {"policy": "fp", "tasks": [task,
                                                        {"name": "b", "program": "idle", "priority": 2,
                                                         "period": "10 ms", "execution": "2 ms"}]}}}


def _errors(raw):
    return {p.path: p.message for p in check_scenario(raw) if p.severity == "error"}


def test_the_fields_are_read_with_units_and_defaults():
    sc = load_scenario(_raw(period="10 ms", release_jitter={"dist": "uniform", "low": "0 ms", "high": "2 ms"},
                            abort_on_miss=True))
    a = sc.nodes["cpu"].tasks[0]
    assert isinstance(a.release_jitter, UniformTime) and (a.release_jitter.low, a.release_jitter.high) == (0, 2 * MS)
    assert a.abort_on_miss is True
    s = load_scenario(_raw(min_interarrival="7 ms", extra_interarrival={"dist": "exponential", "mean": "3 ms"}))
    a = s.nodes["cpu"].tasks[0]
    assert a.release_kind == "sporadic" and a.min_interarrival == 7 * MS and a.deadline == 7 * MS
    assert isinstance(a.extra_interarrival, ExponentialTime) and a.extra_interarrival.mean == 3 * MS
    spec = a.checked("cpu")
    assert spec.min_interarrival == 7 * MS and spec.extra_interarrival.dist == "exponential"
    assert load_scenario(_raw(period="10 ms", release_jitter="1 ms")).nodes["cpu"].tasks[0].checked("cpu") \
        .release_jitter.const == MS  # a time is a constant jitter


def test_unused_fields_stay_out_of_the_resolved_scenario():
    task = load_scenario(_raw(period="10 ms")).resolved_dict()["nodes"]["cpu"]["tasks"][0]
    assert not {"release_jitter", "min_interarrival", "extra_interarrival", "abort_on_miss"} & set(task)
    used = load_scenario(_raw(period="10 ms", abort_on_miss=True)).resolved_dict()["nodes"]["cpu"]["tasks"][0]
    assert used["abort_on_miss"] is True


@pytest.mark.parametrize("fields, path, words", [
    ({"release": "sporadic"}, "min_interarrival", "needs a minimum inter-arrival"),
    ({"period": "10 ms", "min_interarrival": "5 ms"}, "min_interarrival", "only sporadic tasks"),
    ({"release": "aperiodic", "release_jitter": "1 ms"}, "release_jitter", "periodic and sporadic tasks only"),
    ({"period": "10 ms", "release_jitter": {"dist": "uniform", "low": "2 ms", "high": "1 ms"}}, "release_jitter",
     "low must not exceed high"),
    ({"period": "10 ms", "release_jitter": {"dist": "poisson", "mean": "1 ms"}}, "release_jitter", "dist"),
    ({"period": "10 ms", "extra_interarrival": {"dist": "exponential", "mean": "1 ms"}}, "extra_interarrival",
     "needs 'min_interarrival'"),
    ({"release": "aperiodic", "abort_on_miss": True}, "abort_on_miss", "needs a deadline"),
    ({"period": "10 ms", "abort_on_miss": "sometimes"}, "abort_on_miss", "true or false"),
])
def test_validate_and_run_refuse_bad_fields_at_their_yaml_path(fields, path, words):
    raw = _raw(**fields)
    errors = _errors(copy.deepcopy(raw))
    where = [p for p in errors if p.startswith(f"nodes.cpu.tasks[0].{path}")]
    assert where, errors
    assert words in " ".join(errors[p] for p in where) or words in str(where)
    with pytest.raises(NetsimError):
        netsim.run(raw, out=None)


def _run(fields, **kw):
    return netsim.run(_raw(**fields), out=None, **kw)


def test_jobs_table_and_task_metrics_name_the_jitter_and_the_response_from_arrival(tmp_path):
    res = netsim.run(_raw(period="10 ms", release_jitter={"dist": "uniform", "low": "0 ms", "high": "3 ms"}),
                     out=tmp_path / "run")
    jobs = res.jobs
    assert list(jobs.columns) == [*JOB_COLUMNS[:-1], "arrival_s", "release_jitter_s", "response_from_arrival_s",
                                  "outcome"]
    a = jobs[jobs.task == "a"]
    assert np.allclose(a.arrival_s - a.release_s, a.release_jitter_s)
    assert ((a.release_jitter_s >= 0) & (a.release_jitter_s <= 0.003)).all()
    assert np.allclose(a.finish_s - a.arrival_s, a.response_from_arrival_s)
    assert np.allclose(a.response_s - a.release_jitter_s, a.response_from_arrival_s)  # response counts from release
    assert jobs[jobs.task == "b"].release_jitter_s.isna().all()  # b has no jitter: empty cells
    m = res.metrics
    assert m["task.cpu.a.max_release_jitter_s"] == pytest.approx(a.release_jitter_s.max())
    assert m["task.cpu.a.max_response_from_arrival_s"] == pytest.approx(a.response_from_arrival_s.max())
    assert "task.cpu.b.max_release_jitter_s" not in m.index
    # read back from jobs.csv: the same metrics (the DataFrame path)
    back = read_table(tmp_path / "run" / "jobs.csv", JOB_TYPES)
    again = _task_metrics(back, 0.2)
    for key in ("max_release_jitter_s", "max_response_from_arrival_s", "mean_response_from_arrival_s"):
        assert again[f"task.cpu.a.{key}"] == pytest.approx(m[f"task.cpu.a.{key}"], rel=1e-12)


def test_a_run_without_the_features_keeps_its_jobs_columns():
    res = _run({"period": "10 ms"})
    assert list(res.jobs.columns) == JOB_COLUMNS
    assert not [k for k in res.metrics.index if "arrival" in k or "jitter" in k]


def test_the_seed_fixes_every_draw_and_another_seed_changes_them():
    fields = {"min_interarrival": "7 ms", "extra_interarrival": {"dist": "exponential", "mean": "3 ms"},
              "release_jitter": {"dist": "uniform", "low": "0 ms", "high": "1 ms"}}
    one, two = _run(fields), _run(fields)
    assert one.jobs.equals(two.jobs)
    raw = _raw(**fields)
    raw["seed"] = 6
    other = netsim.run(raw, out=None)
    assert not np.array_equal(one.jobs[one.jobs.task == "a"].release_s.to_numpy()[:5],
                              other.jobs[other.jobs.task == "a"].release_s.to_numpy()[:5])


def test_abort_on_miss_is_counted_as_killed_and_missed():
    # a: C = 3 ms > D = 2 ms: every job is killed at its deadline
    res = _run({"period": "10 ms", "deadline": "2 ms", "execution": "3 ms", "abort_on_miss": True})
    a = res.jobs[(res.jobs.task == "a") & (res.jobs.outcome != "pending")]  # the job released at the end
    assert len(a) == 20 and (a.outcome == "killed").all() and a.response_s.isna().all()
    assert np.allclose(a.finish_s, a.deadline_s)
    assert res.metrics["task.cpu.a.killed"] == len(a) == res.metrics["task.cpu.a.deadline_misses"]
    assert math.isnan(res.metrics["task.cpu.a.max_response_s"])
