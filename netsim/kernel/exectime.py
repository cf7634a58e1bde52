"""Execution-time models: how long a piece of task code occupies the CPU.

An :class:`ExecTime` is handed to ``job.execute(...)``; every call draws one duration in integer
nanoseconds. Random models draw from the node's execution-time stream
``env.rng(f"kernel.{node}.exec")`` (the kernel passes it in), so a run is reproducible from its seed.

Examples
--------
>>> import numpy as np
>>> ExecTime.constant(500_000).draw(np.random.default_rng(0))
500000
>>> ExecTime.from_spec("0.5 ms").draw(np.random.default_rng(0))
500000
>>> spec = {"dist": "uniform", "low": "0.4 ms", "high": "0.6 ms"}
>>> 400_000 <= ExecTime.from_spec(spec).draw(np.random.default_rng(0)) <= 600_000
True
"""

from __future__ import annotations

import difflib
from typing import Any, Callable, Sequence

import numpy as np

from netsim.errors import ConfigError, SimulationError
from netsim.timebase import TimeParseError, format_time, parse_time

__all__ = ["ExecTime"]

_DISTS: dict[str, tuple[str, ...]] = {
    "constant": ("value",),
    "uniform": ("low", "high"),
    "normal": ("mean", "std", "min", "max"),
    "empirical": ("values",),
    "exponential": ("mean", "shift"),
}


