"""Turn a validated :class:`~netsim.scenario.schema.Scenario` into a runnable :class:`Simulation`.

Lifecycle (desmod's build, connect, run, collect): :func:`build` creates every runtime object and connects
them; :meth:`Simulation.run` runs the event loop; :mod:`netsim.results` collects the tables.

What :func:`build` does, in order:

1. a :class:`~netsim.env.SimEnv` with the scenario seed and the ``record:`` filter;
2. the scenario signals (:func:`netsim.io.signals.make_signal` semantics);
3. the plant from its registered factory (``factory(params)``); each ``disturbances`` entry (plant input ->
   signal) is added with ``plant.add_disturbance`` (exact switching at the signal's jumps); the plant is bound
   to the env (recording its outputs on ``record_grid``; its state/input at events when ``record`` is
   omitted or names ``<plant>.x``/``<plant>.u``); then ``x0`` is set;
4. the ``io`` channels (ADC, DAC, encoder) attached to **every** kernel as analog channels by name
   (an encoder reads as its quantized position; the :class:`~netsim.io.Encoder` object itself is in
   ``env.components["io.<name>"]`` for programs that want its edges);
5. one kernel per node; its tasks and handlers run program instances built with a
   :class:`~netsim.programs.ProgramContext`; timers and external triggers are created from ``trigger:``;
6. the networks (``make_network``), attached to their nodes' kernels; tasks with
   ``release: on_message:<net>`` and handlers with ``trigger: {on_message: net}`` are bound to receptions;
   the energy meters of the nodes with ``energy:`` (:mod:`netsim.energy`);
7. recording of the scenario signals named in ``record:`` (at 0 and at every jump; continuous ones on the grid).

Steps 5 and 6 are :mod:`netsim.build.wiring`; its names are re-exported here.

``netsim validate`` runs this same :func:`build` once, with ``dry_run=True``: on a :class:`DryRunEnv` (an
environment that is never run), and without running code a scenario brings along (issue 14): a plant, signal or
network is built only when it comes from netsim's own plugin modules (:func:`netsim.registry.is_builtin`), the
kernels only when every node uses a built-in policy, and a program only when it is netsim's own and the plant
was built; anything else is left out (a program gets a placeholder body). :mod:`netsim.build.dry_run` turns the
first error into a problem at its YAML path.
"""

from __future__ import annotations

import logging
from collections.abc import Generator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from netsim.build.simulation import PROGRESS_SLICES, DryRunEnv, ProgressFn, SeedWatchEnv, Simulation
from netsim.build.wiring import bind_receivers, build_networks, checked_call, wire_kernels
from netsim.energy import attach_energy
from netsim.env import SimEnv
from netsim.errors import BuildError, ConfigError, NetsimError
from netsim.timebase import MS

if TYPE_CHECKING:
    from netsim.scenario.schema import Scenario

__all__ = ["Simulation", "build", "DryRunEnv", "make_plant", "wire_kernels", "build_networks", "bind_receivers", "DEFAULT_SIGNAL_GRID", "ProgressFn", "PROGRESS_SLICES"]

log = logging.getLogger(__name__)

#: Grid on which continuous (not piecewise-constant) disturbances and recorded signals are refreshed.
DEFAULT_SIGNAL_GRID = 1 * MS

# --------------------------------------------------------------------------------------------- pieces
def _record_filter(scenario: Scenario) -> set[str] | None:
    return None if scenario.record is None else set(scenario.record)


def _make_signals(scenario: Scenario) -> dict[str, Callable[[int], float]]:
    out: dict[str, Callable[[int], float]] = {}
    for name, spec in scenario.signals.items():
        cls = spec.plugin()
        try:
            out[name] = cls(spec.validated_params())
        except NetsimError:
            raise
        except Exception as exc:  # noqa: BLE001
            raise BuildError(f"cannot build signal '{name}': {exc}", path=f"signals.{name}") from exc
    return out


def make_plant(model: str, factory: Any, params: Any) -> Any:
    """``factory(params)``: the plant object of the scenario's ``plant:`` (``model`` names it in messages).

    ``netsim validate`` calls this too, for registered plants that do not declare their ports, to check the
    ``io`` channels against the plant's real inputs and outputs.

    Raises
    ------
    BuildError
        At path ``plant`` when the factory refuses its parameters.
    """
    try:
        return factory(params)
    except NetsimError:
        raise
    except Exception as exc:  # noqa: BLE001
        raise BuildError(f"cannot build plant '{model}': {exc}", path="plant") from exc


