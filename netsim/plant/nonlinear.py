"""Nonlinear plants integrated between events (by :func:`scipy.integrate.solve_ivp`, or by fixed-step RK4: see
:mod:`netsim.plant.integrator`), with mode switching.

``f(t, x, u, params) -> dx/dt`` and ``h(t, x, u, params) -> y`` use python-control's vocabulary (``t`` in
seconds). Between two events the plant is integrated from its current state; inputs are held.

Discontinuous dynamics
----------------------
A right-hand side that jumps with the state (Coulomb friction at ``v = 0``) makes an adaptive integrator
crawl with tiny steps, or chatter forever around the switching surface. Two mechanisms avoid that:

* ``events``: guard functions ``g(t, x, u, params)``; integration stops at their zero crossings and
  restarts, so no step straddles the discontinuity.
* ``modes``: a small hybrid automaton. Each :class:`Mode` has its own right-hand side and guards; when a
  guard crosses zero (or the input changes), ``select_mode(t, x, u, params)`` picks the next mode and may
  return a projected state (``("stick", x_with_v_0)``). :func:`stick_slip_modes` builds the usual
  three-mode friction model (slip forward, slip backward, stick while the applied force stays below
  static friction) so the velocity is held exactly 0 while stuck.
"""

from __future__ import annotations

import math
from typing import Any, Callable, Sequence

import numpy as np
from scipy.integrate import solve_ivp

from netsim.errors import ConfigError, SimulationError
from netsim.plant.base import Plant
from netsim.plant.disturbance import _Source
from netsim.plant.integrator import Rk4Buffers, RkSegments, hermite, rk4_steps, steps_for
from netsim.plant.modes import Fn, Guard, Mode, stick_slip_modes
from netsim.plant.shared import NEVER, _vector
from netsim.timebase import S

__all__ = ["NonlinearPlant", "Mode", "Guard", "stick_slip_modes"]

#: Mode switches allowed at one instant before the plant reports Zeno behaviour.
MAX_SWITCHES_PER_INSTANT = 20


class _SwitchCount:
    """Mode switches at one instant so far (Zeno detection of :meth:`NonlinearPlant._guard_fired`)."""

    __slots__ = ("here", "last_t")

    def __init__(self) -> None:
        self.here = 0
        self.last_t: float | None = None


