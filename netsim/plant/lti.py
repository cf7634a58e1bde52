"""Linear time-invariant plants: continuous (exact zero-order-hold propagation) and discrete.

:class:`LTIPlant` propagates ``x' = A x + B u`` exactly between events. For a step of length ``h`` the
transition ``[Ad Bd]`` comes from **one** matrix exponential, computed the first time ``h`` occurs and kept
in an LRU cache keyed by the integer step length in nanoseconds::

    expm([[A, B], [0, 0]] h) = [[Ad, Bd], [0, I]]

With process noise of intensity ``Qc`` (``x' = A x + B u + w``, ``E[w(t) w(s)'] = Qc delta(t - s)``) the
same single exponential also yields the exact discrete covariance ``Qd = int_0^h e^{As} Qc e^{A's} ds``
(Van Loan 1978), by the block matrix::

    expm([[-A, Qc, 0], [0, A', 0], [0, B', 0]] h0) -> Ad = F22', Bd = F32', Qd = Ad F12

taken at ``h0 = h / 2**k`` (``|A| h0 <= 1`` keeps the ``-A`` block harmless) and doubled ``k`` times
(``Qd(2h) = Ad Qd Ad' + Qd``, ``Bd(2h) = Ad Bd + Bd``, ``Ad(2h) = Ad Ad``).

:class:`DiscretePlant` updates ``x[k+1] = Ad x[k] + Bd u[k]`` at multiples of ``dt_ns``; ``u[k]`` is the input
held just before the update instant (an input written exactly at an update instant takes effect at the next
update), outputs ``y = Cd x + Dd u`` are held between updates.

The per-event matrix-vector products are :func:`netsim.plant.matvec` bound methods (``@``, bit for bit, with
less call overhead), made once per matrix; the divergence checks' ``x.dot(x)`` only feed a comparison.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from typing import TYPE_CHECKING, Any, Callable, Sequence

import numpy as np

from netsim.errors import ConfigError
from netsim.plant.base import Plant
from netsim.plant.blocks import PartwiseLTI
from netsim.plant.disturbance import _Source, _StateNoise
from netsim.plant.noise import is_entry_form
from netsim.plant.shared import NEVER, _vector, as_matrix, matvec, psd_factor
from netsim.timebase import S

#: Ready steps :meth:`LTIPlant.advance_to` keeps (distinct step lengths) before it clears its memo.
_STEPS_KEPT = 8

if TYPE_CHECKING:
    from netsim.env import SimEnv

__all__ = ["LTIPlant", "zoh_transition", "van_loan"]


def zoh_transition(A: np.ndarray, B: np.ndarray, h_s: float) -> tuple[np.ndarray, np.ndarray]:
    """``(Ad, Bd)`` of ``x' = A x + B u`` over ``h_s`` seconds under a held input (one ``expm``)."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = A * h_s
    M[:n, n:] = B * h_s
    from scipy.linalg import expm  # here, not at the top: validate builds plants and never discretises

    E = expm(M)
    return E[:n, :n], E[:n, n:]


