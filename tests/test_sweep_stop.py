"""An interrupted sweep on the process pool stops at once: its workers are terminated, not waited for."""

from __future__ import annotations

import signal
import time

import pytest

from netsim.sweep.executor import _init_worker, open_executor


def _sleep(seconds: float) -> float:
    time.sleep(seconds)
    return seconds


def _sigterm_handler() -> str:
    _init_worker()
    return "default" if signal.getsignal(signal.SIGTERM) == signal.SIG_DFL else "other"


def test_an_interrupt_terminates_the_runs_in_flight_instead_of_waiting_for_them() -> None:
    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt), open_executor(workers=2) as (pool, _, _):
        futures = [pool.submit(_sleep, 60.0) for _ in range(2)]
        time.sleep(1.0)  # both workers are inside their 60 s run
        raise KeyboardInterrupt
    assert time.monotonic() - t0 < 30.0  # waiting for the runs would take 60 s
    assert all(f.done() for f in futures)


def test_a_pool_worker_dies_at_sigterm_whatever_handler_it_inherited() -> None:
    # the CLI turns SIGTERM into KeyboardInterrupt in its own process; a forked worker inherits that handler
    previous = signal.signal(signal.SIGTERM, lambda signum, frame: None)
    try:
        with open_executor(workers=2) as (pool, _, _):
            assert pool.submit(_sigterm_handler).result(timeout=60) == "default"
    finally:
        signal.signal(signal.SIGTERM, previous)
