"""The few numbers a reader wants first from a run: control measures, then timing (``netsim run`` prints them,
a notebook shows them in :meth:`netsim.results.RunResult._repr_html_`)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Mapping

if TYPE_CHECKING:  # for the annotation alone: the summary reads any mapping (issue 29: `netsim run` loads no pandas)
    import pandas as pd

__all__ = ["key_metrics", "seconds_text"]


def seconds_text(value: float) -> str:
    """A duration in seconds as readable text in its unit (``3.5 ms``)."""
    if math.isnan(value):
        return "-"
    a = abs(value)
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6), ("ns", 1e-9)):
        if a >= scale or unit == "ns":
            return f"{value / scale:.4g} {unit}"
    return f"{value:.4g} s"  # pragma: no cover


_TIMING_SCOPES = ("cpu.", "task.", "net.", "latency.")


def key_metrics(metrics: pd.Series | Mapping[str, float] | None) -> tuple[list[tuple[str, str]], list[tuple[str, str]]]:
    """The metrics a reader wants first, as ``(name, text)`` rows: control, then timing.

    Control: every metric outside the ``cpu``, ``task``, ``net`` and ``latency`` scopes (``y.ISE``, ``et.GPI``,
    ``cart.sigma_u``, ...), in ``metrics.csv`` order. Timing: per task the worst response and the deadline misses
    out of the jobs, per network the loss and the worst delay, and the loop latency; times in their unit.
    """
    if metrics is None:
        return [], []
    m = {str(k): float(v) for k, v in dict(metrics).items()}
    control = [(k, f"{v:.6g}") for k, v in m.items() if not k.startswith(_TIMING_SCOPES)]
    timing: list[tuple[str, str]] = []
    for k, v in m.items():
        if k.startswith("task.") and k.endswith(".max_response_s"):
            base = k.removesuffix(".max_response_s")
            misses, jobs = m.get(f"{base}.deadline_misses", math.nan), m.get(f"{base}.jobs", math.nan)
            text = f"worst response {seconds_text(v)}"
            if not math.isnan(misses):
                text += f", {misses:.0f} deadline misses" + (f" in {jobs:.0f} jobs" if not math.isnan(jobs) else "")
            timing.append((base, text))
        elif k.startswith("net.") and k.endswith(".loss_rate"):
            base = k.removesuffix(".loss_rate")
            worst = m.get(f"{base}.max_delay_s", math.nan)
            sent = m.get(f"{base}.messages", math.nan)
            text = f"{100.0 * v:.3g} % lost" + (f" of {sent:.0f} messages" if not math.isnan(sent) else "")
            timing.append((base, text + f", worst delay {seconds_text(worst)}"))
        elif k == "latency.max_s":
            mean = m.get("latency.mean_s", math.nan)
            timing.append(("latency", f"sample to actuation: worst {seconds_text(v)}, mean {seconds_text(mean)}"))
    return control, timing
