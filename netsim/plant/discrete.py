"""Discrete-time LTI plants: ``x[k+1] = Ad x[k] + Bd u[k]`` updated at multiples of ``dt_ns``, outputs held in between."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from netsim.errors import ConfigError
from netsim.plant.disturbance import _Source
from netsim.plant.lti import _LTIBase, _noise_matrix
from netsim.plant.noise import is_entry_form
from netsim.plant.shared import NEVER, _vector, matvec, psd_factor
from netsim.timebase import from_seconds

if TYPE_CHECKING:
    from netsim.env import SimEnv

__all__ = ["DiscretePlant"]


class DiscretePlant(_LTIBase):
    """A discrete-time LTI plant updated at multiples of ``dt_ns`` (plus ``offset_ns``).

    ``x[k+1] = Ad x[k] + Bd u[k] (+ w[k])``, ``y = Cd x + Dd u``; ``u[k]`` is the input held just before the
    update instant; outputs are held between updates. Disturbances are sampled at the update instants
    (sinusoids and discrete disturbance models included).

    Parameters
    ----------
    Ad, Bd, Cd, Dd
        Discrete state-space matrices.
    dt_ns
        Update period in nanoseconds.
    process_noise
        Covariance of ``w[k]`` (n x n or a diagonal vector), drawn from ``plant.<name>.process``.
    offset_ns
        Phase of the update grid (updates at ``offset_ns + k dt_ns``).
    """

    def __init__(
        self,
        Ad: Any,
        Bd: Any,
        Cd: Any,
        Dd: Any,
        dt_ns: int,
        *,
        x0: Any = None,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        state_names: Sequence[str] | None = None,
        process_noise: Any = None,
        offset_ns: int = 0,
        name: str = "plant",
        divergence_bound: float = 1e12,
    ) -> None:
        A, B, C, D = self._init_shapes(Ad, Bd, Cd, Dd, input_names=input_names, output_names=output_names,
                                       state_names=state_names, name=name, divergence_bound=divergence_bound)
        if int(dt_ns) <= 0:
            raise ConfigError(f"plant {name}: dt_ns must be positive, got {dt_ns}")
        self.Ad, self.Bd, self.Cd, self.Dd = A, B, C, D
        # the per-update products Ad @ x, Bd @ u, Cd @ x, Dd @ u (the matrices are fixed once built)
        self._Ax, self._Bu, self._Cx, self._Du = matvec(A), matvec(B), matvec(C), matvec(D)
        self.dt_ns = int(dt_ns)
        self.offset_ns = int(offset_ns)
        n = self.n_states
        self._x = np.zeros(n) if x0 is None else _vector(f"plant {name} x0", x0, n)
        self._L: np.ndarray | None = None
        self._Lw: Any = None  # product L @ w, with _L
        if process_noise is not None:
            self.set_process_noise(process_noise)
        self._rng: np.random.Generator | None = None
        self._ueff = np.zeros(self.n_inputs)
        self._sines: tuple | None = None  # sine disturbance sources (cached once started)
        self._next_update = NEVER  # first update instant after self._t (set when started)

    def set_process_noise(self, process_noise: Any) -> None:
        """Set the covariance of the additive state noise per step (n x n, or a vector) before the run;
        entries ``{inputs|states: [...], sigma: ..., sample: ...}`` add held input noise or state increments
        instead (:meth:`Plant.set_process_noise <netsim.plant.Plant.set_process_noise>`)."""
        if is_entry_form(process_noise):
            super().set_process_noise(process_noise)
            return
        Q = _noise_matrix(process_noise, self.n_states)
        self._L = psd_factor("process_noise", Q) if np.any(Q != 0) else None
        self._Lw = None if self._L is None else matvec(self._L)

    @classmethod
    def from_system(cls, sys: Any, **kwargs: Any) -> "DiscretePlant":
        """Build from a discrete python-control system (``sys.dt > 0``); ``dt_ns`` comes from ``sys.dt``."""
        A, B, C, D, dt, names = cls._system_arrays(sys)
        if dt in (0, None) or dt is True:
            raise ConfigError("system is continuous (or has unspecified dt): use LTIPlant.from_system")
        for key, value in names.items():
            kwargs.setdefault(key, value)
        return cls(A, B, C, D, from_seconds(float(dt)), **kwargs)

    def _check_source(self, src: _Source) -> None:
        if src.kind == "lti_c":
            raise ConfigError(
                f"plant {self.name}: a continuous disturbance model cannot drive a discrete plant; "
                "give the LTIDisturbance a dt_ns"
            )

    def _bind_streams(self, env: SimEnv) -> None:
        self._rng = env.rng(f"plant.{self.name}.process")

    def _start(self) -> None:
        if self._L is not None and self._rng is None:
            from netsim.errors import BuildError

            raise BuildError(f"plant {self.name}: bind(env) before running a plant with process noise")
        super()._start()
        self._sines = tuple(s for s in self._sources if s.kind == "sine")
        self._next_update = self._update_times(self._t, NEVER).start

    def _update_effective_input(self, t: int) -> None:
        self._ueff = self._piecewise_input()

    def _input_now(self, t: int) -> np.ndarray:
        """The input the plant sees at ``t``: ``_ueff`` plus the sine disturbances at ``t``.

        Once the plant has started, ``_sines`` holds the sine sources and the hot paths skip this call when
        it is ``()`` (the input is then ``_ueff`` itself); before, it is None (not known yet).
        """
        u = self._ueff
        sines = self._sines
        if sines is None:  # sources are fixed once the plant has started
            sines = tuple(s for s in self._sources if s.kind == "sine")
            if self._started:
                self._sines = sines
        if sines:
            u = u.copy()
            for s in sines:
                u[s.index] += float(s.signal(t))
        return u

    def _update_times(self, t0: int, t1: int) -> range:
        """Update instants in ``(t0, t1]``."""
        dt, off = self.dt_ns, self.offset_ns
        first = off + ((t0 - off) // dt + 1) * dt
        return range(first, t1 + 1, dt)

    def advance_to(self, t_ns: int) -> None:
        t = int(t_ns)
        if not (self._plain and self._t <= t < self._next_break):
            return super().advance_to(t)
        # Plant.advance_to's work when no disturbance jump lies in (self._t, t]: _step(t), then a notification
        # after noise; with no update instant in (self._t, t] that step only moves the clock
        if t < self._next_update:
            self._t = t
        elif self._step(t):
            self._notify(t)

    def _step(self, t: int) -> bool:
        noisy = False
        tk = self._next_update  # first update instant in (self._t, t], if any
        if tk <= t:
            x = self._x
            Ax, Bu, Lw, bound2, dt = self._Ax, self._Bu, self._Lw, self._bound2, self.dt_ns
            while tk <= t:
                # x = Ad @ x + Bd @ u (+ L @ w): the update at tk integrates the input held over (tk - dt, tk],
                # a sine sampled at its start (without sines that input is _ueff, as _input_now returns it)
                x = Ax(x) + Bu(self._ueff if self._sines == () else self._input_now(tk - dt))
                if Lw is not None:
                    x = x + Lw(self._rng.standard_normal(self.n_states))  # type: ignore[union-attr]
                    noisy = True
                if not (x.dot(x) <= bound2):
                    self._diverged(tk, x)
                tk += dt
            self._x = x
            self._next_update = tk
        self._t = t
        return noisy

    def _output_now(self) -> np.ndarray:
        # without sines the input is _ueff, as _input_now returns it
        u = self._ueff if self._sines == () else self._input_now(self._t)
        return self._Cx(self._x) + self._Du(u)  # Cd @ x + Dd @ u

    def _state_now(self) -> np.ndarray:
        return self._x.copy()

    def _set_state_now(self, x: np.ndarray) -> None:
        self._x = x.copy()

    def predict_exit(
        self, output: int, step: float, count: int, t_first: int, tick: int, max_ticks: int
    ) -> tuple[int | None, int, int]:
        """As :meth:`LTIPlant.predict_exit`: the output only changes at updates and input jumps."""
        max_ticks, t_end, barrier = self._prediction_window(t_first, tick, max_ticks)
        if max_ticks == 0:
            return None, t_first - tick, barrier
        piecewise = [s for s in self._sources if s.kind == "piecewise"]
        changes = set(self._update_times(self._t, t_end))
        for s in piecewise:
            changes.update(int(b) for b in getattr(s.signal, "breakpoints", lambda a, b: [])(self._t, t_end))
        has_sine = any(s.kind == "sine" for s in self._sources)
        x = self._x.copy()
        c, d = self.Cd[output], self.Dd[output]

        def u_at(t: int, t_sine: int | None = None) -> np.ndarray:
            """Input with piecewise sources at ``t`` and sines at ``t_sine`` (default ``t``)."""
            u = self._u.copy()
            for s in self._sources:
                if s.kind == "piecewise":
                    u[s.index] += float(s.signal(t))
                elif s.kind == "sine":
                    u[s.index] += float(s.signal(t if t_sine is None else t_sine))
                elif s.kind in ("held", "lti_d"):
                    u[s.index] += s.value
            return u

        u = u_at(self._t)
        t = self._t
        k = 0
        for tc in sorted(changes) + [NEVER]:
            # ticks before the next change see the current x and u
            while k < max_ticks and t_first + k * tick < tc:
                tk = t_first + k * tick
                y = c @ x + d @ (u_at(tk) if has_sine else u)
                if math.floor(y / step) != count:
                    return tk, tk, tk
                k += 1
            if k >= max_ticks:
                break
            if tc in self._update_times(t, tc):
                # as in _step: the input held over the step, sines sampled at the step's start
                x = self.Ad @ x + self.Bd @ (u_at(t, tc - self.dt_ns) if has_sine else u)
            u = u_at(tc)
            t = tc
        last = t_first + (max_ticks - 1) * tick
        return None, last, barrier if barrier < NEVER and barrier <= last + tick else last