def _build_plant(scenario: Scenario, env: SimEnv, signals: dict[str, Any]) -> Any:
    """The plant from its factory, with disturbances (exact at jumps), bound to ``env``, then ``x0``."""
    spec = scenario.plant
    if spec is None:
        return None
    plant = make_plant(spec.model, spec.plugin(), spec.validated_params())
    if spec.process_noise is not None:
        checked_call(_set_process_noise, "plant.process_noise", plant, spec.process_noise)
    if spec.integrator is not None:
        checked_call(_set_integrator, "plant.integrator", plant, spec.integrator)
    for port, sig_name in spec.disturbances.items():
        checked_call(plant.add_disturbance, f"plant.disturbances.{port}", port, signals[sig_name])
    record_events = scenario.record is None or any(
        r in (f"{plant.name}.x", f"{plant.name}.u") for r in scenario.record
    )
    plant.bind(env, record_events=record_events, record_grid_ns=spec.record_grid)
    if spec.x0 is not None:
        checked_call(plant.set_state, "plant.x0", np.asarray(spec.x0, dtype=float), 0)
    return plant


def _set_integrator(plant: Any, spec: Any) -> None:
    fn = getattr(plant, "set_integrator", None)
    if callable(fn):
        fn(**spec.plant_kwargs())
        return
    raise BuildError(f"this plant ({type(plant).__name__}) has no integrator to choose (LTI and discrete plants are "
                     "propagated exactly); remove 'integrator'", path="plant.integrator")


def _set_process_noise(plant: Any, noise: Any) -> None:
    fn = getattr(plant, "set_process_noise", None)
    if callable(fn):
        fn(noise)
        return
    raise BuildError("this plant does not accept process_noise from the scenario; set it in the model's "
                     "params instead", path="plant.process_noise")


def _schedule_signal(env: SimEnv, sig: Callable[[int], float], t_end: int, grid: int,
                     action: Callable[[int, float], None]) -> None:
    """Call ``action(t, sig(t))`` at 0, at every jump of ``sig`` and, for continuous signals, on ``grid``."""
    piecewise = getattr(sig, "piecewise_constant", False)
    if piecewise and hasattr(sig, "breakpoints"):
        instants = [t for t in sig.breakpoints(0, t_end)]
    else:
        instants = list(range(grid, t_end + 1, grid))

    def proc() -> Generator[Any, Any, None]:
        action(0, sig(0))
        for t in instants:
            yield env.timeout(t - env.now)
            action(t, sig(t))

    env.process(proc())


def _build_io(scenario: Scenario, env: SimEnv, plant: Any) -> dict[str, Any]:
    if not scenario.io:
        return {}
    if plant is None:
        raise BuildError("io channels need a plant; add a 'plant:' section", path="io")
    from netsim.io import ADC, DAC, Encoder

    out: dict[str, Any] = {}
    for name, ch in scenario.io.items():
        path = f"io.{name}"
        try:
            if ch.type == "adc":
                out[name] = ADC(plant, ch.output, noise_std=ch.noise_std, quant_step=ch.quant_step,
                                saturation=ch.saturation, rng=env.rng(f"io.{name}.noise"))
            elif ch.type == "dac":
                out[name] = DAC(plant, ch.input, saturation=ch.saturation, resolution=ch.resolution)
            else:
                out[name] = Encoder(plant, ch.output, step=ch.step, tick_ns=ch.tick, mode=ch.mode)
        except NetsimError:
            raise
        except Exception as exc:  # noqa: BLE001
            raise BuildError(f"cannot build {ch.type} channel '{name}': {exc}", path=path) from exc
        env.components[f"io.{name}"] = out[name]
    return out


def _encoder_reader(enc: Any, plant: Any, output: Any, step: float) -> Callable[[int], float]:
    read = getattr(enc, "read", None)
    if callable(read):
        return read
    idx = plant.output_index(output)

    def quantized(t_ns: int) -> float:
        y = plant.output_value(idx, t_ns)
        return float(np.floor(y / step) * step)

    return quantized