def van_loan(A: np.ndarray, B: np.ndarray, Qc: np.ndarray, h_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Ad, Bd, Qd)`` over ``h_s`` seconds: ZOH transition and exact noise covariance, one ``expm``."""
    n, m = B.shape
    norm = float(np.max(np.sum(np.abs(A), axis=0))) * h_s if n else 0.0
    k = max(0, math.ceil(math.log2(norm))) if norm > 1.0 else 0
    h0 = h_s / 2**k
    H = np.zeros((2 * n + m, 2 * n + m))
    H[:n, :n] = -A * h0
    H[:n, n : 2 * n] = Qc * h0
    H[n : 2 * n, n : 2 * n] = A.T * h0
    H[2 * n :, n : 2 * n] = B.T * h0
    from scipy.linalg import expm  # here, not at the top: validate builds plants and never discretises

    E = expm(H)
    Ad = E[n : 2 * n, n : 2 * n].T.copy()
    Bd = E[2 * n :, n : 2 * n].T.copy()
    Qd = Ad @ E[:n, n : 2 * n]
    for _ in range(k):
        Qd = Ad @ Qd @ Ad.T + Qd
        Bd = Ad @ Bd + Bd
        Ad = Ad @ Ad
    return Ad, Bd, 0.5 * (Qd + Qd.T)


def _shape_lti(A: Any, B: Any, C: Any, D: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    A = as_matrix("A", A)
    n = A.shape[0]
    if A.shape != (n, n):
        raise ConfigError(f"matrix A must be square, got shape {A.shape}")
    b = np.array(B, dtype=float)
    B = as_matrix("B", b.reshape(n, -1) if b.ndim == 1 and n > 1 else b, (n, None))
    m = B.shape[1]
    c = np.array(C, dtype=float)
    C = as_matrix("C", c.reshape(1, -1) if c.ndim == 1 else c, (None, n))
    p = C.shape[0]
    if D is None:
        D = np.zeros((p, m))
    else:
        d = np.array(D, dtype=float)
        if d.ndim < 2 and d.size == p * m:
            d = d.reshape(p, m)
        D = as_matrix("D", d, (p, m))
    return A, B, C, D


def _noise_matrix(process_noise: Any, n: int) -> np.ndarray:
    """An n x n noise matrix from a matrix or a vector (its diagonal); checked positive semi-definite."""
    q = np.array(process_noise, dtype=float)
    Q = as_matrix("process_noise", np.diag(np.atleast_1d(q)) if q.ndim <= 1 else q, (n, n))
    psd_factor("process_noise", Q)
    return Q


class _LTIBase(Plant):
    """Shared machinery of the continuous and discrete LTI plants."""

    _cache_size = 256
    _cache_output = True  # y = C x + D u: a pure function of time, state and effective input

    def _init_shapes(self, A: Any, B: Any, C: Any, D: Any, *, input_names: Sequence[str] | None,
                     output_names: Sequence[str] | None, state_names: Sequence[str] | None, name: str,
                     divergence_bound: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Check the matrices' shapes, set up the common plant state; returns ``(A, B, C, D)`` as arrays."""
        A, B, C, D = _shape_lti(A, B, C, D)
        Plant.__init__(
            self, A.shape[0], B.shape[1], C.shape[0], input_names=input_names, output_names=output_names,
            state_names=state_names, name=name, divergence_bound=divergence_bound,
        )
        return A, B, C, D

    @classmethod
    def _system_arrays(cls, sys: Any) -> tuple[Any, ...]:
        import control

        if isinstance(sys, control.TransferFunction):
            for i in range(sys.noutputs):
                for j in range(sys.ninputs):
                    num = np.trim_zeros(np.atleast_1d(np.asarray(sys.num[i][j], dtype=float)), "f")
                    den = np.trim_zeros(np.atleast_1d(np.asarray(sys.den[i][j], dtype=float)), "f")
                    if num.size > den.size:
                        raise ConfigError(
                            f"transfer function from input {j} to output {i} is not proper "
                            f"(numerator degree {num.size - 1} > denominator degree {den.size - 1}); "
                            "add poles or use a proper model"
                        )
            for arr in (*sys.num, *sys.den):
                for poly in arr:
                    if not np.all(np.isfinite(np.asarray(poly, dtype=float))):
                        raise ConfigError("transfer function contains NaN or Inf coefficients")
            sys = control.ss(sys)
        elif not isinstance(sys, control.StateSpace):
            raise ConfigError(f"expected a python-control StateSpace or TransferFunction, got {type(sys).__name__}")
        names = {
            "input_names": list(sys.input_labels),
            "output_names": list(sys.output_labels),
            "state_names": list(sys.state_labels),
        }
        return np.asarray(sys.A), np.asarray(sys.B), np.asarray(sys.C), np.asarray(sys.D), sys.dt, names


