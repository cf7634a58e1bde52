"""The kernel package's layout: one method per request, a job that sees only its context, small modules."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import netsim.kernel
from netsim.env import SimEnv
from netsim.errors import SimulationError
from netsim.kernel import Job, Kernel, Mailbox, Request
from netsim.kernel.interpreter import Interpreter
from netsim.kernel.job import JobContext
from netsim.kernel.requests import OP_NAMES, Op

KERNEL_DIR = Path(netsim.kernel.__file__).parent
#: DESIGN.md: "modules mostly under 500 lines"; a longer one must say why in its docstring.
MAX_LINES = 500


def test_every_request_but_execute_has_its_own_method_and_a_job_method_of_the_same_name():
    for op in Op:
        assert OP_NAMES[op] == op.name.lower()
        assert callable(getattr(Job, OP_NAMES[op])), f"Job has no method {OP_NAMES[op]}"
        if op is Op.EXECUTE:
            continue  # answered inline by Interpreter._advance (the hot path)
        method = getattr(Interpreter, f"_op_{OP_NAMES[op]}")
        assert Interpreter._OPS[op] is method


def test_a_request_with_an_unknown_operation_is_refused_with_the_task_named():
    env = SimEnv()
    k = Kernel(env, "cpu")

    def body(job):
        yield Request(99)  # type: ignore[arg-type]

    k.create_task("bad", body, priority=1)
    k.create_job("bad")
    with pytest.raises(SimulationError, match=r"task 'bad': unknown request"):
        env.run(10)


def test_a_job_reaches_its_kernel_through_its_context_only():
    env = SimEnv()
    k = Kernel(env, "cpu")
    mb = Mailbox("m")
    seen = {}

    def consumer(job):
        seen["item"] = yield job.fetch(mb)  # blocks: the producer's post unblocks it through the context
        seen["ctx"] = job._ctx

    def producer(job):
        yield job.execute(5)
        yield job.post(mb, "x")

    k.create_task("consumer", consumer, priority=1)
    k.create_task("producer", producer, priority=2)
    k.create_job("consumer")
    k.create_job("producer")
    env.run(100)
    assert seen["item"] == "x"
    ctx = seen["ctx"]
    assert isinstance(ctx, JobContext)
    assert ctx.kernel is k and ctx.shared is k.shared and ctx.rng is k.rng and ctx.name == "cpu"
    assert not hasattr(Job, "_kernel")


@pytest.mark.parametrize("path", sorted(KERNEL_DIR.glob("*.py")), ids=lambda p: p.name)
def test_kernel_modules_are_short_or_say_why(path: Path):
    text = path.read_text(encoding="utf-8")
    n = text.count("\n")
    if n <= MAX_LINES:
        return
    doc = ast.get_docstring(ast.parse(text)) or ""
    assert "Why this module is long:" in doc, (
        f"{path.name} has {n} lines (> {MAX_LINES}); split it, or say in its docstring 'Why this module is long: ...'")


def test_the_package_exports_every_public_name_from_its_home_module():
    for name in netsim.kernel.__all__:
        obj = getattr(netsim.kernel, name)
        home = "netsim.distributions" if name == "ExecTime" else "netsim.kernel."  # one family of random times
        assert obj.__module__.startswith(home), name
    assert set(netsim.kernel.__all__) == set(netsim.kernel._HOMES)
    with pytest.raises(AttributeError, match="no attribute 'Nope'"):
        netsim.kernel.Nope  # noqa: B018
