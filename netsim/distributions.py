"""One family of random times: execution times, release jitter, inter-arrival gaps and link delays.

Every random time of a scenario is one of these frozen models, validated once from YAML and then used as is by
the code that draws from it (the kernel, a link) and by the analysis (its :meth:`~Distribution.upper_bound`).
In YAML a time is written as a time (``"1 ms"``: constant) or as a mapping with ``dist``::

    {dist: constant, value: 1 ms}
    {dist: uniform, low: 1 ms, high: 3 ms}                     # integer ns in [low, high]
    {dist: normal, mean: 1 ms, std: 0.1 ms, min: 0 s, max: 2 ms}   # clipped to [min, max]
    {dist: exponential, mean: 2 ms, shift: 0.5 ms}             # shift + exponential of mean 'mean'
    {dist: shifted_gamma, shape: 2.0, scale: 1 ms, shift: 0.5 ms}  # shift + gamma (mean shape * scale)
    {dist: empirical, values: [1 ms, 2 ms]}                    # or file: delays.csv, column: delay, unit: ms

In Python (integer nanoseconds) the class methods of :class:`Distribution` build them:
``Distribution.uniform(400_000, 600_000)``; ``Distribution.function(fn)`` is a data-dependent time
(``fn(job) -> ns``) that has no YAML form. :class:`netsim.kernel.ExecTime` is this class.

Each :meth:`~Distribution.draw` takes the random stream of its user (``kernel.<node>.exec``,
``kernel.<node>.release.<task>``, ``network.<name>.delay``) and returns integer nanoseconds; a constant draws
nothing from the stream.

Examples
--------
>>> import numpy as np
>>> from pydantic import TypeAdapter
>>> d = TypeAdapter(DistributionSpec).validate_python({"dist": "uniform", "low": "1 ms", "high": "3 ms"})
>>> d.upper_bound()
3000000
>>> 1_000_000 <= d.draw(np.random.default_rng(0)) <= 3_000_000
True
>>> TypeAdapter(DistributionSpec).validate_python("2 ms").upper_bound()
2000000
"""

from __future__ import annotations

import csv
import difflib
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Callable, Literal, Sequence, Union, get_args

import numpy as np
from pydantic import (
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    PrivateAttr,
    Tag,
    TypeAdapter,
    ValidationError,
    model_serializer,
    model_validator,
)

from netsim.errors import ConfigError, SimulationError
from netsim.timebase import UNITS
from netsim.units import Duration, StrictModel, Time

if TYPE_CHECKING:
    from netsim.kernel.job import Job

__all__ = [
    "DISTS",
    "TAG_MARK",
    "Constant",
    "Distribution",
    "DistributionSpec",
    "Empirical",
    "Exponential",
    "Function",
    "Normal",
    "ShiftedGamma",
    "Uniform",
    "dist_tag",
    "load_delays_csv",
    "shorthand",
]

#: The ``dist`` names YAML accepts (``gamma`` is also read as ``shifted_gamma``).
DISTS = ("constant", "uniform", "normal", "exponential", "shifted_gamma", "empirical")

#: The mark of a union member's tag in a validation error's location: :mod:`netsim.scenario.messages` drops such
#: parts, so a problem's path is the YAML one (``release_jitter.high``, not ``release_jitter.§uniform.high``).
TAG_MARK = "§"


