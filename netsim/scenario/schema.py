"""The scenario schema: pydantic models of a netsim YAML scenario.

A scenario is a frozen, validated description (the SimSo split: static description here, runtime objects
in :mod:`netsim.build.builder`). This module is pure data: it imports no loader and no checker (they import
it); :func:`netsim.scenario.load_scenario` fills what only it knows (validated plugin parameters, the raw data,
the baseline scenario) into private attributes.

Why this module is long: it is the whole scenario format in one place, one model per YAML section in the order
a scenario file is written, so that it reads top to bottom like the file it describes. Every model forbids unknown keys; every time field accepts ``"1.5 ms"``
style text (a bare number other than 0 is refused: "add a unit, e.g. '5 ms'") and holds **integer nanoseconds**. Plugin parameters (plant model,
programs, networks, signals, metrics) are kept raw here and validated against the plugin's own ``Params``
model by :mod:`netsim.scenario.validate`; after :func:`netsim.scenario.load_scenario` the validated
``Params`` instance of each plugin is available from ``spec.validated_params()``.

Public classes and their fields (times in ns)
---------------------------------------------
``Scenario``
    ``name`` (at most ``MAX_NAME_LENGTH`` characters), ``description``, ``plugins`` (Python files, relative to
    the scenario file, that register plugins: run only when the user allows it, see :mod:`netsim.trust`),
    ``seed, duration, plant: PlantSpec | None, io: dict[str, IOChannel],
    signals: dict[str, SignalSpec], nodes: dict[str, NodeSpec], networks: dict[str, NetworkSpec],
    record: list[str] | None, metrics: list[MetricSpec], baseline: BaselineSpec | None,
    output: OutputSpec``; methods ``resolved_dict()``, ``node_networks(node)``, ``baseline_scenario()`` (the
    baseline the loader validated with the scenario);
    property ``source`` (the file it came from, or None).
``PlantSpec``
    ``model, params, x0, disturbances (plant input -> signal name), record_grid, process_noise``; or
    ``type`` (e.g. ``ss``, ``tf``: :mod:`netsim.plant.described`) with the model's parameters inline, read as
    ``model`` and ``params``.
``AdcChannel`` / ``DacChannel`` / ``EncoderChannel`` (the ``IOChannel`` union, discriminated by ``type``)
    adc: ``output, noise_std, quant_step, saturation``; dac: ``input, saturation, resolution``;
    encoder: ``output, step, tick, mode``; each an optional ``unit`` (text, for figure axes).
``SignalSpec``
    ``type`` and ``params`` (the other keys of the YAML mapping).
``NodeSpec``
    ``policy, context_switch, tasks: list[TaskSpec], handlers: list[HandlerSpec], energy`` (CPU and radio power, battery:
    :class:`~netsim.energy.params.EnergyModel`, or None).
``TaskSpec``
    ``name, program, params, period, offset, deadline (default: period), priority, execution, wcet,
    release ("periodic" | "aperiodic" | "sporadic" | "on_message:<net>"; default periodic when a period is given),
    preemptible, wcet_handler, deadline_handler, release_jitter, min_interarrival, extra_interarrival,
    abort_on_miss``; properties ``release_kind``, ``release_network``;
    method ``execution_time()``. A program that sends on ``params.network`` names the receiver in
    ``params.to``: a node, or ``all`` to broadcast to every other node on that network (netsim's programs
    refuse a missing ``to``; it used to broadcast silently).
``HandlerSpec``
    ``name, program, params, priority, latency, execution, trigger: HandlerTrigger | None``.
``HandlerTrigger``
    exactly one of ``timer: TimerTrigger(period, start)``, ``on_message: str``,
    ``external: ExternalTrigger(min_interarrival)``; property ``kind``.
``Execution``
    an execution time: an ``int`` (constant ns) or a member of :mod:`netsim.distributions` (``dist`` =
    constant | uniform | normal | exponential | shifted_gamma | empirical).
``NetworkSpec``
    ``type, nodes`` and ``params`` (the other keys of the YAML mapping; ``validated_params()`` includes
    ``nodes``).
``MetricSpec``
    ``type, params``.
``BaselineSpec``
    ``overrides: dict[str, Any]`` (dotted path -> value).
``OutputSpec``
    ``dir`` (relative to ``reports/``, cannot leave it), ``plot``, and the traces a run keeps: ``jobs``,
    ``messages`` (``full`` | ``summary`` | ``off``), ``schedule`` (``on`` | ``off``).

Every plugin spec (``PlantSpec``, ``TaskSpec``, ``HandlerSpec``, ``NetworkSpec``, ``SignalSpec``,
``MetricSpec``) has ``plugin()`` (the registered object) and ``validated_params()`` (its ``Params`` model
instance, or the raw dict when the plugin declares no ``Params``).
"""

