"""The cart as a netsim plant (registered as kind ``plant``, name ``cart``).

Model (Henningsson & Cervin, section II-B)::

    p' = v
    v' = u + u_bias - F(p) sign(v) [- v / Td]      u = Ku sat(uV),  Ku = 25.5 m/s^2,  |uV| <= 1

Inputs ``uV`` (motor command, full-voltage units; saturated here at +-1) and ``u_bias`` (an extra
disturbance acceleration in m/s^2, default 0, for scenario disturbances); outputs and states ``p`` (m) and
``v`` (m/s). ``Td`` (the paper's identified 0.23 s velocity time constant) is off by default, as in the
paper's ``1/Td ~ 0`` design model. Friction: :class:`netsim.models.cart.friction.Friction` -- a Coulomb level
varying along the track, faster at the far end, drawn from the stream ``plant.cart.friction``.

Integration is exact in closed form (:mod:`netsim.models.cart.dynamics`): the friction *level* is held on a fixed
time grid (``friction_step``, 1 ms by default, i.e. the control period: the cart moves < 1 mm per step at
0.8 m/s while the shortest friction wavelength is 0.33 m in the default model, 17 mm in ``modes6``), the
sign follows the velocity exactly, stops and breakaway are handled analytically. Because the level is
tied to the grid and not to the instants at which the plant happens to be sampled, polling and exact
encoders see the same trajectory. The plant implements ``predict_exit`` so the exact-mode encoder can sleep
until the next edge.

Why not ``NonlinearPlant``: its ``solve_ivp`` steps cost about a millisecond per input change (1000 per
simulated second here) while the closed form costs tens of microseconds, which decides whether the Fig. 2
sweep runs in seconds or minutes.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from pydantic import Field

from netsim.models.cart.controllers import KU
from netsim.models.cart.dynamics import propagate, propagate1, stop_time
from netsim.models.cart.friction import FRICTION_STREAM, Friction, FrictionParams
from netsim.errors import BuildError
from netsim.plant import Plant
from netsim.registry import register
from netsim.units import Duration, StrictModel

if TYPE_CHECKING:
    from netsim.env import SimEnv

__all__ = ["CartParams", "CartPlant", "cart", "first_exit"]

_NEVER = 2**62


class CartParams(StrictModel):
    """Parameters of the cart plant."""

    ku: float = Field(KU, gt=0, description="motor gain Ku in m/s^2 per unit of full voltage")
    td: float | None = Field(None, gt=0, description="velocity time constant Td in s (paper: 0.23); null: none")
    friction: FrictionParams = Field(default_factory=FrictionParams)
    friction_step: Duration = Field(1_000_000, description="grid on which the friction level is re-evaluated")


class CartPlant(Plant):
    """The cart with position-dependent Coulomb friction, integrated in closed form (see module docs)."""

    def __init__(self, params: CartParams | None = None, name: str = "cart") -> None:
        super().__init__(2, 2, 2, input_names=["uV", "u_bias"], output_names=["p", "v"], state_names=["p", "v"],
                         name=name)
        self.params = params if params is not None else CartParams()
        self.friction = Friction.draw(self.params.friction, seed=0)
        self._x = np.zeros(2)
        self._grid = int(self.params.friction_step)
        self._f = 0.0
        self._fs = 0.0
        self._f_next = 0
        self._u_acc = 0.0

    # -------------------------------------------------------------- hooks of Plant
    def _bind_streams(self, env: SimEnv) -> None:
        if self.params.friction.realization is None:
            self.friction = Friction.from_rng(self.params.friction, env.rng(FRICTION_STREAM))
        env.components[FRICTION_STREAM] = self.friction

    def _check_source(self, src: Any) -> None:
        if src.kind not in ("piecewise", "held"):
            raise BuildError(f"plant {self.name}: disturbances must be piecewise constant or sampled signals, "
                             f"got a {src.kind} disturbance")

    def _update_effective_input(self, t: int) -> None:
        u = self._piecewise_input()
        self._u_acc = self.params.ku * min(1.0, max(-1.0, float(u[0]))) + float(u[1])

    def _start(self) -> None:
        super()._start()
        self._eval_friction(self._t)

    def _eval_friction(self, t: int) -> None:
        self._f = self.friction.level(float(self._x[0]))
        self._fs = self.friction.params.stiction * self._f
        self._f_next = (t // self._grid + 1) * self._grid

    def _step(self, t: int) -> bool:
        td = self.params.td
        x = self._x
        while self._t < t:
            end = t if t < self._f_next else self._f_next
            p0, v0 = x.tolist()  # Python floats, as float(x[0]), float(x[1])
            if td is None:  # propagate1 without its stop_time call (the same IEEE operations)
                p, v = _segment_end(p0, v0, self._u_acc, self._f, self._fs,
                                    (end - self._t) * 1e-9)[:2]
            else:
                p, v = propagate1(p0, v0, self._u_acc, self._f, self._fs,
                                  (end - self._t) * 1e-9, td)
            x[0] = p
            x[1] = v
            if not (abs(p) < self.divergence_bound and abs(v) < self.divergence_bound):
                self._diverged(end, x)
            self._t = end
            if end == self._f_next:
                self._eval_friction(end)
        return False

    def _output_now(self) -> np.ndarray:
        return self._x.copy()

    def _state_now(self) -> np.ndarray:
        return self._x.copy()

    def _set_state_now(self, x: np.ndarray) -> None:
        self._x = np.asarray(x, dtype=float).copy()
        if self._started:
            self._eval_friction(self._t)

    # -------------------------------------------------------------- exact encoder support
    def predict_exit(
        self, output: int, step: float, count: int, t_first: int, tick: int, max_ticks: int
    ) -> tuple[int | None, int, int]:
        """First tick ``t_first + j tick`` (``j < max_ticks``) where ``floor(y/step) != count``.

        Returns ``(candidate or None, last examined tick, wake-up instant)`` as
        :meth:`netsim.plant.LTIPlant.predict_exit`. The prediction uses the held inputs and the friction grid
        exactly as :meth:`_step` will, so a candidate is confirmed when the plant gets there.
        """
        if not self._started:
            self._start()
        t_end = t_first + (max_ticks - 1) * tick
        barrier = self._next_break
        if barrier <= t_end:
            n_ok = max(0, -(-(barrier - t_first) // tick))
            if n_ok == 0:
                return None, t_first - tick, barrier
            t_end = t_first + (n_ok - 1) * tick
        td = self.params.td
        u = self._u_acc
        t0 = self._t
        p0, v0 = self._x.tolist()
        f, fs, f_next = self._f, self._fs, self._f_next
        lo_band, hi_band = count * step, (count + 1) * step
        tk = t_first
        level = self.friction.level
        stiction = self.friction.params.stiction
        while tk <= t_end:
            if v0 == 0.0 and abs(u) <= fs:
                if output == 1 or lo_band <= p0 < hi_band:
                    tk = t_end + tick  # at rest and stuck: nothing moves until an input changes
                    break
            seg_end = f_next if f_next < t_end else t_end
            # cheap test first: the position range over the segment (at most two monotone pieces)
            dt_seg = (f_next - t0) * 1e-9
            if td is None:  # propagate1 and stop_time in one call: the same IEEE operations (issue 19)
                pe, ve, ts, p_ts = _segment_end(p0, v0, u, f, fs, dt_seg)
            else:
                ts = stop_time(v0, u - math.copysign(f, v0), td) if v0 != 0.0 else math.inf
                pe, ve = propagate1(p0, v0, u, f, fs, dt_seg, td)  # state at the segment's end
                p_ts = propagate1(p0, v0, u, f, fs, ts, td)[0] if ts < dt_seg else 0.0
            lo_p = pe if pe < p0 else p0  # min(p0, pe), max(p0, pe)
            hi_p = pe if pe > p0 else p0
            if ts < dt_seg:  # the motion reverses or stops inside: the turning point bounds the range too
                lo_p, hi_p = min(lo_p, p_ts), max(hi_p, p_ts)
            if output == 0:
                leaves = lo_p < lo_band or hi_p >= hi_band
            else:
                leaves = True
            if leaves and seg_end >= tk and td is None:
                j = first_exit(p0, v0, u, f, fs, tk - t0, tick, (seg_end - tk) // tick + 1, output, step, count)
                if j >= 0:
                    tc = tk + j * tick
                    return tc, tc, tc
            elif leaves and seg_end >= tk:
                n = (seg_end - tk) // tick + 1
                ticks = tk + tick * np.arange(n)
                p, v = propagate(p0, v0, u, f, fs, (ticks - t0) * 1e-9, td)
                y = p if output == 0 else v
                bad = np.floor(y / step) != count
                if bad.any():
                    tc = int(ticks[int(np.argmax(bad))])
                    return tc, tc, tc
            if seg_end >= tk:
                tk += ((seg_end - tk) // tick + 1) * tick
            if f_next > t_end:
                break
            t0, p0, v0 = f_next, pe, ve
            f = level(p0)
            fs = stiction * f
            f_next += self._grid
        last = min(tk - tick, t_end)
        return None, last, last if barrier >= _NEVER else min(barrier, last)


def _segment_end(p0: float, v0: float, u: float, f: float, fs: float,
                 tau: float) -> tuple[float, float, float, float]:
    """``(p, v, ts, p_ts)``: ``(p, v) = propagate1(p0, v0, u, f, fs, tau)`` (``Td`` off), ``ts`` the stop time
    ``stop_time(v0, u - copysign(f, v0), None)`` of its first piece (``inf`` at rest), and, when ``ts < tau``,
    ``p_ts = propagate1(p0, v0, u, f, fs, ts)[0]`` (else 0.0): computed together with the same IEEE operations
    as those calls (one call instead of four per friction segment of :meth:`CartPlant.predict_exit`;
    tests/models/cart/test_cart_segment_end.py compares them on random states)."""
    if v0 == 0.0:
        if abs(u) <= fs:
            return p0, 0.0, math.inf, 0.0
        a = u - math.copysign(f, u)
        return p0 + 0.0 * tau + 0.5 * a * tau * tau, 0.0 + a * tau, math.inf, 0.0
    a = u - math.copysign(f, v0)
    if a == 0.0 or (a > 0.0) == (v0 > 0.0):
        return p0 + v0 * tau + 0.5 * a * tau * tau, v0 + a * tau, math.inf, 0.0
    ts = -v0 / a
    if ts >= tau:
        return p0 + v0 * tau + 0.5 * a * tau * tau, v0 + a * tau, ts, 0.0
    p_stop = p0 + v0 * ts + 0.5 * a * ts * ts
    if abs(u) <= fs:
        return p_stop, 0.0, ts, p_stop
    a2 = u - math.copysign(f, u)
    dt = tau - ts
    return p_stop + 0.0 * dt + 0.5 * a2 * dt * dt, 0.0 + a2 * dt, ts, p_stop


def first_exit(p0: float, v0: float, u: float, f: float, fs: float, off: int, tick: int, n: int, output: int,
               step: float, count: int) -> int:
    """First ``j < n`` where ``floor(y_j / step) != count``, ``y_j`` the position (``output`` 0) or velocity (1)
    of :func:`~netsim.models.cart.dynamics.propagate1` (``Td`` off) at ``(off + j tick) 1e-9`` s; -1 if none.

    The same numbers as evaluating every tick with :func:`~netsim.models.cart.dynamics.propagate` (the same IEEE
    operations per tick), found by bisection: the motion is at most two monotone pieces (before and after the
    velocity reaches zero), and on a monotone piece the ticks inside the band form a prefix. About 15 scalar
    evaluations instead of about 15 numpy operations on up to 100 ticks (issue 19: the exact encoder's
    prediction is the cart's most frequent per-event cost).
    """
    if v0 == 0.0:
        if abs(u) <= fs:
            pieces: tuple[tuple[int, int, float, float, float, float], ...] = ((0, n, p0, 0.0, 0.0, 0.0),)
        else:
            pieces = ((0, n, p0, 0.0, u - math.copysign(f, u), 0.0),)
    else:
        a = u - math.copysign(f, v0)
        ts = stop_time(v0, a, None)
        if ts >= (off + (n - 1) * tick) * 1e-9:  # as propagate: no stop before the last tick, one piece
            split = n
        else:  # the first tick at or after the stop (propagate's `tau < ts` is the moving piece)
            split = min(n, max(0, int((ts * 1e9 - off) // tick)))
            while split > 0 and (off + (split - 1) * tick) * 1e-9 >= ts:
                split -= 1
            while split < n and (off + split * tick) * 1e-9 < ts:
                split += 1
        p_stop = p0 + v0 * ts + 0.5 * a * ts * ts if split < n else 0.0
        a2 = 0.0 if abs(u) <= fs else u - math.copysign(f, u)
        pieces = ((0, split, p0, v0, a, 0.0), (split, n, p_stop, 0.0, a2, ts))
    lo_q, hi_q = count, count + 1
    for first, end, p, v, a, t_from in pieces:
        if first >= end:
            continue
        ha = 0.5 * a
        # y at tick `first` (the IEEE operations of propagate: p + v x + 0.5 a x x, or v + a x)
        x = (off + first * tick) * 1e-9
        if t_from:
            x = x - t_from
        q = (p + v * x + ha * x * x if output == 0 else v + a * x) / step
        if not (lo_q <= q < hi_q):
            return first
        good, worse = first, end  # tick `good` is in the band; the first tick out of it, if any, in (good, end)
        if end - first > 3:
            # first probes: the piece's last tick, then where the band edge falls between the bracket's ends by
            # linear interpolation (a friction segment's motion is nearly linear) and its neighbour; then
            # bisection. Any probe inside (good, worse) keeps the bracket, so the result is the bisection's.
            x = (off + (end - 1) * tick) * 1e-9
            if t_from:
                x = x - t_from
            q1 = (p + v * x + ha * x * x if output == 0 else v + a * x) / step
            if lo_q <= q1 < hi_q:
                continue  # the last tick is in the band: no tick of this piece leaves it
            worse = end - 1
            g = first + int((((hi_q if q1 >= hi_q else lo_q) - q) / (q1 - q)) * (worse - first))
            g = first + 1 if g <= first else (worse - 1 if g >= worse else g)
            x = (off + g * tick) * 1e-9
            if t_from:
                x = x - t_from
            q1 = (p + v * x + ha * x * x if output == 0 else v + a * x) / step
            g2 = g + 1 if lo_q <= q1 < hi_q else g - 1
            if lo_q <= q1 < hi_q:
                good = g
            else:
                worse = g
            if good < g2 < worse:
                x = (off + g2 * tick) * 1e-9
                if t_from:
                    x = x - t_from
                q1 = (p + v * x + ha * x * x if output == 0 else v + a * x) / step
                if lo_q <= q1 < hi_q:
                    good = g2
                else:
                    worse = g2
        while worse - good > 1:
            mid = (good + worse) // 2
            x = (off + mid * tick) * 1e-9
            if t_from:
                x = x - t_from
            q = (p + v * x + ha * x * x if output == 0 else v + a * x) / step
            if lo_q <= q < hi_q:
                good = mid
            else:
                worse = mid
        if worse < end:
            return worse
    return -1


@register("plant", "cart", "Henningsson-Cervin cart: p'' = Ku sat(uV) + u_bias - F(p) sign(v), friction along the track")
def cart(params: CartParams | None = None, **kwargs: Any) -> CartPlant:
    """Build the cart plant from its parameters (see :class:`CartParams`)."""
    p = params if params is not None else CartParams.model_validate(kwargs)
    return CartPlant(p)


cart.Params = CartParams  # type: ignore[attr-defined]
