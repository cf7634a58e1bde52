"""The declarations the type checker reads for the checked task and handler records (netsim.kernel.checked)
describe the classes task.py makes at run time: same fields, in the same order, and the same extra members."""

import dataclasses

from netsim.kernel import checked
from netsim.kernel.task import CheckedHandler, CheckedTask, HandlerSpec, TaskSpec


def test_the_declared_checked_task_has_the_task_spec_fields_in_order():
    assert [f.name for f in dataclasses.fields(checked.CheckedTask)] == list(TaskSpec.model_fields)


def test_the_declared_checked_handler_has_the_handler_spec_fields_in_order():
    assert [f.name for f in dataclasses.fields(checked.CheckedHandler)] == list(HandlerSpec.model_fields)


def test_the_declared_checked_task_names_the_members_the_run_time_class_has():
    declared = {k for k, v in vars(checked.CheckedTask).items() if isinstance(v, property) or callable(v)}
    declared -= {k for k in declared if k.startswith("_")}
    assert declared == {"release_kind", "release_network", "self_released", "replaced"}
    assert all(hasattr(CheckedTask, k) for k in declared)
    assert not hasattr(CheckedHandler, "replaced")