from __future__ import annotations

import math
import re
from typing import Annotated, Any, ClassVar, Literal, Union

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    PrivateAttr,
    StringConstraints,
    Tag,
    ValidationError,
    model_serializer,
    model_validator,
)

from netsim.energy.params import EnergyModel
from netsim.scenario.paths import format_path, parse_path, plain_copy
from netsim.scenario.problems import Problem, ScenarioError
from netsim.scenario.schema_integrator import IntegratorSpec
from netsim.scenario.schema_servers import ServerDecl, TimetableSpec
from netsim.scenario.schema_sync import SyncSpec
from netsim.scenario.schema_verdict import VerdictSpec
from netsim.scenario.schema_task import without_unused_arrivals
from netsim.distributions import DISTS, MEMBERS as DIST_MEMBERS, Distribution, dist_tag
from netsim.kernel.task import HandlerSpec as KernelHandlerSpec
from netsim.kernel.task import TaskSpec as KernelTaskSpec
from netsim.units import Duration, QuietDefaultsModel, StrictModel, Time

__all__ = [
    "NAME_PATTERN",
    "TAG_MARK",
    "EXEC_DISTS",
    "IO_TYPES",
    "SpecModel",
    "PluginSpec",
    "Execution",
    "AdcChannel",
    "DacChannel",
    "EncoderChannel",
    "IOChannel",
    "PlantSpec",
    "SignalSpec",
    "TaskSpec",
    "TimerTrigger",
    "ExternalTrigger",
    "HandlerTrigger",
    "HandlerSpec",
    "NodeSpec",
    "NetworkSpec",
    "MetricSpec",
    "BaselineSpec",
    "OutputSpec",
    "Scenario",
]

#: Names of scenarios, nodes, tasks, networks, channels and signals.
NAME_PATTERN = r"^[A-Za-z0-9_-]+$"
#: Prefix of the internal tags of discriminated unions (dropped from error paths).
TAG_MARK = "§"
EXEC_DISTS = DISTS
IO_TYPES = ("adc", "dac", "encoder")

Name = Annotated[str, StringConstraints(pattern=NAME_PATTERN)]


# --------------------------------------------------------------------------------------------- helpers
def _plant_port(value: Any) -> int | str:
    """A plant input/output: index ``0, 1, ...`` or a signal name (digit-only text becomes an index)."""
    if isinstance(value, bool):
        raise ValueError(f"expected a plant port index (0, 1, ...) or name, got {value!r}")
    if isinstance(value, int):
        if value < 0:
            raise ValueError(f"plant port index must be >= 0, got {value}")
        return value
    if isinstance(value, str) and value.strip():
        text = value.strip()
        return int(text) if text.isdigit() else text
    raise ValueError(f"expected a plant port index (0, 1, ...) or name, got {value!r}")


PlantPort = Annotated[Union[int, str], BeforeValidator(_plant_port)]


def _range(value: Any) -> Any:  # before the tuple[float, float] check: floats, or the value limits.py refuses
    if isinstance(value, (list, tuple)) and len(value) == 2:
        lo, hi = value
        if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (lo, hi)):
            if not all(_is_number(v) for v in (lo, hi)):
                return value  # NaN, infinity or an integer too large for a float: limits.py refuses it at its path
            if not lo < hi:
                raise ValueError(f"expected [low, high] with low < high, got [{lo}, {hi}]")
            return float(lo), float(hi)
    raise ValueError(f"expected [low, high] (two numbers), got {value!r}")


Range = Annotated[tuple[float, float], BeforeValidator(_range)]


def _is_number(v: Any) -> bool:
    if not isinstance(v, (int, float)) or isinstance(v, bool):
        return False
    try:
        return math.isfinite(float(v))
    except OverflowError:  # an integer too large for a float: not usable (limits.py says so at its path)
        return False


def _noise(value: Any) -> Any:
    """Process noise: a number (same intensity on every state), a list (per state) or a matrix; or random
    disturbances ``{states|inputs: [...], sigma: ..., sample: ...}`` (or a list of them, :mod:`netsim.plant.noise`)."""
    if value is None:
        return None
    if isinstance(value, dict) or (isinstance(value, (list, tuple)) and value and all(isinstance(v, dict) for v in value)):
        from netsim.plant.noise import normalized_entries

        return normalized_entries(value)
    if _is_number(value):
        if value < 0:
            raise ValueError(f"noise intensity must be >= 0, got {value}")
        return float(value)
    if isinstance(value, (list, tuple)) and value:
        if all(_is_number(v) for v in value):
            return [float(v) for v in value]
        if all(isinstance(row, (list, tuple)) and row and all(_is_number(v) for v in row) for row in value):
            if len({len(row) for row in value}) != 1:
                raise ValueError("noise matrix rows must all have the same length")
            return [[float(v) for v in row] for row in value]
    raise ValueError(f"expected a number, a list of numbers or a matrix (list of lists), got {value!r}")


