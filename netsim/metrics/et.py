"""Cost functions of section 4 of Cuenca et al. (eqs 23-29) and the ``et_control`` run metric.

Pure functions on arrays and counts:

* :func:`ise` eq (23) ``sqrt(sum (r_k - y_k)^2)`` (of the time-triggered run);
* :func:`isep` eq (24) ``sqrt(sum (y_ETS_k - y_TTS_k)^2)``;
* :func:`sampling_efficiency` eq (25) ``NE = ISEP / ISE``;
* :func:`utilization` eqs (26)-(27) ``Uc = N_sc / N_TTS``, ``Ua = N_ca / N_TTS``;
* :func:`computation_saving_pct` eq (20), :func:`controller_computation` eq (28) ``Cc = Uc (1 - CS) 100``;
* :func:`gpi` eq (29) ``W1 Uc + W2 Ua + W3 NE`` (weights summing to 1).

The registered metric ``et_control`` computes them from a run: the sample sequences ``r_k``, ``y_k`` are
the recorded signals read at ``k T`` (held values), and the transmission counts come from the run's
**messages table** (by tag), never from counters inside the algorithms. ``ISE`` is the baseline's (the TTS
run of the same scenario) when a baseline is given -- "ISE will be a constant value along the study" --
and the run's own otherwise; ``ISEP`` needs the baseline.
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np
from pydantic import Field, field_validator

from netsim.errors import ConfigError
from netsim.metrics.rows import table_rows
from netsim.registry import register
from netsim.timebase import S
from netsim.units import Duration, StrictModel

__all__ = [
    "ise",
    "isep",
    "sampling_efficiency",
    "utilization",
    "computation_saving_pct",
    "controller_computation",
    "gpi",
    "sample_signal",
    "count_messages",
    "et_control",
    "EtControlParams",
    "ET_PREFIX",
    "LEGACY_METRIC_NAMES",
    "canonical_metric_names",
]

log = logging.getLogger(__name__)

#: Scope of the loop-level measures of :func:`et_control` (metric names are ``<scope>.<measure>``).
ET_PREFIX = "et"

#: Metric names written by older versions (before the ``<scope>.<measure>`` rule) -> today's names.
LEGACY_METRIC_NAMES: dict[str, str] = {
    name: f"{ET_PREFIX}.{name}"
    for name in ("N_TTS", "Nsc", "Nca", "Uc", "Ua", "CS", "Cc", "ISE_own", "ISE", "ISEP", "NE", "GPI")
}


def canonical_metric_names(values: dict[str, float]) -> dict[str, float]:
    """``values`` with legacy metric names (:data:`LEGACY_METRIC_NAMES`) renamed to today's names.

    A name that exists under both spellings keeps today's value.
    """
    out = {LEGACY_METRIC_NAMES.get(k, k): v for k, v in values.items() if k not in LEGACY_METRIC_NAMES}
    for old, new in LEGACY_METRIC_NAMES.items():
        if old in values and new not in out:
            out[new] = values[old]
    return out


def ise(r, y) -> float:
    """Eq (23): ``sqrt(sum_k (r_k - y_k)^2)``."""
    e = np.asarray(r, float) - np.asarray(y, float)
    return float(np.sqrt(np.sum(e * e)))


def isep(y_ets, y_tts) -> float:
    """Eq (24): ``sqrt(sum_k |y_ETS_k - y_TTS_k|^2)`` (same sample instants)."""
    a, b = np.asarray(y_ets, float), np.asarray(y_tts, float)
    if a.shape != b.shape:
        raise ConfigError(f"ISEP needs outputs on the same instants, got {a.shape} and {b.shape} samples")
    return float(np.sqrt(np.sum((a - b) ** 2)))


def sampling_efficiency(isep_value: float, ise_value: float) -> float:
    """Eq (25): ``NE = ISEP / ISE``; 0 when both are 0 (the ETS output equals a TTS output that tracks exactly).

    Raises
    ------
    ConfigError
        When ISE is 0 and ISEP is not: the ratio has no value (never a division by zero or an inf).
    """
    if ise_value <= 0:
        if isep_value == 0:
            return 0.0
        raise ConfigError("NE = ISEP/ISE is undefined when ISE is 0 and ISEP is not (the TTS run tracks its "
                          "reference exactly); use a reference the time-triggered loop does not track exactly")
    return float(isep_value) / float(ise_value)


def utilization(n_ets: int, n_tts: int) -> float:
    """Eqs (26)-(27): ``N_ETS / N_TTS``."""
    if n_tts <= 0:
        raise ConfigError("utilization needs N_TTS > 0")
    return n_ets / n_tts


def computation_saving_pct(m: int, n: int) -> float:
    """Eq (20): ``CS = (m - 1)/(m + n) * 100`` %."""
    return (m - 1) / (m + n) * 100.0


def controller_computation(uc: float, m: int, n: int) -> float:
    """Eq (28): ``Cc = Uc (1 - (m-1)/(m+n)) * 100`` %."""
    return uc * (1.0 - (m - 1) / (m + n)) * 100.0


def gpi(uc: float, ua: float, ne: float, weights=(0.45, 0.45, 0.1)) -> float:
    """Eq (29): ``W1 Uc + W2 Ua + W3 NE`` with ``sum W = 1``."""
    w = [float(x) for x in weights]
    if len(w) != 3 or any(x < 0 for x in w) or not math.isclose(sum(w), 1.0, abs_tol=1e-9):
        raise ConfigError(f"GPI weights must be three numbers >= 0 summing to 1, got {weights!r}")
    return w[0] * uc + w[1] * ua + w[2] * ne


def sample_signal(signals, name: str, times_s: np.ndarray) -> np.ndarray:
    """Values of recorded signal ``name`` held at ``times_s`` (last sample at or before each instant)."""
    if name not in signals.columns:
        raise ConfigError(f"et_control: signal '{name}' was not recorded (recorded: {', '.join(map(str, signals.columns))})")
    t = signals["time_s"].to_numpy(float)
    v = signals[name].to_numpy(float)
    ok = ~np.isnan(v)
    t, v = t[ok], v[ok]
    if t.size == 0:
        raise ConfigError(f"et_control: signal '{name}' has no samples")
    idx = np.searchsorted(t, times_s + 1e-12, side="right") - 1
    idx = np.clip(idx, 0, t.size - 1)
    return v[idx]


def count_messages(messages, tag: str, *, delivered: bool = False, before_s: float | None = None) -> int:
    """Messages sent with ``tag`` (optionally only delivered ones, sent before ``before_s``), from the table (a
    DataFrame, or the records' columns of :func:`netsim.metrics.rows.table_rows`)."""
    if messages is None or len(messages) == 0:
        return 0
    sel = np.asarray(messages["tag"]).astype(str) == tag
    if before_s is not None:
        sel &= np.asarray(messages["sent_s"], dtype=float) < before_s
    if delivered:
        sel &= ~np.asarray(messages["dropped"]).astype(bool)
    return int(sel.sum())


class EtControlParams(StrictModel):
    """Parameters of the ``et_control`` metric (validated with the scenario, before anything runs).

    Attributes
    ----------
    period
        The fast sampling period T (``"20 us"`` or seconds); required.
    reference, output
        Recorded signals read at ``k T``: the reference and the noise-free plant output.
    sensor_tag, actuator_tag
        Message tags of sensor-to-controller and controller-to-actuator transmissions.
    m, n
        The MRCI decomposition sizes of eq (20).
    weights
        ``W1, W2, W3`` of eq (29): three numbers >= 0 summing to 1.
    n_tts
        Number of periods compared (default: the periods in the run).
    multiplicity
        Recorded multiplicity signal ``N`` (eq 9, recorded by the controller at arrivals): its largest
        value in the window is ``et.N_max`` (left out when the signal is not recorded).
    past_end
        Recorded per-period flag of the actuator (1: a period played past the end of an ``h >= 1`` packet):
        its sum over the window is ``et.played_past_packet`` (left out when not recorded). A non-zero
        value means ``h < N_max`` (the paper asks for ``h >= N_max``) and is logged as a warning.
    """

    period: Duration
    reference: str = "r"
    output: str = "y"
    sensor_tag: str = "y"
    actuator_tag: str = "u"
    m: int = Field(default=2, ge=1)
    n: int = Field(default=1, ge=0)
    weights: tuple[float, float, float] = (0.45, 0.45, 0.1)
    n_tts: int | None = Field(default=None, gt=0)
    multiplicity: str = "N"
    past_end: str = "u_past_end"

    @field_validator("weights")
    @classmethod
    def _weights_sum_to_one(cls, value: tuple[float, float, float]) -> tuple[float, float, float]:
        if any(w < 0 for w in value):
            raise ValueError(f"GPI weights must not be negative, got {list(value)}")
        if not math.isclose(sum(value), 1.0, abs_tol=1e-9):
            raise ValueError(f"GPI weights must sum to 1, got {list(value)} (sum {sum(value):g})")
        return value


def _et_params(params: Any) -> EtControlParams:
    from netsim.metrics.runtime import validate_params

    return validate_params(EtControlParams, params, "et_control")


@register("metric", "et_control", "et.Uc, et.Ua, et.Cc, et.CS, et.ISE, et.ISEP, et.NE, et.GPI of Cuenca et al. "
         "eqs (20)-(29)")
def et_control(result: Any, params: Any, baseline: Any | None = None) -> dict[str, float]:
    """Metrics of an event-triggered run (``params``: :class:`EtControlParams`) against an optional TTS baseline.

    The names are ``et.<measure>`` (see :data:`LEGACY_METRIC_NAMES` for the unprefixed names of older run
    folders): ``et.N_TTS`` (by default the number of whole periods in the run, counted in integer nanoseconds),
    ``et.Nsc``, ``et.Nca`` (transmissions sensor->controller and controller->actuator in those periods),
    ``et.Uc``, ``et.Ua`` (eqs 26-27), ``et.CS`` (eq 20), ``et.Cc`` (eq 28), ``et.ISE`` (eq 23, of the TTS
    baseline when there is one), ``et.ISE_own`` (eq 23 of this run), ``et.ISEP`` (eq 24), ``et.NE`` (eq 25)
    and ``et.GPI`` (eq 29); when recorded, ``et.N_max`` (largest multiplicity) and ``et.played_past_packet``
    (periods the actuator played past its packet's end, i.e. ``h < N_max``), and from the messages table
    ``et.u_gap_max`` (the longest run of periods one packet had to cover). Eq (23) is a root of a sum over samples, not the time integral ``<y>.ISE`` of
    :func:`netsim.metrics.et.runtime.control_error`.
    """
    p = _et_params(params)
    sig = result.signals
    duration_s = float(result.meta.get("duration_s") or 0.0) if hasattr(result, "meta") else 0.0
    if not duration_s:
        duration_s = float(sig["time_s"].max()) if len(sig) else 0.0
    duration_ns = int(round(duration_s * S))
    n_tts = p.n_tts or duration_ns // p.period
    t_k = np.arange(n_tts, dtype=np.int64) * p.period / S
    ref, out, m, n = p.reference, p.output, p.m, p.n
    r_k = sample_signal(sig, ref, t_k)
    y_k = sample_signal(sig, out, t_k)
    # transmissions of the N_TTS periods [0, N_TTS T) (a run that also executes the instant N_TTS T must
    # not count that extra sample)
    window_s = n_tts * p.period / S
    # the records' columns while the messages DataFrame is unbuilt (a run's own result: no pandas table is made)
    messages = table_rows(result, "messages")
    if messages is None:
        messages = result.messages
    n_sc = count_messages(messages, p.sensor_tag, before_s=window_s)
    n_ca = count_messages(messages, p.actuator_tag, before_s=window_s)
    uc = utilization(n_sc, n_tts)
    ua = utilization(n_ca, n_tts)
    own_ise = ise(r_k, y_k)
    res = {
        "N_TTS": float(n_tts), "Nsc": float(n_sc), "Nca": float(n_ca), "Uc": uc, "Ua": ua,
        "CS": computation_saving_pct(m, n), "Cc": controller_computation(uc, m, n), "ISE_own": own_ise,
    }
    if baseline is not None:
        yb = sample_signal(baseline.signals, out, t_k)
        rb = sample_signal(baseline.signals, ref, t_k)
        res["ISE"] = ise(rb, yb)
        res["ISEP"] = isep(y_k, yb)
    else:
        res["ISE"] = own_ise
        res["ISEP"] = 0.0
    if res["ISE"] > 0 or res["ISEP"] == 0:
        res["NE"] = sampling_efficiency(res["ISEP"], res["ISE"])
        res["GPI"] = gpi(uc, ua, res["NE"], p.weights)
    else:  # NE has no value: leave NE and GPI out and say why (the run itself is fine)
        log.warning("et_control: et.NE and et.GPI are left out: the time-triggered run tracks the reference "
                    "exactly (ISE = 0, eq 23) but this run does not (ISEP = %.3g), so NE = ISEP/ISE (eq 25) has no "
                    "value; use a reference the time-triggered loop does not track exactly (e.g. a nonzero step)",
                    res["ISEP"])
    gap = _packet_gap_max(messages, p, n_tts, window_s)
    res.update(_horizon_measures(sig, p, t_k, window_s, gap))
    if gap is not None:
        res["u_gap_max"] = gap
    return {f"{ET_PREFIX}.{k}": v for k, v in res.items()}


et_control.tables = ("messages",)  # type: ignore[attr-defined]  # rows it reads (output.messages: full)


def _packet_gap_max(messages, p: EtControlParams, n_tts: int, window_s: float) -> float | None:
    """Longest run of periods one controller->actuator packet had to cover, from the messages table.

    Each packet is placed in the period it was sent (``floor(sent / T)``; the controller sends in the period
    of its measurement when the loop latency is below ``T``); the run of a packet lasts until the next one,
    the last one's until the end of the window. A packet with ``h`` future actions covers ``h + 1`` periods,
    so ``h >= u_gap_max - 1`` plays no period past a packet's end (None when no packet was sent).
    """
    if messages is None or len(messages) == 0:
        return None
    sent_s = np.asarray(messages["sent_s"], dtype=float)
    sel = (np.asarray(messages["tag"]).astype(str) == p.actuator_tag) & (sent_s < window_s)
    sent_ns = np.round(sent_s[sel] * S).astype(np.int64)
    if sent_ns.size == 0:
        return None
    k = np.unique(sent_ns // p.period)
    return float(np.max(np.diff(np.append(k, n_tts))))


def _horizon_measures(sig, p: EtControlParams, t_k: np.ndarray, window_s: float,
                      gap: float | None = None) -> dict[str, float]:
    """``N_max`` and ``played_past_packet`` from the recorded signals (only those that were recorded)."""
    out: dict[str, float] = {}
    cols = sig.columns
    t = sig["time_s"].to_numpy(float)

    def in_window(name: str) -> np.ndarray:
        v = sig[name].to_numpy(float)
        return v[~np.isnan(v) & (t < window_s)]

    if p.multiplicity in cols and in_window(p.multiplicity).size:
        out["N_max"] = float(np.max(in_window(p.multiplicity)))
    if p.past_end in cols and in_window(p.past_end).size:
        # the actuator's tick records the flag once per period, a little after k T (the table holds values):
        # read it at the end of each period, (k + 1) T - 1 ns
        played = float(np.sum(sample_signal(sig, p.past_end, t_k + (p.period - 1) / S)))
        out["played_past_packet"] = played
        if played > 0:
            log.warning("et_control: the actuator played %d period(s) past the end of its packet (h is shorter "
                        "than the longest run one packet had to cover%s); raise design_params.h", int(played),
                        f", {int(gap)} periods" if gap is not None else "")
    return out


et_control.Params = EtControlParams  # type: ignore[attr-defined]