class NonlinearPlant(Plant):
    """A nonlinear plant ``x' = f(t, x, u, params)``, ``y = h(t, x, u, params)``.

    Parameters
    ----------
    f, h
        Dynamics and output functions (``t`` in seconds); ``h`` returns ``n_outputs`` values.
    n_states, n_inputs, n_outputs
        Dimensions.
    params
        Passed unchanged to ``f``, ``h`` and guards.
    x0
        Initial state (default zeros).
    events
        Guards (functions or :class:`Guard`) at whose zero crossings the integration restarts.
    modes, select_mode, initial_mode
        Hybrid dynamics: see the module docstring and :func:`stick_slip_modes`. ``select_mode`` is called at
        every restart (input change, disturbance jump, guard crossing) and may return ``name`` or
        ``(name, x)``.
    method, rtol, atol, max_step
        solve_ivp settings (defaults RK45, 1e-8, 1e-10, unbounded, ``max_step`` in seconds); ``method="rk4"``
        integrates with fixed RK4 steps of at most ``max_step`` instead (required then; see
        :meth:`set_integrator`).
    """

    def __init__(
        self,
        f: Fn,
        h: Fn,
        n_states: int,
        n_inputs: int,
        n_outputs: int,
        *,
        params: Any = None,
        x0: Any = None,
        events: Sequence[Fn | Guard] | None = None,
        modes: dict[str, Mode] | None = None,
        select_mode: Callable[..., Any] | None = None,
        initial_mode: str | None = None,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        state_names: Sequence[str] | None = None,
        name: str = "plant",
        method: str = "RK45",
        rtol: float = 1e-8,
        atol: float = 1e-10,
        max_step: float | None = None,
        divergence_bound: float = 1e12,
    ) -> None:
        super().__init__(
            n_states, n_inputs, n_outputs, input_names=input_names, output_names=output_names,
            state_names=state_names, name=name, divergence_bound=divergence_bound,
        )
        if not callable(f) or not callable(h):
            raise ConfigError(f"plant {name}: f and h must be callables f(t, x, u, params)")
        self.f, self.h, self.params = f, h, params
        self._x = np.zeros(self.n_states) if x0 is None else _vector(f"plant {name} x0", x0, self.n_states)
        common = tuple(g if isinstance(g, Guard) else Guard(g) for g in (events or ()))
        if modes:
            if select_mode is None:
                raise ConfigError(f"plant {name}: modes need a select_mode(t, x, u, params) function")
            self.modes = {k: Mode(m.f, tuple(m.guards) + common) for k, m in modes.items()}
        else:
            self.modes = {"default": Mode(None, common)}
        self.select_mode = select_mode
        self.mode = initial_mode if initial_mode is not None else next(iter(self.modes))
        if self.mode not in self.modes:
            raise ConfigError(f"plant {name}: initial_mode {self.mode!r} is not one of {list(self.modes)}")
        self.method, self.rtol, self.atol = "RK45", 1e-8, 1e-10
        self.max_step = math.inf
        self._rk4_ns: int | None = None  # the largest RK4 step (ns) when integrating with RK4
        self._rk4_buf = Rk4Buffers(self.n_states)
        if method.lower() == "rk4":
            self.set_integrator("rk4", max_step=max_step)
        else:
            self.set_integrator("solve_ivp", solver=method, rtol=rtol, atol=atol, max_step=max_step)
        self.rhs_evaluations = 0
        self.mode_switches = 0
        self._ueff = np.zeros(self.n_inputs)
        self._rate: np.ndarray | None = None  # held state-noise rates (netsim.plant.noise), if any
        self._check_output(self._x)

    def set_integrator(self, method: str = "solve_ivp", *, max_step: float | None = None, solver: str | None = None,
                       rtol: float | None = None, atol: float | None = None) -> None:
        """Choose how the plant is integrated between events (``plant.integrator`` in a scenario).

        Parameters
        ----------
        method
            ``"solve_ivp"`` (:func:`scipy.integrate.solve_ivp`, one call per segment) or ``"rk4"`` (classical
            Runge-Kutta in fixed steps, :mod:`netsim.plant.integrator`).
        max_step
            Seconds. RK4: the largest step (required; at least 1 ns). solve_ivp: a bound on its step (default
            unbounded).
        solver, rtol, atol
            solve_ivp's method name and tolerances (defaults RK45, 1e-8, 1e-10); not taken with RK4.
        """
        if self._started:
            raise ConfigError(f"plant {self.name}: choose the integrator before the simulation starts")
        if method == "rk4":
            if max_step is None or not (max_step > 0 and math.isfinite(max_step)):
                raise ConfigError(f"plant {self.name}: integrator rk4 needs a finite positive max_step, got {max_step}")
            if solver is not None or rtol is not None or atol is not None:
                raise ConfigError(f"plant {self.name}: solver, rtol and atol apply to solve_ivp only, not to rk4")
            step_ns = int(round(max_step * S))
            if step_ns < 1:
                raise ConfigError(f"plant {self.name}: integrator rk4 max_step {max_step} s is below 1 ns")
            self._rk4_ns, self.max_step = step_ns, step_ns / S
            self.method, self._rk_segments = "rk4", None
            return
        if method != "solve_ivp":
            raise ConfigError(f"plant {self.name}: integrator method must be 'solve_ivp' or 'rk4', got {method!r}")
        rtol = self.rtol if rtol is None else float(rtol)
        atol = self.atol if atol is None else float(atol)
        if not (rtol > 0 and atol > 0):
            raise ConfigError(f"plant {self.name}: solve_ivp tolerances must be positive, got rtol {rtol}, atol {atol}")
        self._rk4_ns = None
        self.method = "RK45" if solver is None else str(solver)
        self.rtol, self.atol = rtol, atol
        self.max_step = math.inf if max_step is None else float(max_step)
        if not self.max_step > 0:
            raise ConfigError(f"plant {self.name}: solve_ivp max_step must be positive, got {max_step}")
        self._rk_segments = RkSegments.make(self.method, self.n_states, rtol, atol, self.max_step)

    def _check_output(self, x: np.ndarray) -> None:
        y = np.atleast_1d(np.asarray(self.h(0.0, x, np.zeros(self.n_inputs), self.params), dtype=float))
        if y.shape != (self.n_outputs,):
            raise ConfigError(f"plant {self.name}: h returns {y.size} values, n_outputs is {self.n_outputs}")

    def _check_source(self, src: _Source) -> None:
        if src.kind == "lti_c":
            raise ConfigError(
                f"plant {self.name}: continuous disturbance models need an LTI plant; give the LTIDisturbance "
                "a dt_ns (discrete model) instead"
            )

    def _state_rates_changed(self) -> None:
        """Held rates on states (``model: rate``): added to the right-hand side of every mode until the next."""
        rate = np.zeros(self.n_states)
        for src in self._sources:
            if src.kind == "state" and src.rate:  # type: ignore[attr-defined]
                rate[src.states] += src.rates  # type: ignore[attr-defined]
        self._rate = rate

    def _update_effective_input(self, t: int) -> None:
        self._ueff = self._piecewise_input()
        if self._started and self.select_mode is not None:
            self._reselect(t / S)

    def _input_fn(self, base: np.ndarray) -> Callable[[float], np.ndarray]:
        sines = [s for s in self._sources if s.kind == "sine"]
        if not sines:
            return lambda t: base

        def u_of(t: float) -> np.ndarray:
            u = base.copy()
            for s in sines:
                sig = s.signal
                u[s.index] += sig.bias + sig.amplitude * math.sin(sig.omega * t + sig.phase)
            return u

        return u_of

    def _reselect(self, t: float) -> None:
        choice = self.select_mode(t, self._x, self._input_fn(self._ueff)(t), self.params)  # type: ignore[misc]
        name, x = (choice, self._x) if isinstance(choice, str) else choice
        if name not in self.modes:
            raise SimulationError(f"plant {self.name}: select_mode returned unknown mode {name!r}")
        if name != self.mode:
            self.mode_switches += 1
        self.mode = name
        self._x = np.asarray(x, dtype=float).copy()

    def _start(self) -> None:
        super()._start()
        if self.select_mode is not None:
            self._reselect(self._t / S)

    # ---------------------------------------------------------------- integration
    def _integrate(
        self,
        t0: float,
        t1: float,
        x: np.ndarray,
        mode: str,
        u_of: Callable[[float], np.ndarray],
        extra: Sequence[Guard] = (),
    ) -> tuple[float, np.ndarray, str, bool]:
        """Integrate over ``[t0, t1]`` seconds with mode switching; stop early at an ``extra`` guard.

        Returns ``(t_reached, x, mode, stopped_by_extra)``.
        """
        if self._rk4_ns is not None:
            return self._integrate_rk4(t0, t1, x, mode, u_of, extra)
        t = t0
        zeno = _SwitchCount()
        params = self.params
        rate = self._rate
        while t < t1:
            m = self.modes[mode]
            f = m.f or self.f

            def rhs(tt: float, xx: np.ndarray, f: Fn = f) -> np.ndarray:
                self.rhs_evaluations += 1
                if rate is None:
                    return f(tt, xx, u_of(tt), params)
                return np.asarray(f(tt, xx, u_of(tt), params), dtype=float) + rate  # held state noise rates

            guards = list(m.guards) + list(extra)
            evs = []
            for g in guards:
                def ev(tt: float, xx: np.ndarray, g: Guard = g) -> float:
                    return float(g.fn(tt, xx, u_of(tt), params))

                ev.terminal = True  # type: ignore[attr-defined]
                ev.direction = g.direction  # type: ignore[attr-defined]
                evs.append(ev)
            sol: Any  # solve_ivp's result, or RkSegments' with the fields read below but the events
            try:
                if not evs and self._rk_segments is not None:  # solve_ivp's steps without solve_ivp (integrator.py)
                    sol = self._rk_segments.solve(rhs, t, t1, x)
                else:
                    sol = solve_ivp(rhs, (t, t1), x, method=self.method, rtol=self.rtol, atol=self.atol,
                                    max_step=self.max_step, events=evs or None)
            except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
                raise SimulationError(f"plant {self.name}: integrator failed at t = {t:.12g} s: {exc}") from exc
            t_new = float(sol.t[-1])
            x = sol.y[:, -1]
            if not (x @ x <= self._bound2):
                self._diverged(int(round(t_new * S)), x)
            if sol.status == -1:
                raise SimulationError(f"plant {self.name}: integrator failed at t = {t_new:.12g} s: {sol.message}")
            if sol.status != 1:
                return t1, x, mode, False
            fired = [i for i, te in enumerate(sol.t_events) if len(te)]
            i = fired[0]
            t_new = float(sol.t_events[i][0])
            x = np.asarray(sol.y_events[i][0], dtype=float)
            if i >= len(m.guards):
                return t_new, x, mode, True
            mode, x = self._guard_fired(t_new, x, mode, u_of, zeno)
            t = t_new
        return t1, x, mode, False

    def _guard_fired(
        self, t_new: float, x: np.ndarray, mode: str, u_of: Callable[[float], np.ndarray], zeno: "_SwitchCount"
    ) -> tuple[str, np.ndarray]:
        """The mode (and state) after a mode guard fired at ``t_new``; refuses endless switching at one instant."""
        if zeno.last_t is not None and t_new - zeno.last_t <= 1e-12 * max(1.0, abs(t_new)):
            zeno.here += 1
            if zeno.here > MAX_SWITCHES_PER_INSTANT:
                raise SimulationError(
                    f"plant {self.name}: modes switch endlessly at t = {t_new:.9g} s (Zeno behaviour); "
                    "check the guards and select_mode"
                )
        else:
            zeno.here = 0
        zeno.last_t = t_new
        if self.select_mode is not None:
            choice = self.select_mode(t_new, x, u_of(t_new), self.params)
            new, x = (choice, x) if isinstance(choice, str) else choice
            x = np.asarray(x, dtype=float)
            if new not in self.modes:
                raise SimulationError(f"plant {self.name}: select_mode returned unknown mode {new!r}")
            if new != mode:
                self.mode_switches += 1
            mode = new
        return mode, x

    def _integrate_rk4(
        self,
        t0: float,
        t1: float,
        x: np.ndarray,
        mode: str,
        u_of: Callable[[float], np.ndarray],
        extra: Sequence[Guard] = (),
    ) -> tuple[float, np.ndarray, str, bool]:
        """:meth:`_integrate` by fixed RK4 steps of at most ``self._rk4_ns``: each stretch between mode switches
        is cut into equal steps; a guard that changes sign over a step is located on the step's cubic Hermite
        interpolant (:func:`netsim.plant.integrator.hermite`) by bisection to 1 ns."""
        params, rate, buf, max_ns = self.params, self._rate, self._rk4_buf, self._rk4_ns
        assert max_ns is not None
        x = np.asarray(x, dtype=float)
        t = t0
        zeno = _SwitchCount()
        while t < t1:
            m = self.modes[mode]
            f = m.f or self.f
            if rate is None:
                def rhs(tt: float, xx: np.ndarray, f: Fn = f) -> Any:
                    return f(tt, xx, u_of(tt), params)
            else:
                def rhs(tt: float, xx: np.ndarray, f: Fn = f) -> Any:
                    return np.asarray(f(tt, xx, u_of(tt), params), dtype=float) + rate  # held state noise rates

            guards = m.guards + tuple(extra)
            n = steps_for(int(round((t1 - t) * S)), max_ns)
            h = (t1 - t) / n
            if not guards:
                x = self._rk4(rhs, t, x, h, n, t1)
                return t1, x, mode, False
            g_prev = [float(g.fn(t, x, u_of(t), params)) for g in guards]
            hit = None
            for i in range(n):
                ta = t + i * h
                tb = t1 if i == n - 1 else t + (i + 1) * h
                xb = self._rk4(rhs, ta, x, tb - ta, 1, tb)
                g_new = [float(g.fn(tb, xb, u_of(tb), params)) for g in guards]
                hit = self._first_crossing(rhs, guards, g_prev, g_new, ta, x, tb, xb, u_of)
                if hit is not None:
                    break
                x, g_prev = xb, g_new
            if hit is None:
                return t1, x, mode, False
            t_new, x, j = hit
            if j >= len(m.guards):
                return t_new, x, mode, True
            mode, x = self._guard_fired(t_new, x, mode, u_of, zeno)
            t = t_new
        return t1, x, mode, False

    def _rk4(self, rhs: Callable[[float, np.ndarray], Any], t: float, x: np.ndarray, h: float, n: int,
             t_end: float) -> np.ndarray:
        """``n`` RK4 steps of ``h`` from ``(t, x)``, with the divergence check at ``t_end``."""
        try:
            x = rk4_steps(rhs, t, x, h, n, self._rk4_buf)
        except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
            raise SimulationError(f"plant {self.name}: integrator failed at t = {t:.12g} s: {exc}") from exc
        self.rhs_evaluations += 4 * n
        if not (x @ x <= self._bound2):
            self._diverged(int(round(t_end * S)), x)
        return x

    def _first_crossing(
        self, rhs: Callable[[float, np.ndarray], Any], guards: Sequence[Guard], g_prev: list[float],
        g_new: list[float], ta: float, xa: np.ndarray, tb: float, xb: np.ndarray, u_of: Callable[[float], np.ndarray],
    ) -> tuple[float, np.ndarray, int] | None:
        """The earliest guard crossing over the step ``[ta, tb]`` as ``(t, x, guard index)``, or None.

        A guard crosses when it leaves a strictly positive (negative) value for a non-positive (non-negative)
        one in its ``direction``; the instant is bisected on the Hermite interpolant to 1 ns and the state there
        (just past the crossing) returned."""
        fired = [j for j, (g0, g1) in enumerate(zip(g_prev, g_new))
                 if (guards[j].direction >= 0 and g0 < 0 <= g1) or (guards[j].direction <= 0 and g0 > 0 >= g1)]
        if not fired:
            return None
        h = tb - ta
        f0 = np.array(rhs(ta, xa), dtype=float)
        f1 = np.array(rhs(tb, xb), dtype=float)
        self.rhs_evaluations += 2
        params = self.params
        best: tuple[float, np.ndarray, int] | None = None
        for j in fired:
            g, lo, hi = guards[j].fn, 0.0, 1.0
            side = g_prev[j] > 0
            while (hi - lo) * h > 1e-9:
                mid = 0.5 * (lo + hi)
                tm = ta + mid * h
                if (float(g(tm, hermite(xa, f0, xb, f1, h, mid), u_of(tm), params)) > 0) == side:
                    lo = mid
                else:
                    hi = mid
            te = tb if hi >= 1.0 else ta + hi * h
            if best is None or te < best[0]:
                best = (te, xb.copy() if hi >= 1.0 else hermite(xa, f0, xb, f1, h, hi), j)
        return best

    def _step(self, t: int) -> bool:
        _, x, mode, _ = self._integrate(self._t / S, t / S, self._x, self.mode, self._input_fn(self._ueff))
        self._x, self.mode, self._t = np.asarray(x, dtype=float), mode, t
        return False

    def _output_now(self) -> np.ndarray:
        ts = self._t / S
        return np.atleast_1d(np.asarray(self.h(ts, self._x, self._input_fn(self._ueff)(ts), self.params), float))

    def _state_now(self) -> np.ndarray:
        return self._x.copy()

    def _set_state_now(self, x: np.ndarray) -> None:
        self._x = x.copy()
        if self.select_mode is not None:
            self._reselect(self._t / S)

    # ---------------------------------------------------------------- prediction for exact encoders
    def predict_exit(
        self, output: int, step: float, count: int, t_first: int, tick: int, max_ticks: int
    ) -> tuple[int | None, int, int]:
        """Candidate tick where ``floor(y/step)`` may leave ``count``: the first band crossing found by
        solve_ivp events, snapped up to the tick grid (the encoder verifies it on the plant itself)."""
        max_ticks, t_end, barrier = self._prediction_window(t_first, tick, max_ticks)
        if max_ticks == 0:
            return None, t_first - tick, barrier
        lo, hi = count * step, (count + 1) * step
        p = self.params

        def y_of(tt: float, xx: np.ndarray, uu: np.ndarray) -> float:
            return float(np.atleast_1d(self.h(tt, xx, uu, p))[output])

        band = (
            Guard(lambda tt, xx, uu, _p: y_of(tt, xx, uu) - lo, -1.0),
            Guard(lambda tt, xx, uu, _p: y_of(tt, xx, uu) - hi, +1.0),
        )
        breaks = sorted(
            {int(b) for s in self._sources if s.kind == "piecewise" and hasattr(s.signal, "breakpoints")
             for b in s.signal.breakpoints(self._t, t_end)}
        ) + [t_end]
        switches = self.mode_switches  # predictions do not count as the plant's own mode switches
        try:
            return self._predict(y_of, band, breaks, step, count, t_first, tick, max_ticks, barrier)
        finally:
            self.mode_switches = switches

    def _predict(self, y_of: Callable[..., float], band: tuple[Guard, Guard], breaks: list[int], step: float,
                 count: int, t_first: int, tick: int, max_ticks: int, barrier: int) -> tuple[int | None, int, int]:
        t, x, mode = self._t, self._x.copy(), self.mode
        u = self._ueff.copy()
        y_now = y_of(t / S, x, self._input_fn(u)(t / S))
        if math.floor(y_now / step) != count:  # left the band before the first unexamined tick
            return t_first, t_first, t_first
        for b in breaks:
            if b > t:
                te, x, mode, hit = self._integrate(t / S, b / S, x, mode, self._input_fn(u), band)
                if hit:
                    tns = int(round(te * S))
                    j = max(0, -(-(tns - t_first) // tick))
                    cand = t_first + j * tick
                    if j < max_ticks:
                        return cand, cand, cand
                    break
                t = b
            u = self._u.copy()
            for s in self._sources:
                if s.kind == "piecewise":
                    u[s.index] += float(s.signal(b))
                elif s.kind in ("held", "lti_d"):
                    u[s.index] += s.value
        last = t_first + (max_ticks - 1) * tick
        return None, last, barrier if barrier < NEVER and barrier <= last + tick else last