ProcessNoise = Annotated[Any, BeforeValidator(_noise)]



# --------------------------------------------------------------------------------------------- bases
class SpecModel(StrictModel):
    """Base of every scenario model: unknown keys are errors, instances are read-only."""

    model_config = ConfigDict(extra="forbid", frozen=True, validate_assignment=False)


class PluginSpec(SpecModel):
    """A scenario entry that names a registered plugin and carries parameters for it."""

    #: Registry kind of the plugin this spec names.
    plugin_kind: ClassVar[str] = ""
    _validated: Any = PrivateAttr(default=None)

    def plugin_name(self) -> str:
        """The registered name (or ``module:attr``) of the plugin: the spec's ``type`` unless overridden."""
        return str(getattr(self, "type"))

    def raw_params(self) -> dict[str, Any]:
        """The parameters as written in the scenario (what the plugin's ``Params`` validates)."""
        return dict(getattr(self, "params", {}) or {})

    def plugin(self) -> Any:
        """The registered object (class or function) this spec names.

        Raises
        ------
        ConfigError
            When the name is not registered (with a "did you mean").
        """
        from netsim import registry

        return registry.lookup(self.plugin_kind, self.plugin_name())

    def validated_params(self) -> Any:
        """The plugin's ``Params`` instance for these parameters (raw dict if the plugin has no ``Params``).

        Cached; filled by :func:`netsim.scenario.load_scenario`. Validates now when the scenario was built
        without the loader (``Scenario.model_validate(raw)``).

        Raises
        ------
        ScenarioError
            When the parameters do not fit the plugin's ``Params`` (one problem per error, paths relative to
            the parameters; the loader gives the full messages with YAML paths and lines).
        """
        if self._validated is None:
            self._validated = _validate_params(self.plugin(), self.raw_params())
        return self._validated

    def attach_validated(self, params: Any) -> None:
        """Store the validated parameters (used by the loader)."""
        self._validated = params


def _validate_params(plugin: Any, raw: dict[str, Any]) -> Any:
    """``raw`` validated by ``plugin.Params`` (a pydantic model); ``dict(raw)`` when the plugin declares none."""
    cls = getattr(plugin, "Params", None)
    if not (isinstance(cls, type) and issubclass(cls, BaseModel)):
        return dict(raw)
    try:
        return cls.model_validate(raw)
    except ValidationError as exc:
        problems = [Problem(format_path([p for p in err["loc"] if not str(p).startswith(TAG_MARK)]),
                            str(err["msg"]).removeprefix("Value error, ")) for err in exc.errors()]
        raise ScenarioError(problems) from None


# --------------------------------------------------------------------------------------------- execution
def _exec_tag(value: Any) -> str | None:
    if isinstance(value, (str, int, float)) and not isinstance(value, bool):
        return f"{TAG_MARK}const"
    return dist_tag(value)


#: An execution time: constant ns (from ``"0.5 ms"``; dumped as the time it is) or a member of netsim's one family
#: of random times (:mod:`netsim.distributions`).
Execution = Annotated[
    Union[(Annotated[Time, Tag(f"{TAG_MARK}const")], *DIST_MEMBERS)],  # type: ignore[valid-type]
    Discriminator(_exec_tag, custom_error_type="execution_spec", custom_error_message="bad execution time"),
]


def _exec_time(execution: Any) -> Distribution | None:
    """The execution time as the distribution the programs draw from (a constant for a bare time), or None."""
    if execution is None or isinstance(execution, Distribution):
        return execution
    return Distribution.constant(execution)


# --------------------------------------------------------------------------------------------- io
class _Channel(SpecModel, QuietDefaultsModel):
    """An io channel: ``unit`` (optional text, e.g. ``rad``, ``V``) names its value's unit for figure axes; left
    out of the resolved scenario while unset, so a scenario without units resolves (and hashes) as before."""

    _QUIET_DEFAULTS: ClassVar[dict[str, Any]] = {"unit": None}

    unit: str | None = Field(default=None, min_length=1, max_length=40)


class AdcChannel(_Channel):
    """Analog input: samples plant output ``output`` (index or name), with noise, quantization, saturation."""

    type: Literal["adc"]
    output: PlantPort = 0
    noise_std: float = Field(default=0.0, ge=0)
    quant_step: float | None = Field(default=None, gt=0)
    saturation: Range | None = None


