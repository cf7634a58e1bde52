"""TaskSpec/HandlerSpec: the kernel's frozen descriptions are the one definition of a task and a handler."""

from __future__ import annotations

import dataclasses

import pytest

from netsim.env import SimEnv
from netsim.errors import BuildError
from netsim.kernel import HandlerSpec, Kernel, TaskSpec
from netsim.kernel.task import CheckedTask
from netsim.scenario import schema
from netsim.timebase import MS, US


def body(job):
    yield job.execute(1 * MS)


def test_checked_fills_the_deadline_with_the_period_and_keeps_the_rest():
    spec = TaskSpec("ctl", period=10 * MS, priority=2).checked("cpu")
    assert _fields(spec) == _fields(TaskSpec("ctl", period=10 * MS, offset=0, deadline=10 * MS, priority=2, wcet=None,
                                             preemptible=True))
    assert TaskSpec("bg").checked("cpu").deadline is None  # aperiodic without a deadline: none


@pytest.mark.parametrize("fields, field, text", [
    ({"period": 0}, "period", "must be positive"),
    ({"offset": 3}, "offset", "applies to periodic and sporadic tasks only"),
    ({"period": 5, "priority": "high"}, "priority", "must be a number"),
    ({"period": 5, "wcet_handler": "h"}, "wcet_handler", "needs a 'wcet' budget"),
    ({"deadline_handler": "h"}, "deadline_handler", "needs a deadline"),
])
def test_checked_names_node_task_and_field(fields, field, text):
    with pytest.raises(BuildError, match=text) as info:
        TaskSpec("t", **fields).checked("cpu")
    assert (info.value.node, info.value.task, info.value.field) == ("cpu", "t", field)


def test_add_task_and_add_handler_take_the_descriptions():
    env = SimEnv()
    k = Kernel(env, "cpu")
    task = k.add_task(TaskSpec("ctl", period=5 * MS, priority=1), body)
    handler = k.add_handler(HandlerSpec("isr", priority=0, latency=10 * US), body)
    assert task.spec.deadline == 5 * MS and handler.spec.latency == 10 * US
    with pytest.raises(BuildError, match=r"task 'isr2', field 'latency'"):
        k.add_handler(HandlerSpec("isr2", latency=-1), body)
    env.run(5 * MS + 1)
    # the job released at 0 runs its 1 ms alone: response 1 ms; the one released at 5 ms is still running
    assert [(r.release, r.response) for r in k.job_records] == [(0, 1 * MS), (5 * MS, None)]


def test_the_yaml_task_is_the_kernel_task_spec():
    # one description: the scenario's task entry is a kernel TaskSpec (no copy of its fields or defaults)
    assert issubclass(schema.TaskSpec, TaskSpec)
    for name, field in TaskSpec.model_fields.items():
        assert name in schema.TaskSpec.model_fields
        assert schema.TaskSpec.model_fields[name].default == field.default, name


def test_the_yaml_handler_is_the_kernel_handler_spec():
    assert issubclass(schema.HandlerSpec, HandlerSpec)
    for name, field in HandlerSpec.model_fields.items():
        assert schema.HandlerSpec.model_fields[name].default == field.default, name


def _fields(spec):
    return {name: getattr(spec, name) for name in TaskSpec.model_fields}


def test_a_yaml_task_is_checked_by_the_kernel_as_it_is():
    task = schema.TaskSpec.model_validate({"name": "ctl", "program": "p", "period": "10 ms", "priority": 1,
                                           "wcet": "2 ms", "wcet_handler": "ovr"})
    assert _fields(task.checked("cpu")) == _fields(TaskSpec("ctl", period=10 * MS, deadline=10 * MS, priority=1,
                                                             wcet=2 * MS, wcet_handler="ovr", release="periodic"))
    on_msg = schema.TaskSpec.model_validate({"name": "act", "program": "p", "release": "on_message:can"})
    assert on_msg.checked("cpu").period is None and on_msg.release_network == "can"
    isr = schema.HandlerSpec.model_validate({"name": "isr", "program": "p", "latency": "5 us", "priority": 2})
    assert isr.checked("cpu") == HandlerSpec("isr", 2, 5 * US).checked("cpu")


def test_the_checked_form_has_exactly_the_task_spec_fields():
    # the kernel runs from a slotted record (fast reads at every release), made from TaskSpec's own field list
    assert [f.name for f in dataclasses.fields(CheckedTask)] == list(TaskSpec.model_fields)
    assert TaskSpec("ctl", period=5 * MS).checked("cpu").replaced(period=7 * MS).period == 7 * MS


def test_checked_runs_once_per_node_for_one_description():
    spec = TaskSpec("ctl", period=10 * MS, priority=2)
    assert spec.checked("cpu") is spec.checked("cpu")  # validate's dry run and the build share it
    assert spec.checked("other") is not spec.checked("cpu")
