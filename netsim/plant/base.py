"""The plant base class: state at an integer-nanosecond instant, advanced lazily under held inputs (see :mod:`netsim.plant`)."""

from __future__ import annotations

import abc
import logging
import math
from typing import Any, Callable, ClassVar, Iterable, Sequence

import numpy as np

from netsim.env import NORMAL, RECORD, schedule_call
from netsim.errors import BuildError, ConfigError, DivergenceError, SimulationError
from netsim.plant.disturbance import _classify, _Source
from netsim.plant.shared import NEVER, _names, _vector
from netsim.timebase import format_time, to_seconds

__all__ = ["Plant"]

_log = logging.getLogger("netsim.plant")


class Plant(abc.ABC):
    """Common interface and lazy-advance machinery of all plants.

    Subclasses implement :meth:`_step` (propagate over ``[self._t, t]`` with the effective input constant
    apart from sinusoidal/continuous-model disturbances they handle themselves), :meth:`_output_now` and
    :meth:`_state_now`, and may override :meth:`advance_to` with a faster path.

    A subclass whose output is a pure function of (plant time, state, effective input) sets
    ``_cache_output = True``: the output is then computed once per such triple and kept (privately) until
    the plant time, the state (:meth:`set_state`) or the effective input (an input change, a disturbance
    jump) changes; :meth:`output` hands out copies, :meth:`output_value` and the ``record_grid`` sampler
    read it without one.

    Parameters
    ----------
    n_states, n_inputs, n_outputs
        Dimensions.
    input_names, output_names, state_names
        Signal names (default ``u[i]``, ``y[i]``, ``x[i]`` as in python-control).
    name
        Plant name: noise streams are ``plant.<name>.process`` and recorded signals ``<name>.x``.
    divergence_bound
        The run stops with :class:`DivergenceError` when the state norm exceeds this (or is not finite).
    """

    def __init__(
        self,
        n_states: int,
        n_inputs: int,
        n_outputs: int,
        *,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        state_names: Sequence[str] | None = None,
        name: str = "plant",
        divergence_bound: float = 1e12,
    ) -> None:
        if n_states < 0 or n_inputs < 0 or n_outputs < 1:
            raise ConfigError(f"plant {name}: needs n_states >= 0, n_inputs >= 0, n_outputs >= 1")
        self.name = str(name)
        self.n_states, self.n_inputs, self.n_outputs = int(n_states), int(n_inputs), int(n_outputs)
        self.input_names = _names("input", input_names, self.n_inputs, "u")
        self.output_names = _names("output", output_names, self.n_outputs, "y")
        self.state_names = _names("state", state_names, self.n_states, "x")
        if not (divergence_bound > 0 and math.isfinite(divergence_bound)):
            raise ConfigError(f"plant {name}: divergence_bound must be a positive finite number")
        self.divergence_bound = float(divergence_bound)
        self._bound2 = self.divergence_bound**2
        self.env: Any = None
        self._t = 0
        self._u = np.zeros(self.n_inputs)  # inputs as last set (before disturbances)
        self._listeners: list[Callable[[int], None]] = []
        self._sources: list[_Source] = []
        self._next_break = NEVER
        self._has_held = False
        self._started = False
        self._record_events = False
        # True once started when an advance needs no per-call bookkeeping (no sampled-and-held disturbance
        # to re-sample, no state recording): the subclasses' fast paths are allowed then
        self._plain = False
        self._y: np.ndarray | None = None  # cached output at time _y_t (see _cache_output)
        self._y_t = -1

    _cache_output: ClassVar[bool] = False

    # ---------------------------------------------------------------- names
    def input_index(self, key: int | str) -> int:
        """Index of input ``key`` (an index or a name)."""
        return self._index("input", key, self.input_names)

    def output_index(self, key: int | str) -> int:
        """Index of output ``key`` (an index or a name)."""
        return self._index("output", key, self.output_names)

    def state_index(self, key: int | str) -> int:
        """Index of state ``key`` (an index or a name)."""
        return self._index("state", key, self.state_names)

    def _index(self, kind: str, key: int | str, names: list[str]) -> int:
        if isinstance(key, (int, np.integer)) and not isinstance(key, bool):
            if 0 <= int(key) < len(names):
                return int(key)
            raise ConfigError(f"plant {self.name}: {kind} index {key} out of range 0..{len(names) - 1}")
        if key in names:
            return names.index(str(key))
        raise ConfigError(f"plant {self.name} has no {kind} {key!r}; its {kind}s are {names}")

    # ---------------------------------------------------------------- life cycle
    @property
    def time_ns(self) -> int:
        """Instant the plant state refers to."""
        return self._t

    def bind(
        self,
        env: Any,
        *,
        record_events: bool = False,
        record_grid_ns: int | None = None,
        grid_prefix: str = "",
    ) -> "Plant":
        """Attach the plant to a :class:`~netsim.env.SimEnv` (noise streams, recording). Call once.

        Parameters
        ----------
        record_events
            Record the state ``<name>.x`` at every propagation instant and the held input ``<name>.u`` at
            every input change.
        record_grid_ns
            Also record every output, under its output name (prefixed by ``grid_prefix``), on this fixed grid
            starting at the current time (a chain of call entries on the event heap).
        """
        if self.env is not None:
            raise BuildError(f"plant {self.name} is already bound to an environment")
        self.env = env
        self._t = int(env.now)
        self._record_events = bool(record_events)
        self._plain = self._started and self._is_plain()
        for src in self._sources:
            src.rng = self._source_stream(src)
        self._bind_streams(env)
        if record_grid_ns is not None:
            grid = int(record_grid_ns)
            if grid <= 0:
                raise ConfigError(f"plant {self.name}: record_grid must be positive, got {record_grid_ns}")
            schedule_call(env.sim, 0, RECORD, _grid_tick, (self, grid, [grid_prefix + n for n in self.output_names]))
        env.at_end(self._finish)
        return self

    def _bind_streams(self, env: Any) -> None:
        """Subclasses fetch their noise streams here."""

    def _record_grid(self, names: list[str]) -> None:
        """Record the outputs now (one sample of the ``record_grid``)."""
        env = self.env
        now = env.sim.now
        self.advance_to(now)
        rec = env.recorder
        times, values = rec.times, rec.values
        for name, v in zip(names, self._current_output().tolist()):  # tolist: Python floats, in one call
            ts = times.get(name)
            if ts is not None and (rec.enabled is None or name in rec.enabled):  # Recorder.record's fast case
                ts.append(now)
                values[name].append(v)
            else:
                env.record(name, v)

    def _finish(self, t_end: int) -> None:
        if t_end > self._t:
            self.advance_to(t_end)

    def on_input_change(self, callback: Callable[[int], None]) -> Callable[[], None]:
        """Call ``callback(t_ns)`` whenever the predicted future trajectory changes; returns an unsubscriber."""
        self._listeners.append(callback)
        return lambda: self._listeners.remove(callback) if callback in self._listeners else None

    def _notify(self, t: int) -> None:
        if self._listeners:
            for cb in list(self._listeners):
                cb(t)

    def _now(self, t_ns: int | None) -> int:
        if t_ns is not None:
            return int(t_ns)
        return max(int(self.env.now), self._t) if self.env is not None else self._t

    # ---------------------------------------------------------------- disturbances
    def add_disturbance(self, input: int | str, signal: Any) -> None:
        """Add ``signal`` to input ``input`` (the plant sees held input + disturbances).

        ``signal``: a number, a signal spec ``{type: step, at: ..., value: ...}``, a
        :class:`netsim.io.signals.Signal`, an :class:`LTIDisturbance`, or any callable ``t_ns -> value``
        (sampled and held at propagation instants). Must be called before the plant first advances.
        """
        if self._started:
            raise BuildError(f"plant {self.name}: add disturbances before the simulation starts")
        src = _classify(self.input_index(input), signal)
        self._check_source(src)
        self._add_source(src)

    def _add_source(self, src: _Source) -> None:
        src.rng = self._source_stream(src)
        self._sources.append(src)
        self._has_held = any(s.kind == "held" for s in self._sources)
        self._on_sources_changed()

    def _source_stream(self, src: _Source) -> Any:
        """The random stream of a stochastic source once bound (None otherwise)."""
        if self.env is None:
            return None
        if src.kind == "state":
            return self.env.rng(f"plant.{self.name}.state_noise")
        if src.lti is not None and src.lti.noisy:
            return self.env.rng(f"plant.{self.name}.disturbance.{self.input_names[src.index]}")
        return None

    def add_input_noise(self, input: int | str, sigma: float, sample_ns: int) -> None:
        """Add white noise held per sample to input ``input``: ``sigma * N(0, 1)`` drawn at every multiple of
        ``sample_ns`` and held until the next (:class:`~netsim.plant.noise.HeldNoise`, stream
        ``plant.<name>.disturbance.<input>``). A piecewise-constant input: exact propagation stays exact."""
        from netsim.plant.noise import add_held_noise

        add_held_noise(self, self.input_index(input), sigma, sample_ns)

    def add_state_noise(self, states: Sequence[int | str], sigma: float | Sequence[float], sample_ns: int,
                        model: str = "increment") -> None:
        """Add random noise to ``states`` (stream ``plant.<name>.state_noise``, see :mod:`netsim.plant.noise`).

        ``model="increment"``: at every multiple ``k * sample_ns`` (``k >= 1``) each listed state jumps by
        ``sigma_i * sqrt(sample) * N(0, 1)`` (``sigma`` per square root of a second); any plant. ``"rate"``:
        ``sigma_i * N(0, 1)`` drawn at every multiple (``k >= 0``) is held and added to the state's derivative
        (LTI and ``NonlinearPlant`` plants)."""
        if self._started:
            raise BuildError(f"plant {self.name}: add state noise before the simulation starts")
        from netsim.plant.noise import state_noise

        src = state_noise(self.name, [self.state_index(s) for s in states], sigma, sample_ns, model == "rate")
        if src.rate and type(self)._state_rates_changed is Plant._state_rates_changed:
            self._state_rates_changed()  # refuses
        self._add_source(src)

    def set_process_noise(self, process_noise: Any) -> None:
        """Add the random disturbances of a scenario's ``process_noise`` entries before the run: held white
        noise on inputs, random-walk increments on states (:mod:`netsim.plant.noise`).

        LTI and discrete plants also take an intensity (a number, a vector or a matrix) here."""
        from netsim.plant.noise import apply_entries

        apply_entries(self, process_noise)

    def _check_source(self, src: _Source) -> None:
        """Subclasses reject disturbance kinds they cannot propagate."""

    def _state_rates_changed(self) -> None:
        """Subclasses that take held rates on states (``model: rate``) read the new ones here."""
        raise ConfigError(f"plant {self.name} does not take a held rate on its states; use model: increment")

    def _on_sources_changed(self) -> None:
        """Subclasses rebuild augmented models here."""

    def _start(self) -> None:
        """First use: evaluate the disturbances at the start instant."""
        self._started = True
        self._plain = self._is_plain()
        for src in self._sources:
            if (src.kind == "state" or (src.kind == "lti_d" and src.lti.noisy)) and src.rng is None:  # type: ignore[union-attr]
                raise BuildError(f"plant {self.name}: bind(env) before running a noisy disturbance model")
            src.start()
        if any(s.kind == "state" and s.rate for s in self._sources):  # type: ignore[attr-defined]
            self._state_rates_changed()
        self._refresh_sources(self._t)

    def _is_plain(self) -> bool:
        """True when an advance needs no per-call bookkeeping (see ``_plain``); fixed once started."""
        return not self._has_held and not self._record_events

    def _refresh_sources(self, t: int) -> None:
        self._y = None  # the effective input may change
        nxt = NEVER
        for src in self._sources:
            src.refresh(t)
            src.next_ns = src.next_break_after(t)
            nxt = min(nxt, src.next_ns)
        self._next_break = nxt
        self._update_effective_input(t)

    def _break_at(self, t: int) -> bool:
        """Process the disturbance jumps due at ``t``; True when a stochastic update happened."""
        stochastic = False
        for src in self._sources:
            if src.next_ns == t and src.kind == "lti_d":
                src.step_discrete()
                stochastic = stochastic or src.L is not None
            elif src.next_ns == t and src.kind == "state":
                if src.rate:  # type: ignore[attr-defined]
                    src.draw_rates()  # type: ignore[attr-defined]
                    self._state_rates_changed()
                else:
                    self._set_state_now(src.jump(self._state_now()))  # type: ignore[attr-defined]
                stochastic = True
        self._refresh_sources(t)
        return stochastic

    def _piecewise_input(self) -> np.ndarray:
        """Held inputs plus the current values of piecewise/held/discrete-model disturbances."""
        u = self._u.copy()
        for src in self._sources:
            if src.kind in ("piecewise", "held", "lti_d"):
                u[src.index] += src.value
        return u

    def _update_effective_input(self, t: int) -> None:
        """Subclasses store the effective input used by :meth:`_step`."""

    def prediction_barrier(self) -> int:
        """Next instant beyond which the future cannot be predicted from the current state (stochastic
        disturbance updates), or a huge number."""
        return min((s.next_ns for s in self._sources if s.kind in ("lti_d", "state")), default=NEVER)

    def _prediction_window(self, t_first: int, tick: int, max_ticks: int) -> tuple[int, int, int]:
        """``(max_ticks, t_end, barrier)`` for ``predict_exit``: the ticks ``t_first + j*tick`` that lie
        strictly before the prediction barrier (starting the plant first if needed)."""
        if not self._started:
            self._start()
        barrier = self.prediction_barrier()
        t_end = t_first + (max_ticks - 1) * tick
        if barrier <= t_end:
            max_ticks = max(0, -(-(barrier - t_first) // tick))  # ticks strictly before the barrier
            t_end = t_first + (max_ticks - 1) * tick
        return max_ticks, t_end, barrier

    # ---------------------------------------------------------------- propagation
    def advance_to(self, t_ns: int) -> None:
        """Propagate the state to ``t_ns`` under the held inputs (no-op when already there)."""
        t = int(t_ns)
        if not self._started:
            self._start()
        if t <= self._t:
            if t < self._t:
                self._backwards(t)
            return
        stochastic = False
        while True:
            if self._has_held:
                self._refresh_sources(self._t)
            b = self._next_break
            if b > t:
                stochastic |= self._step(t)
                break
            if b > self._t:
                stochastic |= self._step(b)
            stochastic |= self._break_at(b)
            if b == t:
                break
        if self._record_events:
            self.env.record(f"{self.name}.x", self._state_now(), self._t)
        if stochastic:
            self._notify(self._t)

    def _backwards(self, t: int) -> None:
        raise SimulationError(
            f"plant {self.name}: asked for t = {format_time(t)} but the plant is already at "
            f"{format_time(self._t)} (time cannot go backwards)"
        )

    @abc.abstractmethod
    def _step(self, t: int) -> bool:
        """Propagate from ``self._t`` to ``t`` (no jumps in between); True when noise was added."""

    @abc.abstractmethod
    def _output_now(self) -> np.ndarray:
        """The output at the plant's current time."""

    @abc.abstractmethod
    def _state_now(self) -> np.ndarray:
        """The (physical) state at the plant's current time."""

    def _diverged(self, t: int, x: np.ndarray) -> None:
        norm = float(np.sqrt(np.dot(x, x))) if np.all(np.isfinite(x)) else float("nan")
        raise DivergenceError(
            f"plant diverged at t = {to_seconds(t):.9g} s: plant {self.name} state norm {norm:.3g} "
            f"exceeds the divergence bound {self.divergence_bound:.3g} (unstable loop?)",
            t,
        )

    # ---------------------------------------------------------------- sampling and actuation
    def output(self, t_ns: int | None = None) -> np.ndarray:
        """Outputs at ``t_ns`` after advancing the plant there (default: ``env.now``, or the plant's own time
        when that is later or the plant is unbound).

        The array is the caller's own (a copy where the plant caches its output).
        """
        self.advance_to(self._now(None) if t_ns is None else t_ns)  # advance_to takes int(t_ns) as _now does
        y = self._current_output()
        return y.copy() if self._cache_output else y

    def output_value(self, index: int, t_ns: int | None = None) -> float:
        """Output number ``index`` (an int, see :meth:`output_index`) at ``t_ns`` as a float: the value of
        ``float(self.output(t_ns)[index])`` without building an array for the caller."""
        self.advance_to(self._now(None) if t_ns is None else t_ns)
        return float(self._current_output()[index])

    def _current_output(self) -> np.ndarray:
        """The output at the plant's current time. With ``_cache_output`` this is the cached array itself:
        callers read it or copy it, never modify or keep it."""
        if not self._cache_output:
            return self._output_now()
        y = self._y
        if y is None or self._y_t != self._t:
            y = self._y = self._output_now()
            self._y_t = self._t
        return y

    def state(self, t_ns: int | None = None) -> np.ndarray:
        """State (a copy) at ``t_ns`` after advancing the plant there (default as in :meth:`output`)."""
        self.advance_to(self._now(t_ns))
        return self._state_now()

    @property
    def inputs(self) -> np.ndarray:
        """Held inputs as last set (without disturbances)."""
        return self._u.copy()

    def set_input(self, key: int | str, value: float, t_ns: int | None = None) -> None:
        """Advance to ``t_ns`` (default now), then hold input ``key`` at ``value`` (zero-order hold)."""
        # a valid int index is its own input_index (the call is skipped for what DACs pass)
        i = key if type(key) is int and 0 <= key < self.n_inputs else self.input_index(key)
        v = float(value)
        if not math.isfinite(v):
            raise SimulationError(
                f"plant {self.name}: input {self.input_names[i]} set to {value!r} at "
                f"t = {to_seconds(self._now(t_ns)):.9g} s (the controller produced a non-finite value)"
            )
        t = self._now(None) if t_ns is None else int(t_ns)  # self._now(t_ns) without the call
        self.advance_to(t)
        if self._u[i] == v:
            return
        self._u[i] = v
        self._input_changed(t)

    def set_inputs(self, values: Iterable[float], t_ns: int | None = None) -> None:
        """Advance to ``t_ns`` (default now), then hold all inputs at ``values``."""
        u = np.array(list(values), dtype=float)
        if u.shape != (self.n_inputs,):
            raise ConfigError(f"plant {self.name}: set_inputs needs {self.n_inputs} values, got {u.size}")
        if not np.all(np.isfinite(u)):
            raise SimulationError(f"plant {self.name}: non-finite input {u.tolist()}")
        t = self._now(t_ns)
        self.advance_to(t)
        if np.array_equal(u, self._u):
            return
        self._u[:] = u
        self._input_changed(t)

    def _input_changed(self, t: int) -> None:
        self._y = None
        self._update_effective_input(t)
        if self._record_events:
            self.env.record(f"{self.name}.u", self._u, t)
        self._notify(t)

    def set_state(self, x: Any, t_ns: int | None = None) -> None:
        """Advance to ``t_ns`` then overwrite the state (e.g. a disturbance impulse)."""
        t = self._now(t_ns)
        self.advance_to(t)
        self._set_state_now(_vector(f"plant {self.name} state", x, self.n_states))
        self._y = None
        self._notify(t)

    @abc.abstractmethod
    def _set_state_now(self, x: np.ndarray) -> None:
        """Overwrite the physical state at the plant's current time."""


def _grid_tick(item: tuple) -> None:
    """One sample of the ``record_grid`` (a call item of :mod:`netsim.env`: ``(_grid_tick, (plant, grid,
    names))``), then the item of the next sample, ``grid`` ns later. Every sample runs at ``RECORD`` priority
    (:mod:`netsim.env`), after everything else of its instant.

    An exception while sampling (e.g. :class:`~netsim.errors.DivergenceError`) is raised by an item scheduled
    now (NORMAL: it runs next), as a failing simpy process would raise it.
    """
    value = item[1]
    plant = value[0]
    sim = plant.env.sim
    try:
        plant._record_grid(value[2])
    except BaseException as exc:  # noqa: BLE001 - handed to the event loop, as a failing process would
        schedule_call(sim, 0, NORMAL, _raise, exc)
        return
    schedule_call(sim, value[1], RECORD, _grid_tick, value)


def _raise(item: tuple) -> None:
    raise item[1]