def _ns(value: Any, what: str) -> int:
    """A non-negative integer number of nanoseconds from an int (ns) or a float (rounded)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ConfigError(f"{what} must be a number of nanoseconds, got {value!r}")
    ns = int(round(float(value))) if not isinstance(value, (int, np.integer)) else int(value)
    if ns < 0:
        raise ConfigError(f"{what} must not be negative, got {ns} ns")
    return ns


def _spec_time(value: Any, what: str) -> int:
    """Parse a YAML time (``"0.5 ms"`` or seconds) into ns, naming ``what`` on error."""
    try:
        return parse_time(value)
    except TimeParseError as exc:
        raise ConfigError(f"{what}: {exc}") from None


class ExecTime:
    """A model of execution time, drawn once per ``job.execute`` request.

    Build one with the class methods :meth:`constant`, :meth:`uniform`, :meth:`normal`,
    :meth:`empirical`, :meth:`function`, or from a YAML spec with :meth:`from_spec`.

    Attributes
    ----------
    kind : str
        ``"constant"``, ``"uniform"``, ``"normal"``, ``"empirical"``, ``"exponential"`` or ``"function"``.
    const : int | None
        The duration of a ``"constant"`` model (what every :meth:`draw` returns), else ``None``; the kernel
        reads it instead of calling :meth:`draw`.
    """

    __slots__ = ("kind", "_a", "_b", "_lo", "_hi", "_values", "_fn", "const")

    def __init__(self, kind: str, a: int = 0, b: int = 0, lo: int = 0, hi: int | None = None,
                 values: np.ndarray | None = None, fn: Callable[[Any], Any] | None = None) -> None:
        self.kind = kind
        self._a = a
        self._b = b
        self._lo = lo
        self._hi = hi
        self._values = values
        self._fn = fn
        self.const = a if kind == "constant" else None

    # ----------------------------------------------------------------- constructors
    @classmethod
    def constant(cls, ns: int) -> "ExecTime":
        """Always ``ns`` nanoseconds."""
        return cls("constant", a=_ns(ns, "constant execution time"))

    @classmethod
    def uniform(cls, lo: int, hi: int) -> "ExecTime":
        """Uniform integer nanoseconds in ``[lo, hi]``."""
        lo_ns, hi_ns = _ns(lo, "uniform execution time 'low'"), _ns(hi, "uniform execution time 'high'")
        if hi_ns < lo_ns:
            raise ConfigError(f"uniform execution time needs low <= high, got low={lo_ns} ns, high={hi_ns} ns")
        return cls("uniform", a=lo_ns, b=hi_ns)

    @classmethod
    def normal(cls, mean: int, std: int, lo: int = 0, hi: int | None = None) -> "ExecTime":
        """Normal with ``mean`` and ``std`` (ns), clipped to ``[lo, hi]`` (``hi=None``: no upper bound)."""
        mean_ns = _ns(mean, "normal execution time 'mean'")
        std_ns = _ns(std, "normal execution time 'std'")
        lo_ns = _ns(lo, "normal execution time 'min'")
        hi_ns = None if hi is None else _ns(hi, "normal execution time 'max'")
        if hi_ns is not None and hi_ns < lo_ns:
            raise ConfigError(f"normal execution time needs min <= max, got min={lo_ns} ns, max={hi_ns} ns")
        return cls("normal", a=mean_ns, b=std_ns, lo=lo_ns, hi=hi_ns)

    @classmethod
    def empirical(cls, values: Sequence[int]) -> "ExecTime":
        """One of ``values`` (ns), each equally likely (a measured histogram as raw samples)."""
        vals = [_ns(v, "empirical execution time value") for v in values]
        if not vals:
            raise ConfigError("empirical execution time needs at least one value")
        return cls("empirical", values=np.asarray(vals, dtype=np.int64))

    @classmethod
    def exponential(cls, mean: int, shift: int = 0) -> "ExecTime":
        """``shift`` plus an exponential variable of mean ``mean`` (ns, rounded to integer ns): e.g. the random
        part of a sporadic task's inter-arrival time (unbounded: :attr:`upper_bound` is ``None``)."""
        mean_ns = _ns(mean, "exponential time 'mean'")
        if mean_ns <= 0:
            raise ConfigError(f"exponential time needs a positive mean, got {mean_ns} ns")
        return cls("exponential", a=mean_ns, lo=_ns(shift, "exponential time 'shift'"))

    @classmethod
    def function(cls, fn: Callable[[Any], int]) -> "ExecTime":
        """Data-dependent: ``fn(job) -> ns`` is called at each request (e.g. depends on ``job.data``)."""
        if not callable(fn):
            raise ConfigError(f"function execution time needs a callable fn(job) -> ns, got {fn!r}")
        return cls("function", fn=fn)

    @classmethod
    def from_spec(cls, spec: Any) -> "ExecTime":
        """Parse a YAML execution-time spec.

        Parameters
        ----------
        spec
            ``"0.5 ms"`` (or a bare number of **seconds**), an :class:`ExecTime` (returned as is), or a
            mapping ``{dist: uniform, low, high}``, ``{dist: normal, mean, std, min, max}``,
            ``{dist: empirical, values: [...]}``, ``{dist: constant, value}``, ``{dist: exponential, mean,
            shift}``; times in the mapping are
            strings with units or seconds.

        Raises
        ------
        ConfigError
            For a negative time, an unknown ``dist`` (with a suggestion) or unknown/missing keys.
        """
        if isinstance(spec, ExecTime):
            return spec
        if spec is None:
            raise ConfigError("execution time is missing; write e.g. '0.5 ms' or {dist: uniform, low, high}")
        if isinstance(spec, (str, int, float)) and not isinstance(spec, bool):
            return cls.constant(_spec_time(spec, "execution time"))
        if not isinstance(spec, dict):
            raise ConfigError(f"execution time must be a time or a mapping with 'dist', got {spec!r}")
        dist = spec.get("dist")
        if dist not in _DISTS:
            close = difflib.get_close_matches(str(dist), list(_DISTS), n=1)
            hint = f"; did you mean '{close[0]}'?" if close else f" (known: {', '.join(_DISTS)})"
            raise ConfigError(f"unknown execution-time dist {dist!r}{hint}")
        allowed = _DISTS[dist]
        for key in spec:
            if key != "dist" and key not in allowed:
                close = difflib.get_close_matches(str(key), list(allowed), n=1)
                hint = f"; did you mean '{close[0]}'?" if close else f" (allowed: {', '.join(allowed)})"
                raise ConfigError(f"execution time dist '{dist}' has no key '{key}'{hint}")

        def need(key: str) -> Any:
            if key not in spec:
                raise ConfigError(f"execution time dist '{dist}' needs '{key}'")
            return spec[key]

        if dist == "constant":
            return cls.constant(_spec_time(need("value"), "execution time 'value'"))
        if dist == "uniform":
            return cls.uniform(_spec_time(need("low"), "execution time 'low'"),
                               _spec_time(need("high"), "execution time 'high'"))
        if dist == "normal":
            lo = _spec_time(spec.get("min", 0), "execution time 'min'")
            hi = spec.get("max")
            return cls.normal(_spec_time(need("mean"), "execution time 'mean'"),
                              _spec_time(need("std"), "execution time 'std'"), lo,
                              None if hi is None else _spec_time(hi, "execution time 'max'"))
        if dist == "exponential":
            return cls.exponential(_spec_time(need("mean"), "exponential time 'mean'"),
                                   _spec_time(spec.get("shift", 0), "exponential time 'shift'"))
        values = need("values")
        if not isinstance(values, (list, tuple)):
            raise ConfigError(f"execution time dist 'empirical' needs a list of 'values', got {values!r}")
        return cls.empirical([_spec_time(v, "execution time value") for v in values])

    # ----------------------------------------------------------------- drawing
    def draw(self, rng: np.random.Generator, job: Any = None) -> int:
        """One execution time in nanoseconds.

        Parameters
        ----------
        rng
            The node's execution-time stream.
        job
            The requesting job (used by :meth:`function` models).
        """
        kind = self.kind
        if kind == "constant":
            return self._a
        if kind == "uniform":
            return int(rng.integers(self._a, self._b + 1))
        if kind == "normal":
            x = self._a + self._b * float(rng.standard_normal())
            if x < self._lo:
                x = self._lo
            if self._hi is not None and x > self._hi:
                x = self._hi
            return int(round(x))
        if kind == "empirical":
            values = self._values
            assert values is not None
            return int(values[int(rng.integers(0, len(values)))])
        if kind == "exponential":
            return self._lo + int(round(float(rng.exponential(float(self._a)))))
        assert self._fn is not None
        ns = self._fn(job)
        try:
            out = int(round(ns))
        except (TypeError, ValueError):
            raise SimulationError(f"execution-time function returned {ns!r}; it must return nanoseconds") from None
        if out < 0:
            raise SimulationError(f"execution-time function returned a negative time ({out} ns)")
        return out

    @property
    def upper_bound(self) -> int | None:
        """Largest possible draw in ns (``None`` when unbounded or data-dependent)."""
        if self.kind == "constant":
            return self._a
        if self.kind == "uniform":
            return self._b
        if self.kind == "normal":
            return self._hi
        if self.kind == "empirical":
            assert self._values is not None
            return int(self._values.max())
        return None

    def __repr__(self) -> str:
        if self.kind == "constant":
            return f"ExecTime.constant({format_time(self._a)!r})"
        if self.kind == "uniform":
            return f"ExecTime.uniform({format_time(self._a)!r}, {format_time(self._b)!r})"
        if self.kind == "normal":
            return f"ExecTime.normal(mean={self._a}, std={self._b}, lo={self._lo}, hi={self._hi})"
        if self.kind == "exponential":
            return f"ExecTime.exponential(mean={self._a}, shift={self._lo})"
        if self.kind == "empirical":
            return f"ExecTime.empirical(<{0 if self._values is None else len(self._values)} values>)"
        return f"ExecTime.function({self._fn!r})"
