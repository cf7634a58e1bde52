"""Checks beyond the base schema: plugin parameters and cross references.

These checks work on the **raw** scenario data (plain dicts from YAML) and skip anything malformed, so they
run even when the base schema found problems and ``netsim validate`` reports everything in one go.

What is checked
---------------
- Every plugin named in the scenario exists (plant ``model``, signal ``type``, task/handler ``program``,
  network ``type``, metric ``type``, node ``policy`` unless fp/rm/dm/edf), with a "did you mean"; its
  ``params`` fit the plugin's ``Params`` model (paths such as ``nodes.sensor.tasks[0].params.bits``).
- The limits of :mod:`netsim.scenario.limits`: finite numbers within 1e15, names of at most 100 characters, a
  non-empty ``nodes`` whose nodes each run something, unique task and handler names per node (the message names
  the first definition), and a warning when the run is expected to simulate very many events.
- ``wcet_handler``/``deadline_handler`` name handlers of the node.
- A network's ``nodes`` exist; ``release: on_message:<net>`` and ``trigger: {on_message: <net>}`` name a
  network the node is attached to.
- A periodic task has a period, an aperiodic or message-released task has none, a sporadic task has a
  ``min_interarrival`` (and only it): the kernel's release rules (:meth:`netsim.kernel.task.TaskSpec.checked`);
  under policy ``fp`` every task has a priority. A deadline longer than the period is allowed (TrueTime
  semantics: jobs continue and may queue up) but reported as a **warning**. These read each task's validated
  model (the scenario's, or the entry validated alone when the schema refused something else), never its raw
  times.
- Program parameter naming conventions: ``network``/``*_network`` (and ``networks``/``*_networks``) name a
  network the node is on; ``to`` names a node on that network, or ``all`` to broadcast (netsim's own programs
  refuse a missing ``to``); a source of interfering traffic (program attribute ``interference_source``) whose
  frames reach a node that consumes that network's messages is a **warning**; ``channel``/``*_channel``
  (and plurals) name an ``io`` channel; ``signal``, ``reference``, ``*_signal`` (and plurals) name a signal;
  ``tasks``/``*_tasks`` name periodic tasks of the program's node (e.g. a feedback scheduler's).
- I/O channel plant ports lie within the plant's inputs/outputs when the plant factory declares them
  (``ports(params) -> (input_names, output_names)``, or attributes ``input_names``/``output_names`` or
  ``n_inputs``/``n_outputs``); plant ``disturbances`` name plant inputs and scenario signals.
- A program's own ``scenario_warnings(raw_scenario, params) -> [(key, text)]`` (e.g. the 2WD cart filter whose
  sensor model differs from the plant's), reported as **warnings** at the task's ``params.<key>``.
- ``record`` entries are names; the runner warns (in ``meta.json``) about names nothing recorded.
- Metric parameters that name recorded signals (``reference``, ``output``, ``signal``, ``*_signal`` and the
  plurals ``signals``, ``outputs``, ``*_signals``) must be in the ``record:`` list when one is given (the
  metric reads them from the signals table after the run). A metric's ``chain`` (or ``*_chain``) lists
  ``node.task`` names of existing tasks or handlers.
- (The baseline, ``baseline.overrides`` applied, is validated by the loader like the scenario itself.)
- The kernel's own task checks (:meth:`netsim.kernel.task.TaskSpec.checked`, then the built-in policy's
  ``check``): e.g. ``rm``/``dm`` refuse a deadline longer than the period, a ``wcet_handler`` needs a ``wcet``.
- A ``module:attr`` plugin must accept the arguments build calls it with (:mod:`netsim.scenario.calls`); a
  registered plant that does not declare its ports is built (build's own ``make_plant``) for the io check.

A scenario that passes all of these then goes through build's kernel and network construction
(:mod:`netsim.build.dry_run`: the run's own build on a dry-run environment), so ``validate`` refuses what ``run``
would refuse while building.

Why this module is long: one checker walks the raw scenario once, section by section, and the cross references
it checks tie the sections together (a task's network and receiver, a metric's recorded signals and tasks, a
program's channels); split by section, each part would need the others' indexes.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any, Iterable

from pydantic import BaseModel, ValidationError

from netsim.errors import ConfigError
from netsim.scenario.limits import NAME_MAX, LineOf, limit_problems
from netsim.scenario.messages import problems_from_validation_error
from netsim.scenario.paths import PathPart, did_you_mean, format_path, parse_path
from netsim.scenario.problems import WARNING, Problem, ScenarioError
from netsim.scenario.schema_sync import sync_ref_problems
from netsim.kernel.policies import find_policy, is_builtin_policy, resolve_policy
from netsim.timebase import TimeParseError, format_time, parse_time

if TYPE_CHECKING:
    from netsim.scenario.schema import Scenario

__all__ = ["validate_params", "check_raw", "plugin_load_problems"]

log = logging.getLogger(__name__)

def plugin_load_problems(load_all: bool = False) -> list[Problem]:
    """The plugin modules that failed to import so far in this process, as warnings (``load_all``: import
    every plugin module first, as ``netsim list`` and ``netsim docs`` do).

    A half-written or broken plugin module must not stop validation: its plugins are then reported as
    unavailable, and this warning says why. Plugin modules are imported lazily (:mod:`netsim.registry`), so
    without ``load_all`` the warnings cover the modules the checks so far needed.
    """
    from netsim import registry

    failures = registry.load_plugins() if load_all else registry.plugin_failures()
    return [
        Problem("", f"plugin module '{module}' failed to import ({error}); its plugins are unavailable", severity=WARNING)
        for module, error in failures
    ]


def _params_model(plugin: Any) -> type[BaseModel] | None:
    cls = getattr(plugin, "Params", None)
    return cls if isinstance(cls, type) and issubclass(cls, BaseModel) else None


def validate_params(plugin: Any, raw: dict[str, Any]) -> Any:
    """Validate ``raw`` parameters with ``plugin.Params``; the raw dict when the plugin has no ``Params``.

    Raises
    ------
    ScenarioError
        With one problem per invalid parameter (paths relative to the parameters).
    """
    cls = _params_model(plugin)
    if cls is None:
        return dict(raw)
    try:
        return cls.model_validate(raw)
    except ValidationError as exc:
        raise ScenarioError(problems_from_validation_error(exc, model=cls)) from None


def _d(x: Any) -> dict[str, Any]:
    return x if isinstance(x, dict) else {}


def _l(x: Any) -> list[Any]:
    return x if isinstance(x, list) else []


def _names(x: Any) -> list[str]:
    return [k for k in _d(x) if isinstance(k, str)]


class _Checker:
    """Collects problems and validated plugin parameters for one raw scenario."""

    def __init__(self, raw: dict[str, Any], scenario: Scenario | None = None) -> None:
        self.raw = raw
        self.scenario = scenario  # the validated Scenario (None when the schema refused something)
        self.tasks: dict[tuple[str, int], Any] = {}  # (node, index) -> the task's validated TaskSpec
        self.problems: list[Problem] = []
        self.validated: dict[str, Any] = {}
        self.nodes = _names(raw.get("nodes"))
        self.networks = _d(raw.get("networks"))
        self.io = _names(raw.get("io"))
        self.signals = _names(raw.get("signals"))
        self.attached: dict[str, set[str]] = {}
        for net_name, net in self.networks.items():
            for node in _l(_d(net).get("nodes")):
                if isinstance(node, str):
                    self.attached.setdefault(node, set()).add(net_name)

    # ------------------------------------------------------------------ helpers
    def error(self, parts: Iterable[PathPart], message: str) -> None:
        self.problems.append(Problem(format_path(list(parts)), message))

    def warn(self, parts: Iterable[PathPart], message: str) -> None:
        self.problems.append(Problem(format_path(list(parts)), message, severity=WARNING))

    def lookup(self, kind: str, name: Any, at: list[PathPart]) -> Any:
        """The registered plugin or None (after recording a problem, also when build could not call it)."""
        if not isinstance(name, str) or not name:
            return None  # the schema reports the type problem
        from netsim import registry
        from netsim.scenario.calls import call_problem

        try:
            plugin = registry.lookup(kind, name)
        except ConfigError as exc:
            self.error(at, exc.message)
            return None
        except Exception as exc:  # noqa: BLE001 - importing a user's "module:attr" may raise anything
            self.error(at, f"cannot load {kind} '{name}': {type(exc).__name__}: {exc}")
            return None
        problem = call_problem(kind, name, plugin) if ":" in name else None  # registered: made for this call
        if problem is not None:
            self.error(at, problem)
            return None
        return plugin

    def params(self, plugin: Any, raw: Any, prefix: list[PathPart], key: str) -> Any:
        """Validate plugin parameters; stores and returns the validated object (None when invalid)."""
        if plugin is None or not isinstance(raw, dict):
            return None
        cls = _params_model(plugin)
        if cls is None:
            self.validated[key] = dict(raw)
            return dict(raw)
        try:
            model = cls.model_validate(raw)
        except ValidationError as exc:
            self.problems += problems_from_validation_error(exc, prefix=prefix, model=cls)
            return None
        except Exception as exc:  # noqa: BLE001 - a plugin validator that crashes is reported at its path
            self.error(prefix, f"parameters rejected: {type(exc).__name__}: {exc}")
            return None
        self.nested(model, prefix)
        self.validated[key] = model
        return model

    def nested(self, model: Any, prefix: list[PathPart]) -> None:
        """Parameters a plugin hands to another plugin (``design_params`` of a controller design), checked with
        that plugin's ``Params`` when the model names them (``nested_params()``)."""
        nested = getattr(model, "nested_params", None)
        if not callable(nested):
            return
        try:
            items = nested()
        except Exception as exc:  # noqa: BLE001 - a plugin's own hook that crashes is reported at its path
            self.error(prefix, f"parameters rejected: {type(exc).__name__}: {exc}")
            return
        for field, cls, raw in items:
            if not (isinstance(cls, type) and issubclass(cls, BaseModel)) or not isinstance(raw, dict):
                continue
            try:
                cls.model_validate(raw)
            except ValidationError as exc:
                self.problems += problems_from_validation_error(exc, prefix=[*prefix, field], model=cls)

    def network_ref(self, node: str, net: Any, at: list[PathPart]) -> bool:
        """Check that ``net`` is a network ``node`` is attached to; True when it is."""
        if not isinstance(net, str):
            return False
        if net not in self.networks:
            self.error(at, f"unknown network '{net}'{did_you_mean(net, self.networks, what='networks')}")
            return False
        if net not in self.attached.get(node, set()):
            on = ", ".join(str(n) for n in _l(_d(self.networks[net]).get("nodes"))) or "none"
            self.error(at, f"node '{node}' is not attached to network '{net}' (its nodes: {on}); add '{node}' to networks.{net}.nodes")
            return False
        return True

    # ------------------------------------------------------------------ sections
    def run(self) -> None:
        outputs, inputs = self.plant()
        self.io_channels(outputs, inputs)
        self.signal_specs()
        self.network_specs()
        for name, node in _d(self.raw.get("nodes")).items():
            if isinstance(name, str) and len(name) <= NAME_MAX and isinstance(node, dict):  # limits: long names
                self.node(name, node)
        self.metrics(outputs)
        self.verdict_signals(outputs)
        self.record(outputs)
        self.problems += plugin_load_problems()  # the modules the lookups above imported (lazy registry)

    def plant(self) -> tuple[list[Any] | None, list[Any] | None]:
        plant = self.raw.get("plant")
        if not isinstance(plant, dict):
            return None, None
        if "type" in plant:  # a described plant (type: ss, tf, ...): its parameters are inline, at plant.<field>
            factory = self.lookup("plant", plant.get("type"), ["plant", "type"])
            fixed = ("type", "model", "params", "x0", "disturbances", "record_grid", "process_noise", "integrator")
            raw = {k: v for k, v in plant.items() if k not in fixed}
            if isinstance(plant.get("params"), dict):
                raw = {**plant["params"], **raw}
            params = self.params(factory, raw, ["plant"], "plant")
        else:
            factory = self.lookup("plant", plant.get("model"), ["plant", "model"])
            params = self.params(factory, plant.get("params", {}) if plant.get("params") is not None else {}, ["plant", "params"], "plant")
        inputs, outputs = _ports(factory, params)
        if factory is not None and params is not None and (inputs is None or outputs is None):
            inputs, outputs = self.built_ports(plant.get("model"), factory, params, inputs, outputs)
        for key, sig in _d(plant.get("disturbances")).items():
            self.port_ref(key, inputs, "input", ["plant", "disturbances", str(key)])
            if isinstance(sig, str) and sig not in self.signals:
                self.error(["plant", "disturbances", str(key)], f"unknown signal '{sig}'{did_you_mean(sig, self.signals, what='signals')}")
        return outputs, inputs

    def built_ports(self, model: Any, factory: Any, params: Any, inputs: list[Any] | None,
                    outputs: list[Any] | None) -> tuple[list[Any] | None, list[Any] | None]:
        """Ports of a registered plant that does not declare them, from the plant ``build`` would make.

        Only plants from netsim's own plugin modules are built (:func:`netsim.registry.is_builtin`; validating
        must not run code a scenario brings along). A plant that refuses its parameters is reported as
        ``build`` would report it.
        """
        from netsim.registry import is_builtin
        from netsim.build.builder import make_plant

        if not isinstance(model, str) or not is_builtin(factory):
            return inputs, outputs

        try:
            built = make_plant(model, factory, params)
        except ConfigError as exc:
            self.error(parse_path(exc.path) if exc.path else ["plant"], exc.message)
            return inputs, outputs
        names_in, names_out = getattr(built, "input_names", None), getattr(built, "output_names", None)
        if inputs is None and isinstance(names_in, (list, tuple)):
            inputs = list(names_in)
        if outputs is None and isinstance(names_out, (list, tuple)):
            outputs = list(names_out)
        return inputs, outputs

    def port_ref(self, port: Any, ports: list[Any] | None, what: str, at: list[PathPart]) -> None:
        if ports is None or isinstance(port, bool):
            return
        if isinstance(port, str) and port.strip().isdigit():
            port = int(port)
        if isinstance(port, int):
            if not 0 <= port < len(ports):
                n = len(ports)
                self.error(at, f"plant {what} index {port} out of range: the plant has {n} {what}{'s' if n != 1 else ''}" + (f" (0..{n - 1})" if n else ""))
        elif isinstance(port, str):
            names = [p for p in ports if isinstance(p, str)]
            if names and port not in names:
                self.error(at, f"the plant has no {what} '{port}'{did_you_mean(port, names, what=what + 's')}")

    def io_channels(self, outputs: list[Any] | None, inputs: list[Any] | None) -> None:
        for name, ch in _d(self.raw.get("io")).items():
            if not isinstance(ch, dict):
                continue
            if self.raw.get("plant") is None:
                self.error(["io", name], "io channels connect to a plant, but the scenario has no 'plant:' section")
                continue
            kind = ch.get("type")
            if kind in ("adc", "encoder"):
                self.port_ref(ch.get("output", 0), outputs, "output", ["io", name, "output"])
            elif kind == "dac":
                self.port_ref(ch.get("input", 0), inputs, "input", ["io", name, "input"])

    def signal_specs(self) -> None:
        for name, sig in _d(self.raw.get("signals")).items():
            if not isinstance(sig, dict):
                continue
            plugin = self.lookup("signal", sig.get("type"), ["signals", name, "type"])
            raw = {k: v for k, v in sig.items() if k not in ("type", "params")}
            if isinstance(sig.get("params"), dict):
                raw = {**sig["params"], **raw}
            self.params(plugin, raw, ["signals", name], f"signals.{name}")

    def network_specs(self) -> None:
        for name, net in self.networks.items():
            if not isinstance(net, dict):
                continue
            seen: set[str] = set()
            for i, node in enumerate(_l(net.get("nodes"))):
                if not isinstance(node, str):
                    continue
                if node not in self.nodes:
                    self.error(["networks", name, "nodes", i], f"unknown node '{node}'{did_you_mean(node, self.nodes, what='nodes')}")
                if node in seen:
                    self.error(["networks", name, "nodes", i], f"node '{node}' is listed twice")
                seen.add(node)
            plugin = self.lookup("network", net.get("type"), ["networks", name, "type"])
            raw = {k: v for k, v in net.items() if k not in ("type", "params")}
            if isinstance(net.get("params"), dict):
                raw = {**net["params"], **raw}
            raw.setdefault("nodes", [])
            self.params(plugin, raw, ["networks", name], f"networks.{name}")

    def node(self, name: str, node: dict[str, Any]) -> None:
        base: list[PathPart] = ["nodes", name]
        policy = node.get("policy", "fp")
        if isinstance(policy, str) and not is_builtin_policy(policy):
            try:
                find_policy(policy)  # the one resolver the kernel uses (issue 15 C)
            except ConfigError as exc:
                self.error([*base, "policy"], exc.message)
            except Exception as exc:  # noqa: BLE001 - a policy plugin that fails to load is a problem at its path
                self.error([*base, "policy"], f"cannot load policy '{policy}': {type(exc).__name__}: {exc}")
        handlers = [h.get("name") for h in _l(node.get("handlers")) if isinstance(h, dict)]
        self.receivers: dict[str, str] = {}
        for kind in ("tasks", "handlers"):
            for i, item in enumerate(_l(node.get(kind))):
                if not isinstance(item, dict):
                    continue
                at: list[PathPart] = [*base, kind, i]
                if kind == "tasks":
                    self.task(name, node, item, at, handlers, self.task_model(name, i, item))
                else:
                    self.handler(name, item, at)
                program = self.lookup("program", item.get("program"), [*at, "program"])
                raw = item.get("params", {})
                raw = {} if raw is None else raw
                model = self.params(program, raw, [*at, "params"], format_path(at))
                values = _values(model) if model is not None else _d(raw)
                self.problems += sync_ref_problems(name, node, model, [*at, "params"])
                if kind == "tasks" and item.get("period") is None:
                    self.pid_period(model, [*at, "params"])
                self.conventions(name, values, [*at, "params"])
                if getattr(program, "interference_source", False) is True:
                    self.interference(name, values, [*at, "params"])
                hook = getattr(program, "scenario_warnings", None)  # a program's own checks of its setting
                if callable(hook) and model is not None:
                    for key, text in hook(self.raw, values):
                        self.warn([*at, "params", key], text)

    def pid_period(self, model: Any, at: list[PathPart]) -> None:
        """A PID program in a task without a period needs its own sampling period ``h`` (PID.from_params's rule)."""
        from netsim.control.pid import PIDParams

        if isinstance(model, PIDParams) and model.h is None:
            self.error(at, "this PID controller runs in a task without a period, so it has no sampling period; "
                           "add 'h: 10 ms' (say) to params, or give the task a period")

    def task_model(self, node_name: str, index: int, item: dict[str, Any]) -> Any:
        """The validated :class:`~netsim.scenario.schema.TaskSpec` of a task entry: the scenario's own (read once
        by the schema), or, when the schema refused something elsewhere, this entry validated alone so that its
        checks still run (None when the entry itself is refused: the schema reports it)."""
        if self.scenario is not None:
            model = self.scenario.nodes[node_name].tasks[index]
        else:
            from netsim.scenario.schema import TaskSpec

            try:
                model = TaskSpec.model_validate(item)
            except ValidationError:
                model = None
        if model is not None:
            self.tasks[(node_name, index)] = model
        return model

    def task(self, node_name: str, node: dict[str, Any], task: dict[str, Any], at: list[PathPart],
             handlers: list[Any], model: Any) -> None:
        """A task's release rules, the kernel's and the policy's checks (on its validated model) and its
        handler and network references."""
        if model is not None and model.release_network is not None:
            net = model.release_network
            if self.network_ref(node_name, net, [*at, "release"]):
                self.one_receiver(node_name, net, at, [*at, "release"])
        refused = self.kernel_checks(node_name, node, model, at)
        table = getattr(model.execution, "table", None) if model is not None else None
        if table is not None:  # an empirical execution time read from a CSV file: build reads it (netsim.build.builder._execution)
            try:
                table()
            except ConfigError as exc:
                self.error([*at, "execution"], exc.message)
        if model is not None and model.period is not None and model.deadline is not None \
                and model.deadline > model.period and "deadline" not in refused:
            self.warn([*at, "deadline"], f"deadline {format_time(model.deadline)} is longer than the period "
                                         f"{format_time(model.period)}; jobs may overlap (allowed)")
        for key in ("wcet_handler", "deadline_handler"):
            ref = task.get(key)
            if isinstance(ref, str) and ref not in handlers:
                known = [h for h in handlers if isinstance(h, str)]
                self.error([*at, key], f"node '{node_name}' has no handler '{ref}'{did_you_mean(ref, known, what='handlers')}")

    def kernel_checks(self, node_name: str, node: dict[str, Any], model: Any, at: list[PathPart]) -> set[str]:
        """The kernel's own checks of a task (:meth:`netsim.kernel.task.TaskSpec.checked`: release rules, times,
        handlers), then the built-in policy's ``check``, exactly as ``build`` runs them; returns the fields they
        refused.

        Skipped for a task the schema refuses (it reports that). Policies that are not built in are not
        instantiated here (validating must not run a scenario's own code).
        """
        from netsim.errors import BuildError

        if model is None:
            return set()
        policy_name = node.get("policy", "fp")
        try:
            spec = model.checked(node_name)
            if is_builtin_policy(policy_name):
                resolve_policy(policy_name, node_name).check(node_name, spec)
        except BuildError as exc:
            field = getattr(exc, "field", None)  # netsim.kernel.task.task_error's field and reason: the path's
            reason = getattr(exc, "reason", None)  # last key and the message at it
            self.error([*at, field] if field else at, reason if isinstance(reason, str) else exc.message)
            return {field} if field else set()
        return set()

    def handler(self, node_name: str, handler: dict[str, Any], at: list[PathPart]) -> None:
        trigger = handler.get("trigger")
        if isinstance(trigger, dict) and isinstance(trigger.get("on_message"), str):
            where = [*at, "trigger", "on_message"]
            if self.network_ref(node_name, trigger["on_message"], where):
                self.one_receiver(node_name, trigger["on_message"], at, where)
        if isinstance(trigger, dict) and isinstance(trigger.get("periodic_load"), dict):
            self.periodic_load(handler, trigger["periodic_load"], at)

    def periodic_load(self, handler: dict[str, Any], load: dict[str, Any], at: list[PathPart]) -> None:
        """A periodic load needs a constant execution time that fits in its period."""
        execution = handler.get("execution")
        if isinstance(execution, dict) and execution.get("dist") == "constant":
            execution = execution.get("value")
        if isinstance(execution, dict):
            self.error([*at, "execution"], "a handler with a 'periodic_load' trigger needs a constant execution time "
                                           f"(e.g. 'execution: 2 us'), not a '{execution.get('dist')}' distribution")
            return
        cost = (_time_or_none(handler.get("latency")) or 0) + (_time_or_none(execution) or 0)
        period = _time_or_none(load.get("period"))
        if period is not None and period > 0 and cost >= period:
            self.error([*at, "execution"], f"latency + execution ({format_time(cost)}) must be shorter than the "
                                           f"periodic_load period ({format_time(period)})")

    def consumers(self, net: str) -> dict[str, str]:
        """Nodes whose task or handler is released by every message on ``net``: node -> that item's path."""
        out: dict[str, str] = {}
        for node_name, node in _d(self.raw.get("nodes")).items():
            for kind in ("tasks", "handlers"):
                for i, item in enumerate(_l(_d(node).get(kind))):
                    item = _d(item)
                    release = item.get("release")
                    trigger = _d(item.get("trigger")).get("on_message")
                    if (isinstance(release, str) and release.replace(" ", "") == f"on_message:{net}") or trigger == net:
                        out.setdefault(str(node_name), format_path(["nodes", str(node_name), kind, i]))
        return out

    def interference(self, node: str, values: dict[str, Any], at: list[PathPart]) -> None:
        """Warn when interfering frames reach a node that consumes the network's messages."""
        from netsim.programs import BROADCAST

        net, to = values.get("network"), values.get("to")
        if not isinstance(net, str) or net not in self.networks or not isinstance(to, (str, type(None))):
            return  # a 'to' that is not a name: the program's parameters report it
        members = [n for n in _l(_d(self.networks[net]).get("nodes")) if isinstance(n, str)]
        reached = [n for n in members if n != node] if to in (None, BROADCAST) else [to]
        consumers = self.consumers(net)
        hit = [n for n in reached if n in consumers and n != node]
        if hit:
            which = ", ".join(f"'{n}' ({consumers[n]})" for n in hit)
            self.warn([*at, "to"], f"interfering frames on '{net}' reach {which}, released by every message on "
                                   f"'{net}'; send them where nothing consumes them (TrueTime's interference node "
                                   f"sends to itself: 'to: {node}')")

    def one_receiver(self, node: str, net: str, owner: list[PathPart], at: list[PathPart]) -> None:
        """A node has one receiver (task or handler) per network: the kernel binds each network once."""
        if net in self.receivers:
            self.error(at, f"messages from network '{net}' already go to {self.receivers[net]} on node '{node}'; "
                           "a node has one receiver per network (let that program hand messages on)")
        else:
            self.receivers[net] = format_path(owner)

    def conventions(self, node: str, values: dict[str, Any], at: list[PathPart]) -> None:
        """Check program parameters that name networks, nodes, channels and signals (see module doc)."""
        for key, value in values.items():
            if not isinstance(key, str):
                continue
            where = [*at, key]
            if key == "network" or key.endswith("_network"):
                self.network_ref(node, value, where)
            elif key == "networks" or key.endswith("_networks"):
                for i, v in enumerate(_l(value)):
                    self.network_ref(node, v, [*where, i])
            elif key == "channel" or key.endswith("_channel"):
                self.name_ref(value, self.io, "io channel", where)
                if key.endswith("output_channel"):  # a program writes it: job.analog_out needs a DAC
                    self.dac_ref(value, where)
            elif key == "channels" or key.endswith("_channels"):
                for i, v in enumerate(_l(value)):
                    self.name_ref(v, self.io, "io channel", [*where, i])
            elif key in ("signal", "reference") or key.endswith("_signal"):
                self.name_ref(value, self.signals, "signal", where)
            elif key == "signals" or key.endswith("_signals"):
                for i, v in enumerate(_l(value)):
                    self.name_ref(v, self.signals, "signal", [*where, i])
            elif key == "to":
                self.to_ref(node, value, values.get("network"), where)
            elif key == "tasks" or key.endswith("_tasks"):  # e.g. a feedback scheduler's controlled tasks
                for i, v in enumerate(_l(value)):
                    self.periodic_task_ref(node, v, [*where, i])
            elif isinstance(value, (dict, BaseModel)):  # nested parameters follow the same conventions
                self.conventions(node, _values(value), where)
            elif isinstance(value, list):  # and so do lists of them (measurements: [{network: can, ...}])
                for i, item in enumerate(value):
                    if isinstance(item, (dict, BaseModel)):
                        self.conventions(node, _values(item), [*where, i])

    def dac_ref(self, value: Any, at: list[PathPart]) -> None:
        """An ``*output_channel`` parameter names an io channel of type ``dac`` (what ``analog_out`` writes)."""
        channel = _d(self.raw.get("io")).get(value) if isinstance(value, str) else None
        kind = _d(channel).get("type")
        if isinstance(kind, str) and kind != "dac":
            dacs = [n for n, c in _d(self.raw.get("io")).items() if _d(c).get("type") == "dac"]
            self.error(at, f"io channel '{value}' is an {kind}, and a program writes its output to a dac; use one "
                           f"of the dac channels ({', '.join(map(str, dacs)) or 'none: add one under io'})")

    def periodic_task_ref(self, node: str, name: Any, at: list[PathPart]) -> None:
        """A program parameter naming a periodic task of its own node (``tasks``, ``*_tasks``), not the task
        whose parameters these are."""
        items = _l(_d(_d(self.raw.get("nodes")).get(node)).get("tasks"))
        tasks = {t["name"]: t for t in items if isinstance(t, dict) and isinstance(t.get("name"), str)}
        if not isinstance(name, str):
            return
        # at: nodes.<node>.tasks[i].params...: the task whose parameters these are
        owner = items[at[3]] if len(at) > 3 and at[2] == "tasks" and isinstance(at[3], int) else None
        if name not in tasks:
            self.error(at, f"node '{node}' has no task '{name}'{did_you_mean(name, list(tasks), what='tasks')}")
        elif owner is tasks[name]:
            self.error(at, f"task '{name}' is the task these parameters belong to; remove it (name other periodic "
                           f"tasks of node '{node}')")
        elif tasks[name].get("period") is None:
            self.error(at, f"task '{name}' is not periodic (it has no period); give it a period or list a "
                           f"periodic task of node '{node}'")

    def name_ref(self, value: Any, known: list[str], what: str, at: list[PathPart]) -> None:
        if isinstance(value, str) and value not in known:
            self.error(at, f"unknown {what} '{value}'{did_you_mean(value, known, what=what + 's')}")

    def to_ref(self, node: str, to: Any, net: Any, at: list[PathPart]) -> None:
        from netsim.programs import BROADCAST

        if to is None or not isinstance(to, str) or to == BROADCAST:
            return
        if to not in self.nodes:
            self.error(at, f"unknown node '{to}'{did_you_mean(to, self.nodes, what='nodes')}")
            return
        if isinstance(net, str) and net in self.networks:
            members = [n for n in _l(_d(self.networks[net]).get("nodes")) if isinstance(n, str)]
            if to not in members:
                self.error(at, f"node '{to}' is not on network '{net}' (its nodes: {', '.join(members) or 'none'}); add it to networks.{net}.nodes or send to one of those")
        elif net is None and not (self.attached.get(node, set()) & self.attached.get(to, set())):
            self.error(at, f"nodes '{node}' and '{to}' share no network; attach both to one in 'networks'")

    def metrics(self, outputs: list[Any] | None = None) -> None:
        for i, metric in enumerate(_l(self.raw.get("metrics"))):
            if not isinstance(metric, dict):
                continue
            plugin = self.lookup("metric", metric.get("type"), ["metrics", i, "type"])
            raw = metric.get("params", {})
            raw = {} if raw is None else raw
            model = self.params(plugin, raw, ["metrics", i, "params"], f"metrics[{i}]")
            if plugin is not None:
                values = _values(model) if model is not None else _d(raw)
                self.metric_signals(str(metric.get("type")), values, ["metrics", i, "params"])
                type_path: list[str | int] = ["metrics", i, "type"]
                refs = [*_signal_refs(values, ["metrics", i, "params"]),
                        *((list(type_path), n) for n in getattr(plugin, "reads_signals", ()))]
                self.grid_outputs(str(metric.get("type")), values, refs, outputs)
                self.metric_reads(plugin, str(metric.get("type")), ["metrics", i, "type"])
                from netsim.metrics.chain import unkept_tables  # run refused these, validate passed them (issue 31)

                for table, message in unkept_tables(plugin, i, str(metric.get("type")), _d(self.raw.get("output"))):
                    self.error(["output", table], message)
                for key, value in values.items():
                    if isinstance(key, str) and (key == "chain" or key.endswith("_chain")):
                        if isinstance(value, list) and not value:  # was accepted, and reported "worst -"
                            self.error(["metrics", i, "params", key], f"'{key}' is empty; list the tasks of the "
                                       "chain as 'node.task', e.g. [sensor.sample, controller.control]")
                        for j, ref in enumerate(_l(value)):
                            self.task_ref(ref, ["metrics", i, "params", key, j])

    def metric_signals(self, metric: str, values: dict[str, Any], at: list[PathPart]) -> None:
        """A metric reads recorded signals after the run: with a ``record:`` list, each signal its parameters
        name (fields ``reference``, ``output``, ``signal``, ``*_signal`` and their plurals) must be in it."""
        record = self.raw.get("record")
        if not isinstance(record, list):
            return  # omitted or null: everything is recorded
        kept = {r for r in record if isinstance(r, str)}
        for where, name in _signal_refs(values, at):
            if name in kept or name.split("[", 1)[0] in kept:
                continue
            listed = ", ".join(r for r in record if isinstance(r, str)) or "nothing"
            self.error(where, f"metric '{metric}' reads signal '{name}', which 'record:' leaves out "
                              f"(record: [{listed}]); add '{name}' to 'record:'")

    def grid_outputs(self, metric: str, values: dict[str, Any], refs: list[tuple[list[PathPart], str]],
                     outputs: list[Any] | None, reader: str | None = None) -> None:
        """A plant output is recorded under its name only on ``plant.record_grid``: without the grid, a metric
        reading one (``refs``: its signal parameters and its ``reads_signals``) fails after the run ("signal 'y'
        was not recorded"), unless something else records that
        name (an ``io`` channel or a ``signals`` source of that name, or a program parameter naming it, e.g.
        ``record_as: y``), so the check stays on the safe side."""
        plant = self.raw.get("plant")
        if not isinstance(plant, dict) or plant.get("record_grid") is not None or not outputs:
            return
        ports = {p for p in outputs if isinstance(p, str)}
        others = {*_d(self.raw.get("io")), *_d(self.raw.get("signals")), *_strings(self.raw.get("nodes"))}
        for where, name in refs:
            base = name.split("[", 1)[0]
            if base in ports and base not in others:
                period = values.get("period")
                grid = (format_time(period) if isinstance(period, int) and not isinstance(period, bool) and period > 0
                        else period if isinstance(period, str) else "1 ms")
                who = reader or f"metric '{metric}'"
                self.error(where, f"{who} reads the plant output '{name}', which is recorded only on "
                                  f"the plant's record grid, and 'plant:' sets no 'record_grid'; add e.g. "
                                  f"'record_grid: {grid}' under 'plant:'")

    def metric_reads(self, plugin: Any, metric: str, at: list[PathPart]) -> None:
        """A metric that reads fixed signal names declares them (``reads_signals``); with a ``record:`` list, each
        must be in it (a name ``xhat`` covers the columns ``xhat[0]``, ``xhat[1]``, ...)."""
        record = self.raw.get("record")
        reads = getattr(plugin, "reads_signals", ())
        if not isinstance(record, list) or not reads:
            return
        kept = {r for r in record if isinstance(r, str)}
        missing = [name for name in reads if name not in kept]
        if missing:
            listed = ", ".join(sorted(kept)) or "nothing"
            self.error(at, f"metric '{metric}' reads the signals {', '.join(missing)}, which 'record:' leaves out "
                           f"(record: [{listed}]); add them to 'record:'")

    def verdict_signals(self, outputs: list[Any] | None) -> None:
        """``verdict.signals`` and ``verdict.bound`` name signals the run judges after it ends: each must be
        recorded (in a ``record:`` list if there is one; a plant output needs ``plant.record_grid``), as for a
        metric's signals; otherwise the run could not judge it."""
        block = self.raw.get("verdict")
        if not isinstance(block, dict):
            return
        refs: list[tuple[list[PathPart], str]] = [
            (["verdict", "signals", j], n) for j, n in enumerate(_l(block.get("signals"))) if isinstance(n, str) and n]
        refs += [(["verdict", "bound", n], n) for n in _d(block.get("bound")) if isinstance(n, str) and n]
        record = self.raw.get("record")
        if isinstance(record, list):
            kept = {r for r in record if isinstance(r, str)}
            listed = ", ".join(r for r in record if isinstance(r, str)) or "nothing"
            for where, name in refs:
                if name not in kept and name.split("[", 1)[0] not in kept:
                    self.error(where, f"the verdict judges signal '{name}', which 'record:' leaves out "
                                      f"(record: [{listed}]); add '{name}' to 'record:'")
        self.grid_outputs("verdict", {}, refs, outputs, reader="the verdict")

    def task_ref(self, ref: Any, at: list[PathPart]) -> None:
        """``ref`` is ``node.task`` naming an existing task or handler of that node."""
        if not isinstance(ref, str):
            return  # the Params model reports the type
        node, sep, task = ref.partition(".")
        if not sep or not node or not task:
            self.error(at, f"expected 'node.task', got '{ref}'")
            return
        if node not in self.nodes:
            self.error(at, f"unknown node '{node}'{did_you_mean(node, self.nodes, what='nodes')}")
            return
        spec = _d(_d(self.raw.get("nodes")).get(node))
        names = [str(item["name"]) for kind in ("tasks", "handlers") for item in _l(spec.get(kind))
                 if isinstance(item, dict) and isinstance(item.get("name"), str)]
        if task not in names:
            hint = did_you_mean(task, names, what="tasks and handlers")
            self.error(at, f"node '{node}' has no task or handler '{task}'{hint}")

    def record(self, outputs: list[Any] | None) -> None:
        """``record`` entries must be names (text); whether each is ever recorded is known only after the run
        (programs record under names of their own), so the runner reports the names that stayed empty."""
        for i, name in enumerate(_l(self.raw.get("record"))):
            if not isinstance(name, str) or not name.strip():
                self.error(["record", i], f"expected a signal name, got {name!r}")


