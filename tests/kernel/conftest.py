"""Helpers shared by the kernel tests: building a kernel and simple task bodies."""

from __future__ import annotations

from typing import Any, Callable

import pytest

from netsim.env import SimEnv
from netsim.kernel import Kernel


def exec_body(*durations: int, log: list[Any] | None = None) -> Callable[[Any], Any]:
    """A body that executes ``durations`` in turn (and logs ``(task, job_id, start_of_code)``)."""

    def body(job: Any) -> Any:
        if log is not None:
            log.append((job.task_name, job.job_id, job.now))
        for d in durations:
            yield job.execute(d)

    return body


@pytest.fixture
def env() -> SimEnv:
    return SimEnv(seed=3)


@pytest.fixture
def make_kernel(env: SimEnv) -> Callable[..., Kernel]:
    def make(policy: str = "fp", **kwargs: Any) -> Kernel:
        return Kernel(env, kwargs.pop("name", "node"), policy=policy, **kwargs)

    return make


@pytest.fixture
def body_factory() -> Callable[..., Callable[[Any], Any]]:
    return exec_body