class DacChannel(_Channel):
    """Analog output: sets plant input ``input`` (zero-order hold), with saturation and resolution."""

    type: Literal["dac"]
    input: PlantPort = 0
    saturation: Range | None = None
    resolution: float | None = Field(default=None, gt=0)


class EncoderChannel(_Channel):
    """Incremental encoder on plant output ``output``: quantization ``step``, read by an ISR every ``tick``."""

    type: Literal["encoder"]
    output: PlantPort = 0
    step: float = Field(gt=0)
    tick: Duration
    mode: Literal["exact", "polling"] = "exact"


def _io_tag(value: Any) -> str | None:
    kind = value.get("type") if isinstance(value, dict) else getattr(value, "type", None)
    return f"{TAG_MARK}{kind}" if kind in IO_TYPES else None


#: One named I/O channel, discriminated by ``type``.
IOChannel = Annotated[
    Union[
        Annotated[AdcChannel, Tag(f"{TAG_MARK}adc")],
        Annotated[DacChannel, Tag(f"{TAG_MARK}dac")],
        Annotated[EncoderChannel, Tag(f"{TAG_MARK}encoder")],
    ],
    Discriminator(_io_tag, custom_error_type="io_type", custom_error_message="bad io channel type"),
]


# --------------------------------------------------------------------------------------------- plant, signals
class PlantSpec(PluginSpec):
    """The plant: a registered model (kind ``plant``) or ``module:attr`` factory with its parameters."""

    plugin_kind: ClassVar[str] = "plant"
    model: str = Field(min_length=1)
    params: dict[str, Any] = Field(default_factory=dict)
    x0: list[float] | None = None
    disturbances: dict[PlantPort, Name] = Field(default_factory=dict)
    record_grid: Duration | None = None
    process_noise: ProcessNoise = Field(None, description=(
        "LTI/discrete plants: intensity of white noise on the state (number, vector or matrix). Any plant: "
        "entries {inputs: [...], sigma, sample} (white noise held per sample on inputs) or {states: [...], sigma, "
        "sample} (random-walk increments sigma*sqrt(sample)*N(0,1) at each sample; model: rate holds sigma*N(0,1) "
        "on dx/dt instead), one or a list (netsim.plant.noise)"))
    integrator: IntegratorSpec | None = Field(None, description=(
        "nonlinear plants: {method: solve_ivp, rtol, atol} (default, scipy per segment) or {method: rk4, "
        "max_step: 1 ms} (fixed-step Runge-Kutta, faster; netsim.plant.integrator)"))

    @model_validator(mode="before")
    @classmethod
    def _described(cls, data: Any) -> Any:
        """``{type: ss|tf|NAME, ...}``: the plant named by ``type`` with its parameters inline (as networks and
        signals write theirs); the plant section's own keys (``x0``, ``disturbances`` ...) stay where they are."""
        if not isinstance(data, dict) or "type" not in data:
            return data
        if "model" in data:
            raise ValueError("give either 'type' (a described plant, e.g. 'type: ss') or 'model', not both")
        data = {("model" if k == "type" else k): v for k, v in data.items()}
        return _gather_params(data, _PLANT_KEYS)

    def plugin_name(self) -> str:
        return self.model


#: The plant section's own keys; with ``type:`` every other key is a parameter of the plant model.
_PLANT_KEYS = ("model", "x0", "disturbances", "record_grid", "process_noise", "integrator")


def _gather_params(data: Any, fixed: tuple[str, ...]) -> Any:
    """Move every key not in ``fixed`` into ``params`` (inline parameters, as scenarios write them)."""
    if not isinstance(data, dict):
        return data
    out = {k: v for k, v in data.items() if k in fixed}
    params: dict[str, Any] = {}
    explicit = data.get("params")
    if isinstance(explicit, dict):
        params.update(explicit)
    elif "params" in data:
        params["params"] = explicit
    params.update({k: v for k, v in data.items() if k not in fixed and k != "params"})
    out["params"] = params
    return out


class SignalSpec(PluginSpec):
    """A reference or disturbance signal: ``{type: square, amplitude: 1, period: 2 s}``.

    The keys other than ``type`` are the signal's parameters (validated by the registered ``signal``).
    """

    plugin_kind: ClassVar[str] = "signal"
    type: str = Field(min_length=1)
    params: dict[str, Any] = Field(default_factory=dict)

    @model_validator(mode="before")
    @classmethod
    def _inline(cls, data: Any) -> Any:
        return _gather_params(data, ("type",))

    def plugin_name(self) -> str:
        return self.type