def _ns(value: Any, what: str) -> int:
    """A non-negative integer number of nanoseconds from an int (ns) or a float (rounded)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ConfigError(f"{what} must be a number of nanoseconds, got {value!r}")
    ns = int(value) if isinstance(value, (int, np.integer)) else int(round(float(value)))
    if ns < 0:
        raise ConfigError(f"{what} must not be negative, got {ns} ns")
    return ns


class Distribution(StrictModel):
    """A random time in integer nanoseconds (the base of the family; see the module notes).

    Attributes
    ----------
    dist : str
        The member's name, as written in YAML.
    """

    model_config = ConfigDict(extra="forbid", frozen=True, validate_assignment=False)

    dist: str

    def draw(self, rng: np.random.Generator, job: Job | None = None) -> int:
        """One draw in ns from ``rng`` (``job``: the requesting job, read by :class:`Function` only)."""
        raise NotImplementedError

    def upper_bound(self) -> int | None:
        """The largest possible draw in ns (``None``: unbounded or data-dependent)."""
        return None

    def sampler(self, rng: np.random.Generator) -> Callable[[], int]:
        """A function of no argument drawing from ``rng`` (for a hot loop, e.g. a link's delays)."""
        return lambda: self.draw(rng)

    @property
    def const(self) -> int | None:
        """The value of a constant (what every draw returns), else ``None``."""
        return None

    # ------------------------------------------------------------------ Python constructors (integer ns)
    @staticmethod
    def constant(ns: int) -> Constant:
        """Always ``ns`` nanoseconds."""
        return Constant.model_construct(dist="constant", value=_ns(ns, "constant execution time"))

    @staticmethod
    def uniform(lo: int, hi: int) -> Uniform:
        """Uniform integer nanoseconds in ``[lo, hi]``."""
        lo_ns, hi_ns = _ns(lo, "uniform execution time 'low'"), _ns(hi, "uniform execution time 'high'")
        if hi_ns < lo_ns:
            raise ConfigError(f"uniform execution time needs low <= high, got low={lo_ns} ns, high={hi_ns} ns")
        return Uniform.model_construct(dist="uniform", low=lo_ns, high=hi_ns)

    @staticmethod
    def normal(mean: int, std: int, lo: int = 0, hi: int | None = None) -> Normal:
        """Normal with ``mean`` and ``std`` (ns), clipped to ``[lo, hi]`` (``hi=None``: no upper bound)."""
        mean_ns = _ns(mean, "normal execution time 'mean'")
        std_ns = _ns(std, "normal execution time 'std'")
        lo_ns = _ns(lo, "normal execution time 'min'")
        hi_ns = None if hi is None else _ns(hi, "normal execution time 'max'")
        if hi_ns is not None and hi_ns < lo_ns:
            raise ConfigError(f"normal execution time needs min <= max, got min={lo_ns} ns, max={hi_ns} ns")
        return Normal.model_construct(dist="normal", mean=mean_ns, std=std_ns, min=lo_ns, max=hi_ns)

    @staticmethod
    def exponential(mean: int, shift: int = 0) -> Exponential:
        """``shift`` plus an exponential variable of mean ``mean`` (ns, rounded to integer ns; unbounded)."""
        mean_ns = _ns(mean, "exponential time 'mean'")
        if mean_ns <= 0:
            raise ConfigError(f"exponential time needs a positive mean, got {mean_ns} ns")
        return Exponential.model_construct(dist="exponential", mean=mean_ns, shift=_ns(shift, "exponential time 'shift'"))

    @staticmethod
    def empirical(values: Sequence[int]) -> Empirical:
        """One of ``values`` (ns), each equally likely (a measured histogram as raw samples)."""
        vals = [_ns(v, "empirical execution time value") for v in values]
        if not vals:
            raise ConfigError("empirical execution time needs at least one value")
        return Empirical.model_construct(dist="empirical", values=vals, file=None, column=0, unit="s")

    @staticmethod
    def function(fn: Callable[[Any], int]) -> Function:
        """Data-dependent: ``fn(job) -> ns`` is called at each request (e.g. depends on ``job.data``)."""
        if not callable(fn):
            raise ConfigError(f"function execution time needs a callable fn(job) -> ns, got {fn!r}")
        return Function.model_construct(dist="function", fn=fn)

    @staticmethod
    def from_spec(spec: Any) -> Distribution:
        """A distribution from its YAML form (``"0.5 ms"`` or a mapping with ``dist``); one is returned as is.

        For Python callers that hold YAML-like data; a scenario's fields are validated by the schema instead.

        Raises
        ------
        ConfigError
            For a negative or unreadable time, an unknown ``dist`` (with a suggestion), unknown or missing keys.
        """
        if isinstance(spec, Distribution):
            return spec
        if spec is None:
            raise ConfigError("execution time is missing; write e.g. '0.5 ms' or {dist: uniform, low, high}")
        if isinstance(spec, dict) and spec.get("dist") not in (*DISTS, "gamma"):
            dist = spec.get("dist")
            close = difflib.get_close_matches(str(dist), list(DISTS), n=1)
            hint = f"; did you mean '{close[0]}'?" if close else f" (known: {', '.join(DISTS)})"
            raise ConfigError(f"unknown execution-time dist {dist!r}{hint}")
        try:
            return _ADAPTER.validate_python(spec)
        except ValidationError as exc:
            raise ConfigError(_first_error(exc, spec)) from None


class Constant(Distribution):
    """Always ``value`` (the same as writing the time itself)."""

    dist: Literal["constant"] = "constant"
    value: Time = 0

    def draw(self, rng: np.random.Generator, job: Job | None = None) -> int:
        return self.value

    def upper_bound(self) -> int | None:
        return self.value

    def sampler(self, rng: np.random.Generator) -> Callable[[], int]:
        value = self.value
        return lambda: value

    @property
    def const(self) -> int | None:
        return self.value


class Uniform(Distribution):
    """Uniform integer nanoseconds on ``[low, high]``."""

    dist: Literal["uniform"] = "uniform"
    low: Time
    high: Time

    @model_validator(mode="after")
    def _order(self) -> Uniform:
        if self.low > self.high:
            raise ValueError("low must not exceed high")
        return self

    def draw(self, rng: np.random.Generator, job: Job | None = None) -> int:
        return int(rng.integers(self.low, self.high + 1))

    def upper_bound(self) -> int | None:
        return self.high

    def sampler(self, rng: np.random.Generator) -> Callable[[], int]:
        lo, hi = self.low, self.high
        if lo == hi:  # integers(lo, lo + 1) takes nothing from the stream either
            return lambda: lo
        integers = rng.integers
        return lambda: int(integers(lo, hi + 1))


class Normal(Distribution):
    """Normal with ``mean`` and ``std``, clipped to ``[min, max]`` (no upper clip without ``max``)."""

    dist: Literal["normal"] = "normal"
    mean: Time
    std: Time
    min: Time = 0
    max: Time | None = None

    @model_validator(mode="after")
    def _order(self) -> Normal:
        if self.max is not None and self.max < self.min:
            raise ValueError("max must not be below min")
        return self

    def draw(self, rng: np.random.Generator, job: Job | None = None) -> int:
        x = self.mean + self.std * float(rng.standard_normal())
        if x < self.min:
            x = self.min
        if self.max is not None and x > self.max:
            x = self.max
        return int(round(x))

    def upper_bound(self) -> int | None:
        return self.max


class Exponential(Distribution):
    """``shift`` plus an exponential variable of mean ``mean`` (unbounded: the analysis gives no bound with it)."""

    dist: Literal["exponential"] = "exponential"
    mean: Duration
    shift: Time = 0

    def draw(self, rng: np.random.Generator, job: Job | None = None) -> int:
        return self.shift + int(round(float(rng.exponential(float(self.mean)))))

    def sampler(self, rng: np.random.Generator) -> Callable[[], int]:
        mean, shift = float(self.mean), int(self.shift)
        expo = rng.exponential
        return lambda: shift + int(round(expo(mean)))


class ShiftedGamma(Distribution):
    """``shift`` plus a gamma variable of ``shape`` and ``scale`` (mean ``shape * scale``; unbounded)."""

    dist: Literal["shifted_gamma", "gamma"] = "shifted_gamma"
    shape: float = Field(gt=0)
    scale: Duration
    shift: Time = 0

    def draw(self, rng: np.random.Generator, job: Job | None = None) -> int:
        return self.shift + int(round(rng.gamma(float(self.shape), float(self.scale))))

    def sampler(self, rng: np.random.Generator) -> Callable[[], int]:
        shape, scale, shift = float(self.shape), float(self.scale), int(self.shift)
        gamma = rng.gamma
        return lambda: shift + int(round(gamma(shape, scale)))


class Empirical(Distribution):
    """Resampled (with replacement, each equally likely) from measured times: inline ``values`` or a CSV ``file``.

    ``column`` names the CSV column (a header name, or an index when the file has no header); ``unit`` is the
    unit of the numbers in the file (default seconds). The file is read when first drawn from.
    """

    dist: Literal["empirical"] = "empirical"
    values: list[Time] | None = None
    file: str | None = None
    column: str | int = 0
    unit: Literal["ns", "us", "ms", "s"] = "s"

    _table: list[int] | None = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _one_source(self) -> Empirical:
        if (self.values is None) == (self.file is None):
            raise ValueError("give exactly one of 'values' (a list of times) or 'file' (a CSV of delays)")
        if self.values is not None and not self.values:
            raise ValueError("'values' is empty; give at least one time")
        return self

    @model_serializer(mode="wrap")
    def _values_only(self, handler: Any) -> Any:
        data = handler(self)
        if isinstance(data, dict) and data.get("file") is None:  # inline values: the file's keys say nothing
            for key in ("file", "column", "unit"):
                data.pop(key, None)
        return data

    def table(self) -> list[int]:
        """The times in ns (read from the file the first time).

        Raises
        ------
        ConfigError
            From :func:`load_delays_csv`.
        """
        if self._table is None:
            self._table = ([int(v) for v in self.values] if self.values is not None
                           else load_delays_csv(self.file or "", self.column, self.unit).tolist())
        return self._table

    def draw(self, rng: np.random.Generator, job: Job | None = None) -> int:
        table = self.table()
        return int(table[int(rng.integers(0, len(table)))])

    def upper_bound(self) -> int | None:
        return max(self.table())

    def sampler(self, rng: np.random.Generator) -> Callable[[], int]:
        table = self.table()
        n = len(table)
        integers = rng.integers
        return lambda: table[int(integers(n))]


class Function(Distribution):
    """A data-dependent time: ``fn(job) -> ns`` at each draw (Python only; no upper bound)."""

    dist: Literal["function"] = "function"
    fn: Callable[[Any], Any]

    def draw(self, rng: np.random.Generator, job: Job | None = None) -> int:
        ns = self.fn(job)
        try:
            out = int(round(ns))
        except (TypeError, ValueError):
            raise SimulationError(f"execution-time function returned {ns!r}; it must return nanoseconds") from None
        if out < 0:
            raise SimulationError(f"execution-time function returned a negative time ({out} ns)")
        return out


def shorthand(value: Any) -> Any:
    """A bare time (``"1 ms"``) as ``{dist: constant, value: ...}``; anything else unchanged."""
    if isinstance(value, (str, int, float)) and not isinstance(value, bool):
        return {"dist": "constant", "value": value}
    return value


def dist_tag(value: Any) -> str | None:
    """The member of :data:`DistributionSpec` for ``value`` (None: a bad or missing ``dist``, reported as a
    ``time_distribution`` error with the known names by :mod:`netsim.scenario.messages`)."""
    dist = value.get("dist") if isinstance(value, dict) else getattr(value, "dist", None)
    if dist == "gamma":
        dist = "shifted_gamma"
    return f"{TAG_MARK}{dist}" if dist in DISTS else None


#: A random time as a scenario writes it: a time (constant) or ``{dist: ...}`` (see the module notes). The members
#: are spelt out here (not built from a tuple) so that the type checker reads the alias as a union of the classes.
DistributionSpec = Annotated[
    Union[
        Annotated[Constant, Tag(f"{TAG_MARK}constant")],
        Annotated[Uniform, Tag(f"{TAG_MARK}uniform")],
        Annotated[Normal, Tag(f"{TAG_MARK}normal")],
        Annotated[Exponential, Tag(f"{TAG_MARK}exponential")],
        Annotated[ShiftedGamma, Tag(f"{TAG_MARK}shifted_gamma")],
        Annotated[Empirical, Tag(f"{TAG_MARK}empirical")],
    ],
    Discriminator(dist_tag, custom_error_type="time_distribution", custom_error_message="bad time distribution"),
    BeforeValidator(shorthand),
]

#: The members of the family that YAML can name, each under its tag (the union of :data:`DistributionSpec`).
MEMBERS: tuple[Any, ...] = get_args(get_args(DistributionSpec)[0])

_ADAPTER: TypeAdapter[Any] = TypeAdapter(DistributionSpec)


def _first_error(exc: ValidationError, spec: Any) -> str:
    """One line for the first error of a :meth:`Distribution.from_spec` validation (its key, its fix)."""
    errors = exc.errors()
    err = next((e for e in errors if e["type"] == "extra_forbidden"), errors[0])  # a misspelt key explains the rest
    loc = [str(p) for p in err.get("loc", ()) if not str(p).startswith(TAG_MARK)]
    dist = spec.get("dist") if isinstance(spec, dict) else "constant"
    kind = err["type"]
    if kind == "missing":
        return f"execution time dist '{dist}' needs '{loc[-1]}'"
    if kind == "extra_forbidden":
        allowed = [k for k in _member(dist).model_fields if k != "dist"]
        close = difflib.get_close_matches(loc[-1], allowed, n=1)
        hint = f"; did you mean '{close[0]}'?" if close else f" (allowed: {', '.join(allowed)})"
        return f"execution time dist '{dist}' has no key '{loc[-1]}'{hint}"
    msg = str(err.get("msg", "")).removeprefix("Value error, ")
    if msg == "low must not exceed high":
        msg = "needs low <= high"
    where = f"'{loc[-1]}'" if loc else ""
    return f"execution time {where}: {msg}".replace("time : ", "time: ")


def _member(dist: Any) -> type[Distribution]:
    """The class of the member named ``dist`` (:class:`Constant` for an unknown name)."""
    classes: dict[str, type[Distribution]] = {
        "constant": Constant, "uniform": Uniform, "normal": Normal, "exponential": Exponential,
        "shifted_gamma": ShiftedGamma, "gamma": ShiftedGamma, "empirical": Empirical}
    return classes.get(dist, Constant)


def load_delays_csv(path: str | Path, column: str | int = 0, unit: str = "s") -> np.ndarray:
    """Read measured times from a CSV file into integer nanoseconds.

    Raises
    ------
    ConfigError
        If the file is missing, the column unknown, a value not a number or negative, or no value found.
    """
    p = Path(path)
    if not p.is_file():
        raise ConfigError(f"times file '{p}' does not exist; give a CSV of measured times "
                          "(delays, execution times, gaps)")
    with p.open(newline="") as fh:
        rows = [row for row in csv.reader(fh) if row and any(c.strip() for c in row)]
    if not rows:
        raise ConfigError(f"times file '{p}' is empty")
    header = rows[0]
    try:
        [float(c) for c in header if c.strip()]
        has_header = False
    except ValueError:
        has_header = True
    if isinstance(column, str):
        if not has_header or column not in [h.strip() for h in header]:
            known = ", ".join(h.strip() for h in header) if has_header else "no header row"
            raise ConfigError(f"times file '{p}' has no column '{column}' ({known})")
        idx = [h.strip() for h in header].index(column)
    else:
        idx = int(column)
    body = rows[1:] if has_header else rows
    scale = UNITS[unit]
    out = []
    for lineno, row in enumerate(body, start=2 if has_header else 1):
        if idx >= len(row):
            raise ConfigError(f"times file '{p}' line {lineno} has no column {idx}")
        try:
            v = float(row[idx])
        except ValueError:
            raise ConfigError(f"times file '{p}' line {lineno}: {row[idx]!r} is not a number") from None
        if not np.isfinite(v) or v < 0:
            raise ConfigError(f"times file '{p}' line {lineno}: time {v} must be finite and >= 0")
        out.append(int(round(v * scale)))
    if not out:
        raise ConfigError(f"times file '{p}' holds no times")
    return np.asarray(out, dtype=np.int64)