def _signal_refs(values: dict[str, Any], at: list[PathPart]) -> list[tuple[list[PathPart], str]]:
    """``(YAML path, name)`` of each signal a metric's parameters name: fields ``reference``, ``output``,
    ``signal``, ``*_signal`` and their plurals ``signals``, ``outputs``, ``*_signals``."""
    refs: list[tuple[list[PathPart], Any]] = []
    for key, value in values.items():
        if not isinstance(key, str):
            continue
        if key in ("reference", "output", "signal") or key.endswith("_signal"):
            refs.append(([*at, key], value))
        elif key in ("signals", "outputs") or key.endswith("_signals"):
            refs.extend(([*at, key, j], v) for j, v in enumerate(_l(value)))
    return [(where, name) for where, name in refs if isinstance(name, str) and name]


#: Program parameters that name plant outputs the program reads (``measurements[].outputs``, ``tracked``): never
#: a name it records under.
_READ_KEYS = frozenset({"outputs", "tracked"})


def _strings(tree: Any) -> set[str]:
    """Every string value in a raw YAML tree (the names programs may record under), except under the keys of
    :data:`_READ_KEYS`."""
    if isinstance(tree, str):
        return {tree}
    if isinstance(tree, dict):
        return set().union(*(_strings(v) for k, v in tree.items() if k not in _READ_KEYS)) if tree else set()
    if isinstance(tree, list):
        return set().union(*(_strings(v) for v in tree)) if tree else set()
    return set()