def _attach_io(kernel: Any, scenario: Scenario, channels: dict[str, Any], plant: Any, env: SimEnv) -> None:
    """Give the kernel its analog channels; a channel named in ``record:`` is recorded at every read/write."""
    recorder = env.recorder
    for name, ch in scenario.io.items():
        obj = channels[name]
        wanted = recorder.wants(name)  # named in record:, or record: omitted (everything)
        if ch.type == "dac":
            # the channel's name records what the converter puts out (after saturation and resolution),
            # '<name>.command' what the program asked for (issue 21: u read +-600 with saturation [-1, 1])
            write = obj.write
            if wanted:
                def dac_output(value: Any, dac: Any = obj) -> Any:
                    return dac.last

                write = _recording_write(recorder, name, write, dac_output)
            if recorder.wants(f"{name}.command"):
                write = _recording_write(recorder, f"{name}.command", write)
            kernel.attach_analog_out(name, write)
            continue
        read = obj.read if ch.type == "adc" else _encoder_reader(obj, plant, ch.output, ch.step)
        kernel.attach_analog_in(name, _recording_read(recorder, name, read) if wanted else read)


def _recording_read(recorder: Any, name: str, read: Callable[[int], Any]) -> Callable[[int], Any]:
    def recorded_read(t_ns: int) -> Any:
        value = read(t_ns)
        recorder.record(name, t_ns, value)
        return value

    return recorded_read


def _recording_write(recorder: Any, name: str, write: Callable[[int, Any], None],
                     recorded: Callable[[Any], Any] | None = None) -> Callable[[int, Any], None]:
    """``write`` that also records ``recorded(value)`` (default: the value written) under ``name``."""
    def recorded_write(t_ns: int, value: Any) -> None:
        write(t_ns, value)
        recorder.record(name, t_ns, value if recorded is None else recorded(value))

    return recorded_write


def _execution(spec: Any, path: str) -> Any:
    """The entry's execution time (a distribution; None when not given); one read from a CSV file is read now,
    so a missing file is refused at ``<path>.execution`` when the run is built."""
    execution = spec.execution_time()
    table = getattr(execution, "table", None)
    if table is not None:
        try:
            table()
        except ConfigError as exc:
            raise BuildError(exc.message, path=f"{path}.execution") from None
    return execution


def _program(spec: Any, ctx: Any, path: str) -> Any:
    cls = spec.plugin()
    params = spec.validated_params()
    try:
        body = cls(ctx, params)
    except NetsimError as exc:
        if isinstance(exc, ConfigError) and exc.path is None:
            raise BuildError(exc.message, path=path) from None
        raise
    except (ValueError, TypeError, KeyError, ArithmeticError) as exc:  # ArithmeticError: e.g. slycot's, in a design
        raise BuildError(f"cannot build program '{spec.program}': {' '.join(str(exc).split())}", path=path) from exc
    if not callable(body):
        raise BuildError(f"program '{spec.program}' did not produce a callable body", path=path)
    return body


def _placeholder(job: Any) -> Any:
    """The body of a program a dry run does not build (the kernel only checks that bodies are generator
    functions); it never runs."""
    return
    yield  # pragma: no cover - makes this a generator function


def _build_kernels(scenario: Scenario, env: SimEnv, signals: dict[str, Any], channels: dict[str, Any],
                   plant: Any, reach: _Reach) -> tuple[dict[str, Any], dict[str, Any], list[tuple[str, str, str]]]:
    """Kernels with their tasks and handlers; returns also the (node, network, target) receive bindings."""
    if not scenario.nodes:
        return {}, {}, []
    from netsim.programs import ProgramContext

    programs: dict[str, Any] = {}

    def body(spec: Any, kernel: Any, node_name: str, path: str, period: int | None) -> Any:
        execution = _execution(spec, path)
        if not reach.program(spec):
            return _placeholder
        ctx = ProgramContext(env=env, kernel=kernel, node=node_name, task=spec.name, execution=execution,
                             signals=signals, scenario=scenario, period=period, spec=spec, dry_run=reach.dry)
        made = _program(spec, ctx, path)
        programs[f"{node_name}.{spec.name}"] = made
        return made

    def attach(kernel: Any) -> None:
        _attach_io(kernel, scenario, channels, plant, env)

    kernels, bindings = wire_kernels(scenario, env, body, attach if reach.plant else None)
    return kernels, programs, bindings


def _record_signals(scenario: Scenario, env: SimEnv, signals: dict[str, Any]) -> None:
    wanted = scenario.record
    grid = (scenario.plant.record_grid if scenario.plant is not None else None) or DEFAULT_SIGNAL_GRID
    for name, sig in signals.items():
        if wanted is not None and name not in wanted:
            continue
        def record(t: int, v: float, n: str = name) -> None:
            env.record(n, v, t)

        _schedule_signal(env, sig, scenario.duration, grid, record)