# --------------------------------------------------------------------------------------------- nodes
#: The order of a task's keys in a resolved scenario (as written before the kernel's TaskSpec became the YAML task).
_TASK_KEYS = ("name", "program", "params", "period", "offset", "deadline", "priority", "execution", "wcet", "release",
              "preemptible", "wcet_handler", "deadline_handler", "release_jitter", "min_interarrival",
              "extra_interarrival", "abort_on_miss", "set_period", "core", "server")


#: The order of a handler's keys in a resolved scenario.
_HANDLER_KEYS = ("name", "program", "params", "priority", "latency", "execution", "trigger")


class TaskSpec(PluginSpec, KernelTaskSpec):
    """A task on a node: the kernel's own description of a task (:class:`netsim.kernel.task.TaskSpec`: its
    scheduling fields, their units, defaults and release rules) with the program it runs and its execution time.

    Every task needs ``name`` and ``program``. What else each kind of release requires (the kernel's
    :meth:`~netsim.kernel.task.TaskSpec.checked`, run by validate, each with its path):

    - ``release: periodic`` (the default when ``period`` is given): ``period`` is required; ``offset``,
      ``deadline`` (default: the period) are optional.
    - ``release: aperiodic`` (the default without ``period``): no ``period``; released by program code.
    - ``release: on_message:<network>``: no ``period``; the node must be attached to ``<network>`` and has one
      receiver per network.
    - ``release: sporadic`` (the default with ``min_interarrival`` and no ``period``): the kernel releases it,
      arrivals ``min_interarrival`` plus a draw of ``extra_interarrival`` apart; the deadline defaults to
      ``min_interarrival``.
    - ``release_jitter`` (periodic and sporadic tasks): each job arrives a random time after its nominal
      release; ``abort_on_miss: true`` kills a job unfinished at its deadline
      (:mod:`netsim.scenario.schema_task`).
    - Under policy ``fp`` every task needs a ``priority``; a ``wcet_handler`` needs a ``wcet``.

    The kernel takes this model as it is (``Kernel.add_task``): a ``period`` is read once, by its ``Duration``
    type, and checked once per run.
    """

    plugin_kind: ClassVar[str] = "program"
    name: Name
    program: str = Field(min_length=1)
    params: dict[str, Any] = Field(default_factory=dict)
    execution: Execution | None = None
    priority: int | None = None  # YAML priorities are integers (Python may pass floats)
    wcet_handler: Name | None = None  # YAML names a handler (Python may pass a callable)
    deadline_handler: Name | None = None
    core: int | None = Field(None, ge=0, description="the core the task runs on (nodes.<n>.multicore: partitioned)")
    server: Name | None = Field(None, description="the node's CBS or TBS (nodes.<n>.servers) that serves the task")

    @model_serializer(mode="wrap")
    def _without_unused_arrivals(self, handler: Any) -> Any:
        data = handler(self)
        if isinstance(data, dict):
            data = {key: data[key] for key in _TASK_KEYS
                    if key in data and (key not in ("core", "server") or data[key] is not None)}
        return without_unused_arrivals(data)  # resolved scenarios that use none stay as they were

    def plugin_name(self) -> str:
        return self.program

    def execution_time(self) -> Distribution | None:
        """``execution`` as the distribution the task's program draws from (None when not given)."""
        return _exec_time(self.execution)


class TimerTrigger(SpecModel):
    """Timer interrupt: periodic with ``period`` from ``start``, or one-shot at ``start`` without a period."""

    period: Duration | None = None
    start: Time = 0


class ExternalTrigger(SpecModel):
    """External interrupt raised by program code (``kernel.trigger``), at most once per ``min_interarrival``."""

    min_interarrival: Time = 0


class PeriodicLoadTrigger(SpecModel):
    """A fast periodic interrupt accounted in closed form (``Kernel.create_periodic_load``).

    Every tick ``start + k * period`` takes the handler's ``latency + execution`` of CPU from everything else on
    the node, exactly as a timer-driven handler would, without one simulated invocation per tick. The handler's
    code runs only when something invokes it (e.g. an exact-mode encoder at the ticks that see an edge). Its
    execution time must be constant and shorter than the period.
    """

    period: Duration
    start: Time = 0


_TRIGGER_KINDS = ("timer", "on_message", "external", "periodic_load")


