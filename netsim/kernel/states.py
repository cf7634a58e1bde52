"""Life-cycle states of a job (task job or handler invocation), as small integers for speed."""

from __future__ import annotations

__all__ = ["NEW", "READY", "RUNNING", "BLOCKED", "DONE", "STATE_NAMES"]

NEW = 0  # released, queued behind an earlier job of the same task
READY = 1  # waiting for the CPU
RUNNING = 2  # holds the CPU
BLOCKED = 3  # sleeping or waiting on a mailbox, semaphore or event
DONE = 4  # finished or killed

STATE_NAMES = {NEW: "queued", READY: "ready", RUNNING: "running", BLOCKED: "blocked", DONE: "done"}