# --------------------------------------------------------------------------------------------- build
def _lookup(kind: str, name: str) -> Any:
    from netsim import registry

    try:
        return registry.lookup(kind, name)
    except ConfigError:
        return None


@dataclass(frozen=True)
class _Reach:
    """What a build makes: everything for a run; for a dry run, only what netsim's own code makes.

    Attributes
    ----------
    dry
        True for a dry run.
    plant
        Build the signals, the plant and the io channels (a dry run: when each comes from netsim's own modules).
    kernels
        Build the kernels (a dry run: when every node uses a built-in policy).
    networks
        Build the networks (a dry run: when each network type is one of netsim's own Network classes).
    """

    dry: bool = False
    plant: bool = True
    kernels: bool = True
    networks: bool = True

    @classmethod
    def of(cls, scenario: Scenario, dry_run: bool) -> _Reach:
        if not dry_run:
            return cls()
        from netsim.kernel.policies import is_builtin_policy
        from netsim.registry import is_builtin

        objs = [_lookup("signal", s.type) for s in scenario.signals.values()]
        if scenario.plant is not None:
            objs.append(_lookup("plant", scenario.plant.model))
        nets = [_lookup("network", n.type) for n in scenario.networks.values()]
        if nets:  # the network classes only when there are networks (issue 29: start-up)
            from netsim.network.pipeline import Network
        return cls(dry=True,
                   plant=all(o is not None and is_builtin(o) for o in objs),
                   kernels=all(is_builtin_policy(node.policy) for node in scenario.nodes.values()),
                   networks=all(isinstance(c, type) and issubclass(c, Network) and is_builtin(c) for c in nets))

    def program(self, spec: Any) -> bool:
        """Whether the program of a task or handler entry is built (a dry run: netsim's own, with the plant)."""
        if not self.dry:
            return True
        from netsim.registry import is_builtin

        return self.plant and is_builtin(_lookup("program", spec.program))


def build(scenario: Scenario, *, dry_run: bool = False) -> Simulation:
    """Create and connect every runtime object of a validated :class:`~netsim.scenario.schema.Scenario`.

    To build from a file, a dict or a python-control system, use :func:`netsim.scenario.build`, which loads and
    validates first (this module never loads: loading validates by building, so the two stay one-way).

    Parameters
    ----------
    scenario
        The validated scenario.
    dry_run
        Build on a :class:`DryRunEnv` and only what netsim's own code makes (see the module docstring): what
        ``netsim validate`` checks. The result is never run.

    Raises
    ------
    BuildError
        When a valid description cannot be turned into runtime objects (the message names the YAML path).
    TypeError
        When ``scenario`` is not a Scenario.
    """
    from netsim.scenario.schema import Scenario

    if not isinstance(scenario, Scenario):
        raise TypeError(f"builder.build takes a validated Scenario, not {type(scenario).__name__}; use "
                        f"netsim.scenario.build(path_or_dict) or netsim.scenario.load_scenario first")
    reach = _Reach.of(scenario, dry_run)
    env: SimEnv = (DryRunEnv if dry_run else SeedWatchEnv)(seed=scenario.seed, record=_record_filter(scenario))
    signals: dict[str, Callable[[int], float]] = {}
    plant, channels = None, {}
    if reach.plant:
        signals = _make_signals(scenario)
        plant = _build_plant(scenario, env, signals)
        if plant is not None:
            env.components["plant"] = plant
        channels = _build_io(scenario, env, plant)
    kernels: dict[str, Any] = {}
    programs: dict[str, Any] = {}
    networks: dict[str, Any] = {}
    energy: dict[str, Any] = {}
    if reach.kernels:
        kernels, programs, bindings = _build_kernels(scenario, env, signals, channels, plant, reach)
        if reach.networks:
            networks = build_networks(scenario, env, kernels)
            bind_receivers(kernels, networks, bindings)
            energy = attach_energy(scenario, env, kernels, networks)
    _record_signals(scenario, env, signals)
    return Simulation(scenario=scenario, env=env, plant=plant, signals=signals, channels=channels,
                      kernels=kernels, networks=networks, programs=programs, duration=scenario.duration,
                      energy=energy)