class LTIPlant(PartwiseLTI, _LTIBase):
    """A continuous LTI plant ``x' = A x + B u (+ w)``, ``y = C x + D u``, propagated exactly.

    Parameters
    ----------
    A, B, C, D
        State-space matrices (``D=None``: zero). 1-D ``B``/``C`` are read as a column/row.
    x0
        Initial state (default zeros).
    input_names, output_names, state_names, name, divergence_bound
        See :class:`~netsim.plant.Plant`.
    process_noise
        Intensity ``Qc`` of white process noise on the state (n x n, or a vector for a diagonal), drawn
        from ``env.rng(f"plant.{name}.process")`` with the exact Van Loan covariance per step length; or
        entries ``{inputs|states: [...], sigma: ..., sample: ...}`` (:mod:`netsim.plant.noise`).
    """

    def __init__(
        self,
        A: Any,
        B: Any,
        C: Any,
        D: Any = None,
        *,
        x0: Any = None,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        state_names: Sequence[str] | None = None,
        process_noise: Any = None,
        name: str = "plant",
        divergence_bound: float = 1e12,
    ) -> None:
        A, B, C, D = self._init_shapes(A, B, C, D, input_names=input_names, output_names=output_names,
                                       state_names=state_names, name=name, divergence_bound=divergence_bound)
        n = self.n_states
        self.A, self.B, self.C, self.D = A, B, C, D
        self.x0 = np.zeros(n) if x0 is None else _vector(f"plant {name} x0", x0, n)
        entries = is_entry_form(process_noise)
        if process_noise is None or entries:
            self.Qc = np.zeros((n, n))
        else:
            self.Qc = _noise_matrix(process_noise, n)
        self._rng: np.random.Generator | None = None
        self._build(self.x0)
        if entries:  # held input noise or state increments (netsim.plant.noise)
            self.set_process_noise(process_noise)

    @classmethod
    def from_system(cls, sys: Any, **kwargs: Any) -> "LTIPlant":
        """Build from a continuous python-control ``StateSpace`` or ``TransferFunction`` (SISO or MIMO).

        Signal names default to the system's labels. Raises ConfigError for an improper transfer function
        or a discrete-time system (use :meth:`DiscretePlant.from_system`).
        """
        A, B, C, D, dt, names = cls._system_arrays(sys)
        if dt not in (0, None):
            raise ConfigError(f"system has dt = {dt}: use DiscretePlant.from_system for discrete-time models")
        for key, value in names.items():
            kwargs.setdefault(key, value)
        return cls(A, B, C, D, **kwargs)

    def set_process_noise(self, process_noise: Any) -> None:
        """Set the intensity ``Qc`` of white process noise (n x n, or a vector for a diagonal) before the run;
        entries ``{inputs|states: [...], sigma: ..., sample: ...}`` add held input noise or state increments
        instead (:meth:`Plant.set_process_noise <netsim.plant.Plant.set_process_noise>`)."""
        if is_entry_form(process_noise):
            super().set_process_noise(process_noise)
            return
        self.Qc = _noise_matrix(process_noise, self.n_states)
        self._build(self._zu[: self.n_states].copy())

    # ---------------------------------------------------------------- augmented model
    def _check_source(self, src: _Source) -> None:
        pass  # every kind is supported

    def _on_sources_changed(self) -> None:
        self._build(self._zu[: self.n_states].copy())

    def _build(self, x: np.ndarray) -> None:
        """Append oscillators (sine disturbances) and continuous disturbance models to the state."""
        if self._blocks is not None:
            self._unblock()
            x = self._zu[: self.n_states].copy()
        n, m = self.n_states, self.n_inputs
        blocks_A, z0, q_blocks = [], [x], []
        couple: list[tuple[int | None, np.ndarray]] = []  # (input index, row vector acting on the extra block)
        t = self._t / S
        self._sine_bias = np.zeros(m)
        for src in self._sources:
            if src.kind == "sine":
                sig = src.signal
                w = float(sig.omega)
                blocks_A.append(np.array([[0.0, w], [-w, 0.0]]))
                ang = w * t + float(sig.phase)
                z0.append(np.array([math.sin(ang), math.cos(ang)]))
                couple.append((src.index, np.array([float(sig.amplitude), 0.0])))
                q_blocks.append(np.zeros((2, 2)))
                self._sine_bias[src.index] += float(sig.bias)
            elif src.kind == "lti_c":
                lti = src.lti
                assert lti is not None  # an lti_c source carries its model
                blocks_A.append(lti.A)
                z0.append(lti.x0.copy())
                couple.append((src.index, lti.C[0]))
                q_blocks.append(lti.B @ lti.W @ lti.B.T)
            elif isinstance(src, _StateNoise) and src.rate:  # kind "state"
                k = src.sd.size
                blocks_A.append(np.zeros((k, k)))  # held rates: constant between sample instants
                z0.append(src.rates.copy())
                E = np.zeros((n, k))
                E[src.states, np.arange(k)] = 1.0
                couple.append((None, E))
                q_blocks.append(np.zeros((k, k)))
        nz = n + sum(b.shape[0] for b in blocks_A)
        Af = np.zeros((nz, nz))
        Af[:n, :n] = self.A
        Cf = np.zeros((self.n_outputs, nz))
        Cf[:, :n] = self.C
        Qf = np.zeros((nz, nz))
        Qf[:n, :n] = self.Qc
        k = n
        rate_sources = iter([src for src in self._sources if isinstance(src, _StateNoise) and src.rate])
        for blk, (idx, row), q in zip(blocks_A, couple, q_blocks):
            s = blk.shape[0]
            Af[k : k + s, k : k + s] = blk
            if idx is None:  # held rates on states: dx/dt += E r (no output feed-through)
                Af[:n, k : k + s] = row
                next(rate_sources).offset = k
            else:
                Af[:n, k : k + s] = np.outer(self.B[:, idx], row)
                Cf[:, k : k + s] = np.outer(self.D[:, idx], row)
            Qf[k : k + s, k : k + s] = q
            k += s
        Bf = np.zeros((nz, m))
        Bf[:n] = self.B
        self._Af, self._Bf, self._Cf, self._Qf, self._nz = Af, Bf, Cf, Qf, nz
        self._noisy = bool(np.any(Qf != 0.0))
        self._Cz, self._Du = matvec(Cf), matvec(self.D)  # output products (see _output_now)
        self._zu = np.zeros(nz + m)
        self._zu[:nz] = np.concatenate(z0)
        self._cache: OrderedDict[int, tuple[np.ndarray, np.ndarray | None]] = OrderedDict()
        # the steps of the step lengths in use, ready to apply: (z -> G [z; u] product, L) by length (periodic
        # reads and writes use a few lengths over and over; a run with many lengths clears it now and then)
        self._steps: dict[int, tuple[Callable[[np.ndarray], np.ndarray], np.ndarray | None]] = {}
        self._rows: dict[tuple[int, int], np.ndarray] = {}
        self.expm_count = 0
        self._y = None  # the state was rebuilt
        self._update_effective_input(self._t)

    def _bind_streams(self, env: SimEnv) -> None:
        self._rng = env.rng(f"plant.{self.name}.process")

    def _state_rates_changed(self) -> None:
        """The held rates are states of the augmented model: write the new ones there."""
        for src in self._sources:
            if src.kind == "state" and src.rate:  # type: ignore[attr-defined]
                self._zu[src.offset : src.offset + src.sd.size] = src.rates  # type: ignore[attr-defined]
        self._y = None

    def _start(self) -> None:
        if any(s.kind == "sine" for s in self._sources):
            self._build(self._zu[: self.n_states].copy())  # oscillator phases at the start instant
        if self._noisy and self._rng is None:
            from netsim.errors import BuildError

            raise BuildError(f"plant {self.name}: bind(env) before running a plant with process noise")
        super()._start()
        self._blocks = self._make_blocks(zoh_transition)

    def _update_effective_input(self, t: int) -> None:
        self._zu[self._nz :] = self._piecewise_input() + self._sine_bias

    def transition(self, h_ns: int) -> tuple[np.ndarray, np.ndarray | None]:
        """``(G, L)`` for a step of ``h_ns``: ``z+ = G @ [z; u] + L @ N(0, I)`` (``L`` None without noise)."""
        entry = self._cache.get(h_ns)
        if entry is not None:
            self._cache.move_to_end(h_ns)
            return entry
        h = h_ns / S
        if self._noisy:
            Ad, Bd, Qd = van_loan(self._Af, self._Bf, self._Qf, h)
            L: np.ndarray | None = psd_factor("process noise covariance", Qd)
        else:
            Ad, Bd = zoh_transition(self._Af, self._Bf, h)
            L = None
        self.expm_count += 1
        entry = (np.ascontiguousarray(np.hstack((Ad, Bd))), L)
        self._cache[h_ns] = entry
        if len(self._cache) > self._cache_size:
            self._cache.popitem(last=False)
        return entry

    def transition_cache_info(self) -> dict[str, int]:
        """Number of matrix exponentials taken so far and cached step lengths."""
        return {"expm": self.expm_count, "cached": len(self._cache)}

    # ---------------------------------------------------------------- propagation
    def advance_to(self, t_ns: int) -> None:
        t = int(t_ns)
        if not self._started:
            self._start()
        if self._blocks is not None:
            return self._advance_blocks(t)
        if not (self._plain and self._t <= t < self._next_break):
            return super().advance_to(t)
        # Plant.advance_to's work when no disturbance jump lies in (self._t, t]: one step, then a notification
        # after noise
        h = t - self._t
        if h == 0:
            return
        step = self._steps.get(h)  # periodic sampling: no transition cache look-up, no new bound product
        if step is None:
            G, L = self.transition(h)
            if len(self._steps) >= _STEPS_KEPT:
                self._steps.clear()
            step = self._steps[h] = (matvec(G), L)
        if self._apply(step[0], step[1], t):
            self._notify(t)

    def _step(self, t: int) -> bool:
        G, L = self.transition(t - self._t)
        return self._apply(matvec(G), L, t)

    def _apply(self, Gz: Callable[[np.ndarray], np.ndarray], L: np.ndarray | None, t: int) -> bool:
        """``z+ = G [z; u] (+ L w)`` up to ``t`` (``Gz``: the product ``v -> G v``); True when noise was added."""
        z = Gz(self._zu)
        if L is not None:
            z += matvec(L)(self._rng.standard_normal(self._nz))  # type: ignore[union-attr]
        if not (z.dot(z) <= self._bound2):
            self._diverged(t, z)
        self._zu[: self._nz] = z
        self._t = t
        return L is not None

    def _output_now(self) -> np.ndarray:
        nz = self._nz
        return self._Cz(self._zu[:nz]) + self._Du(self._zu[nz:])  # _Cf @ z + D @ u

    def _state_now(self) -> np.ndarray:
        return self._zu[: self.n_states].copy()

    def _set_state_now(self, x: np.ndarray) -> None:
        self._zu[: self.n_states] = x

    @property
    def augmented_state(self) -> np.ndarray:
        """Plant state followed by the oscillator and disturbance-model states (a copy)."""
        return self._zu[: self._nz].copy()

    # ---------------------------------------------------------------- prediction for exact encoders
    def _rows_for(self, idx: int, tick: int, count: int) -> np.ndarray:
        """Rows ``r_j = [C D][idx] P^j`` (``P`` the tick transition on ``[z; u]``), j < count."""
        key = (idx, tick)
        R = self._rows.get(key)
        if R is None or R.shape[0] < count:
            nz, m = self._nz, self.n_inputs
            G, _ = self.transition(tick)
            P = np.eye(nz + m)
            P[:nz] = G
            R = np.concatenate((self._Cf[idx], self.D[idx]))[None, :]
            while R.shape[0] < count:
                R = np.vstack((R, R @ P))
                P = P @ P
            R = np.ascontiguousarray(R[:count])
            self._rows[key] = R
        return R[:count]

    def predict_exit(
        self, output: int, step: float, count: int, t_first: int, tick: int, max_ticks: int
    ) -> tuple[int | None, int, int]:
        """First tick ``t_first + j*tick`` (j < max_ticks) where ``floor(y/step) != count`` on the noise-free
        trajectory from the current state and held inputs.

        Returns ``(candidate or None, last examined tick, wake-up instant)``; the wake-up instant is the
        last examined tick, or an earlier stochastic disturbance update beyond which nothing is known.
        """
        self._unblock()
        max_ticks, t_end, barrier = self._prediction_window(t_first, tick, max_ticks)
        if max_ticks == 0:
            return None, t_first - tick, barrier
        breaks = sorted(
            {int(b) for s in self._sources if s.kind == "piecewise" and hasattr(s.signal, "breakpoints")
             for b in s.signal.breakpoints(self._t, t_end)}
        )
        nz = self._nz
        R = self._rows_for(output, tick, max_ticks)
        zu = self._zu.copy()
        t = self._t
        k = 0
        bi = 0
        while k < max_ticks:
            tk = t_first + k * tick
            b = breaks[bi] if bi < len(breaks) else NEVER
            if b <= tk:  # switch the input at the jump, then continue
                if b > t:
                    zu[:nz] = self.transition(b - t)[0] @ zu
                    t = b
                zu[nz:] = self._input_at(b)
                bi += 1
                continue
            if tk > t:
                zu[:nz] = self.transition(tk - t)[0] @ zu
                t = tk
            kmax = max_ticks if b == NEVER else min(max_ticks, -(-(b - t_first) // tick))
            j0, chunk = 0, 64  # growing chunks: near edges are found without evaluating the whole horizon
            while j0 < kmax - k:
                j1 = min(kmax - k, j0 + chunk)
                bad = np.floor((R[j0:j1] @ zu) / step) != count
                if bad.any():
                    tc = t_first + (k + j0 + int(np.argmax(bad))) * tick
                    return tc, tc, tc
                j0, chunk = j1, chunk * 4
            k = kmax  # the next pass steps from tk straight to the jump
        last = t_first + (max_ticks - 1) * tick
        return None, last, barrier if barrier < NEVER and barrier <= last + tick else last

    def _input_at(self, t: int) -> np.ndarray:
        u = self._u + self._sine_bias
        for s in self._sources:
            if s.kind == "piecewise":
                u[s.index] += float(s.signal(t))
            elif s.kind in ("held", "lti_d"):
                u[s.index] += s.value
        return u