def _values(model: Any) -> dict[str, Any]:
    if isinstance(model, BaseModel):
        return {name: getattr(model, name, None) for name in type(model).model_fields}
    return _d(model)


def _time_or_none(value: Any) -> int | None:
    if value is None:
        return None
    try:
        return parse_time(value)
    except (TimeParseError, TypeError):
        return None


def _ports(factory: Any, params: Any) -> tuple[list[Any] | None, list[Any] | None]:
    """(inputs, outputs) of the plant when its factory declares them cheaply, else (None, None)."""
    if factory is None:
        return None, None
    ports = getattr(factory, "ports", None)
    if callable(ports) and params is not None:
        try:
            ins, outs = ports(params)
            return list(ins), list(outs)
        except Exception:  # noqa: BLE001 - ports are a convenience; a failure only skips the check
            log.debug("plant ports() failed", exc_info=True)
            return None, None

    def side(names_attr: str, count_attr: str) -> list[Any] | None:
        names = getattr(factory, names_attr, None)
        if isinstance(names, (list, tuple)):
            return list(names)
        count = getattr(factory, count_attr, None)
        if isinstance(count, int) and not isinstance(count, bool):
            return list(range(count))
        return None

    return side("input_names", "n_inputs"), side("output_names", "n_outputs")


def check_raw(raw: dict[str, Any], line_of: LineOf | None = None,
              scenario: Scenario | None = None) -> tuple[list[Problem], dict[str, Any]]:
    """Plugin and cross-reference problems of a raw scenario, and the validated plugin parameters.

    Parameters
    ----------
    raw
        The scenario as plain data.
    line_of
        ``line_of(path)``, the line of a YAML path: messages that point at a second place (the first definition
        of a duplicate name) then give its line.
    scenario
        The scenario the schema validated from ``raw`` (None when it refused something): the task checks read
        its tasks' fields instead of parsing the raw times again.

    Returns
    -------
    problems
        Problems with paths (no lines yet).
    validated
        Validated ``Params`` instances (or raw dicts) keyed by the owner's path: ``"plant"``,
        ``"signals.r"``, ``"nodes.n.tasks[0]"``, ``"nodes.n.handlers[0]"``, ``"networks.can"``,
        ``"metrics[0]"``.
    """
    checker = _Checker(raw, scenario)
    checker.run()
    checker.problems += limit_problems(raw, line_of, checker.tasks)
    return checker.problems, checker.validated