class HandlerTrigger(SpecModel):
    """What raises an interrupt handler: exactly one of ``timer``, ``on_message`` (a network), ``external``,
    ``periodic_load``."""

    timer: TimerTrigger | None = None
    on_message: Name | None = None
    external: ExternalTrigger | None = None
    periodic_load: PeriodicLoadTrigger | None = None

    @model_validator(mode="after")
    def _exactly_one(self) -> HandlerTrigger:
        given = [k for k in _TRIGGER_KINDS if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(
                "give exactly one of 'timer', 'on_message', 'external' or 'periodic_load'"
                + (f" (got {', '.join(given)})" if given else "")
            )
        return self

    @model_serializer(mode="wrap")
    def _only_given(self, handler: Any) -> Any:
        data = handler(self)
        return {k: v for k, v in data.items() if v is not None} if isinstance(data, dict) else data

    @property
    def kind(self) -> str:
        """``"timer"``, ``"on_message"``, ``"external"`` or ``"periodic_load"``."""
        for k in _TRIGGER_KINDS:
            if getattr(self, k) is not None:
                return k
        raise AssertionError("unreachable: validated trigger has one kind")


class HandlerSpec(PluginSpec, KernelHandlerSpec):
    """An interrupt handler on a node: beats every task; lower ``priority`` value is more urgent.

    The kernel's own description of a handler (:class:`netsim.kernel.task.HandlerSpec`: ``priority``,
    ``latency``, their units and defaults) with the program it runs, its execution time and its trigger; the
    kernel takes it as it is (``Kernel.add_handler``).
    """

    plugin_kind: ClassVar[str] = "program"
    name: Name
    program: str = Field(min_length=1)
    params: dict[str, Any] = Field(default_factory=dict)
    priority: int = 0  # YAML priorities are integers (Python may pass floats)
    execution: Execution | None = None
    trigger: HandlerTrigger | None = None

    @model_serializer(mode="wrap")
    def _in_file_order(self, handler: Any) -> Any:
        data = handler(self)
        return {key: data[key] for key in _HANDLER_KEYS if key in data} if isinstance(data, dict) else data

    def plugin_name(self) -> str:
        return self.program

    def execution_time(self) -> Distribution | None:
        """``execution`` as the distribution the handler's program draws from (None when not given)."""
        return _exec_time(self.execution)


class NodeSpec(SpecModel):
    """A node: one real-time kernel with its scheduling policy, tasks and interrupt handlers."""

    policy: str = Field(default="fp", min_length=1)
    context_switch: Time = 0
    tasks: list[TaskSpec] = Field(default_factory=list)
    handlers: list[HandlerSpec] = Field(default_factory=list)
    energy: EnergyModel | None = None  # CPU and radio power, battery (issue 20): netsim.energy
    # several cores and speed scaling (issue 30): netsim.kernel.multicore, netsim.kernel.speed, netsim.kernel.cores
    cores: int | None = Field(None, ge=1, le=1024, description="identical cores of the node (default 1)")
    multicore: Literal["global", "partitioned"] | None = Field(None, description=(
        "with cores >= 2: global (default: one ready queue, the m most urgent jobs run) or partitioned (each task "
        "on its tasks[].core)"))
    migration_cost: Time | None = Field(None, description="kernel time a task job pays when it resumes on another core")
    speed: float | None = Field(None, gt=0, le=1, description=(
        "initial CPU speed, a fraction of the nominal clock (execution times are given at 1); enables set_speed"))
    speed_levels: list[Annotated[float, Field(gt=0, le=1)]] | None = Field(None, min_length=1, description=(
        "the speeds set_speed accepts (default: any in (0, 1])"))
    sync: SyncSpec | None = None  # mailboxes, semaphores, events, monitors (issue 20): netsim.scenario.schema_sync
    servers: list[ServerDecl] = Field(default_factory=list)  # CBS/TBS (issue 30): netsim.scenario.schema_servers
    timetable: TimetableSpec | None = None  # a time-triggered schedule table for policy tt (issue 30)

    def task(self, name: str) -> TaskSpec:
        """The task called ``name`` (KeyError if none)."""
        for t in self.tasks:
            if t.name == name:
                return t
        raise KeyError(name)

    def handler(self, name: str) -> HandlerSpec:
        """The handler called ``name`` (KeyError if none)."""
        for h in self.handlers:
            if h.name == name:
                return h
        raise KeyError(name)


# --------------------------------------------------------------------------------------------- networks etc.
class NetworkSpec(PluginSpec):
    """A network: its registered ``type``, the ``nodes`` attached, and the type's other parameters inline."""

    plugin_kind: ClassVar[str] = "network"
    type: str = Field(min_length=1)
    nodes: list[Name] = Field(default_factory=list)
    params: dict[str, Any] = Field(default_factory=dict)

    @model_validator(mode="before")
    @classmethod
    def _inline(cls, data: Any) -> Any:
        return _gather_params(data, ("type", "nodes"))

    def plugin_name(self) -> str:
        return self.type

    def raw_params(self) -> dict[str, Any]:
        return {"nodes": list(self.nodes), **self.params}


class MetricSpec(PluginSpec):
    """A metric computed after the run: ``{type: control_error, params: {reference: r, output: y}}``."""

    plugin_kind: ClassVar[str] = "metric"
    type: str = Field(min_length=1)
    params: dict[str, Any] = Field(default_factory=dict)

    def plugin_name(self) -> str:
        return self.type


class BaselineSpec(SpecModel):
    """A baseline run of the same scenario with ``overrides`` (dotted path -> value) applied."""

    overrides: dict[str, Any] = Field(default_factory=dict)


#: Longest scenario name (it becomes a folder name: ``reports/<name>/``).
MAX_NAME_LENGTH = 100


def _on_off(value: Any) -> Any:
    """``output.schedule``: ``on``/``off``, also as a YAML boolean (``true``/``false``)."""
    if value is True:
        return "on"
    if value is False:
        return "off"
    return value


def _output_dir(value: Any) -> Any:
    """``output.dir``: a relative folder below the output root (``reports/``) that cannot leave it."""
    if not isinstance(value, str):
        return value
    fix = "write a relative folder such as 'my_runs/case1' (it goes under reports/), or choose any folder with --out"
    if not value.strip():
        raise ValueError(f"output.dir is empty; {fix}")
    if len(value) > 200:
        raise ValueError(f"output.dir is {len(value)} characters long (at most 200); {fix}")
    if "\x00" in value or "\\" in value or value.startswith(("/", "~")) or re.match(r"^[A-Za-z]:", value):
        raise ValueError(f"output.dir '{value[:60]}' is not a relative folder; a scenario cannot choose where "
                         f"its files go outside reports/: {fix}")
    if any(part == ".." for part in value.split("/")):
        raise ValueError(f"output.dir '{value[:60]}' leaves reports/ ('..'); {fix}")
    return value


class OutputSpec(SpecModel):
    """Where the run folder goes, whether to draw figures, and which traces a run keeps.

    ``dir`` is a folder relative to the output root ``reports/`` (no absolute path, no ``..``): a scenario
    file cannot choose where files are written outside it; the user does, with ``--out`` (or ``out=``).
    None: ``reports/<name>/<run-id>``.

    Traces (issue 19; :mod:`netsim.results.traces`): ``jobs`` and ``messages`` are ``full`` (one row per job,
    per message copy: ``jobs.csv``, ``messages.csv``), ``summary`` (per task, per network: count, outcomes,
    mean, max and percentiles of the response time or delay, kept online in flat memory: ``jobs_summary.csv``,
    ``messages_summary.csv``) or ``off``; ``schedule`` (``on``/``off``) keeps the kernels' schedule trace (the
    Gantt chart). ``et_control`` reads the message rows and needs ``full``; ``latency`` works in every mode
    (without the tables it is streamed while the run goes: :mod:`netsim.metrics.chain`).
    """

    dir: Annotated[str | None, BeforeValidator(_output_dir)] = None
    plot: bool = False
    jobs: Literal["full", "summary", "off"] = "full"
    messages: Literal["full", "summary", "off"] = "full"
    schedule: Annotated[Literal["on", "off"], BeforeValidator(_on_off)] = "on"

    #: The trace settings' defaults: left out of :meth:`Scenario.resolved_dict` when unchanged, so the resolved
    #: form (and the run folder's ``scenario.yaml``) of a scenario that does not set them stays as it was.
    TRACE_DEFAULTS: ClassVar[dict[str, str]] = {"jobs": "full", "messages": "full", "schedule": "on"}


# --------------------------------------------------------------------------------------------- scenario
class Scenario(SpecModel):
    """A complete, validated scenario (see the module docstring for every field)."""

    name: Annotated[str, StringConstraints(pattern=NAME_PATTERN, max_length=MAX_NAME_LENGTH)]
    description: str = ""
    plugins: list[str] = Field(default_factory=list)
    seed: int = Field(default=0, ge=0)
    duration: Duration
    plant: PlantSpec | None = None
    io: dict[Name, IOChannel] = Field(default_factory=dict)
    signals: dict[Name, SignalSpec] = Field(default_factory=dict)
    nodes: dict[Name, NodeSpec] = Field(default_factory=dict)
    networks: dict[Name, NetworkSpec] = Field(default_factory=dict)
    record: list[str] | None = None
    metrics: list[MetricSpec] = Field(default_factory=list)
    baseline: BaselineSpec | None = None
    output: OutputSpec = Field(default_factory=OutputSpec)
    verdict: VerdictSpec | None = None  # how the run is judged stable (netsim.scenario.schema_verdict); None: defaults

    _source: str | None = PrivateAttr(default=None)
    _raw: Any = PrivateAttr(default=None)
    _baseline: Any = PrivateAttr(default=None)
    _run_check: Any = PrivateAttr(default=None)  # loaded for a run: the build's checks (build.dry_run.RunCheck)

    @property
    def source(self) -> str | None:
        """The scenario file this came from (None for a dict)."""
        return self._source

    def node_networks(self, node: str) -> list[str]:
        """Names of the networks ``node`` is attached to, in file order."""
        return [name for name, net in self.networks.items() if node in net.nodes]

    def plugin_specs(self) -> list[tuple[str, PluginSpec]]:
        """Every plugin spec with the YAML path of its parameters' owner (``nodes.n.tasks[0]``, ...)."""
        out: list[tuple[str, PluginSpec]] = []
        if self.plant is not None:
            out.append(("plant", self.plant))
        out += [(f"signals.{n}", s) for n, s in self.signals.items()]
        for node_name, node in self.nodes.items():
            out += [(f"nodes.{node_name}.tasks[{i}]", t) for i, t in enumerate(node.tasks)]
            out += [(f"nodes.{node_name}.handlers[{i}]", h) for i, h in enumerate(node.handlers)]
        out += [(f"networks.{n}", s) for n, s in self.networks.items()]
        out += [(f"metrics[{i}]", m) for i, m in enumerate(self.metrics)]
        return out

    def resolved_dict(self) -> dict[str, Any]:
        """Plain YAML/JSON-ready data with every default filled in and times as text (``"10 ms"``).

        Plugin parameters appear with their plugin's defaults when they have been validated (always the case
        for a scenario from :func:`~netsim.scenario.load_scenario`). Network and signal parameters are written
        inline (``{type: can, nodes: [...], bitrate: ...}``), as in scenario files, so the result loads back
        into an equal scenario.
        """
        data = self.model_dump(mode="json")
        if not data.get("plugins"):
            data.pop("plugins", None)  # most scenarios have none: their resolved form (and hash) stays as it was
        for node in data.get("nodes", {}).values():  # a node without an energy model resolves as before (issue 20)
            if node.get("energy", 0) is None:
                del node["energy"]
            if node.get("sync", 0) is None:  # the same for the sync objects
                del node["sync"]
            if not node.get("servers", 1):  # and for servers and tables (issue 30)
                del node["servers"]
            if node.get("timetable", 0) is None:
                del node["timetable"]
            for key in ("cores", "multicore", "migration_cost", "speed", "speed_levels"):  # and the CPU (issue 30)
                if node.get(key, 0) is None:
                    del node[key]
        if isinstance(data.get("plant"), dict) and data["plant"].get("integrator", 0) is None:
            del data["plant"]["integrator"]  # no integrator chosen: resolved (and hashed) as before (issue 29)
        if data.get("verdict", 0) is None:  # no verdict: block: resolved (and hashed) as before (issue 26)
            del data["verdict"]
        for key, default in OutputSpec.TRACE_DEFAULTS.items():  # the same for the trace settings (issue 19)
            if data["output"].get(key) == default:
                data["output"].pop(key)
        for path, spec in self.plugin_specs():
            params = _params_json(spec)
            parts = parse_path(path)
            if parts[0] == "networks":
                params.pop("nodes", None)
                data["networks"][parts[1]] = {"type": spec.plugin_name(), "nodes": list(spec.nodes), **params}  # type: ignore[attr-defined]
            elif parts[0] == "signals":
                data["signals"][parts[1]] = {"type": spec.plugin_name(), **params}
            else:
                target: Any = data
                for part in parts:
                    target = target[part]
                target["params"] = params
        return data

    def baseline_scenario(self) -> Scenario | None:
        """The baseline scenario (this one with ``baseline.overrides`` applied and no baseline), or None.

        The loader validates it with the scenario (:func:`~netsim.scenario.load_scenario`), once.

        Raises
        ------
        ScenarioError
            For a scenario with a baseline that was not made by the loader (``Scenario.model_validate``).
        """
        if self.baseline is None:
            return None
        if self._baseline is None:
            raise ScenarioError([Problem("baseline", "the baseline is validated by the loader: load this scenario "
                                                     "with netsim.scenario.load_scenario to run its baseline")])
        return self._baseline


def _params_json(spec: PluginSpec) -> dict[str, Any]:
    """The parameters of ``spec`` as plain data: its validated ``Params`` (with defaults), else as written."""
    validated = spec._validated
    if isinstance(validated, BaseModel):
        try:
            return validated.model_dump(mode="json")
        except Exception:  # noqa: BLE001 - a Params model with values JSON cannot hold: keep what the user wrote
            pass
    elif isinstance(validated, dict):
        return plain_copy(validated)
    return plain_copy(spec.raw_params())
