"""The control side of Fig. 1 of Cuenca et al. as one numeric object: NUMRE + MRCI (+ DOB) + eq (22).

:class:`ControlSide` is called once per *received* measurement ``(k, y_k)`` and returns the packet it
computed and whether eq (22) lets it go to the actuator. Two modes:

``estimator=None`` (Cases 1 and 2, no NUMRE)
    ``e_k = r_k - y_k``; the MRCI steps once (its slow mode of phase ``k mod m`` and the fast modes) and the
    packet holds the current action only (``h = 0``): the actuator holds it (ZOH).

with a :class:`~netsim.control.numre.Numre` (Cases 3-6)
    1. ``N = k - k_ls`` (eq 9); the prior ``x(k|k-N)`` is the state predicted at the previous arrival
       with the inputs the actuator *actually applies* (the packet sent then, or -- if eq (22) held the
       packet back -- the older packet still playing, then its last value held);
    2. correction with ``K(N)`` (eq 11);
    3. cascade (eq 14, Section 2): for ``l = 0..h``: ``y_hat, d_hat`` (eq 15, or the DOB), the MRCI on
       ``r_{k+l} - y_hat`` minus ``d_hat`` gives ``u_{k+l}``, the model predicts ``x(k+l+1|k)`` with it;
    4. the controller states (MRCI, DOB) of every cascade step are kept, so that at the next arrival
       ``k + N`` they continue from the state they had reached at ``k + N`` (the controller "ran" through
       the cascade). If ``N > h`` (``h < N_max``, which the paper forbids) the prediction and the
       controller are continued past the packet with the held last action, and the violation is counted
       in :attr:`horizon_violations` and logged.

With a DOB (Case 6, :mod:`netsim.control.dob`) ``d_hat`` of each cascade step is ``D(z)`` applied to the
previous action and ``y_hat`` (eq 16); the NUMRE then predicts with ``u`` only (eq 14, plant model). The
DOB must be a *stable* filter: its states are carried through the cascade and restarted from snapshots at
each arrival, and when eq (22) holds a packet back its inputs were the computed (not the applied)
actions, so nothing cancels an unstable DOB mode (:class:`~netsim.control.dob.DisturbanceObserver`
refuses one).

The controller-side trigger compares ``u_k`` with the first value of the last *sent* packet (eq 21-22).

Lazy evaluation: the cascade of an arrival is computed step by step only as far as something asks for it
(the packet's ``values`` are a :class:`CascadeActions` sequence; the next arrival asks for the states at its
``N``). The actuator plays a packet only until the next one arrives, so with frequent arrivals most of the
``h + 1`` steps are never needed. Every step that is computed is computed with the same arithmetic, from the
same states, as the eager cascade: results are identical, only cheaper. This requires ``reference`` to be a
pure function of ``k`` (it is called when a step is computed).
The sign convention: ``u = C(e) - d_hat`` (``d`` enters the plant as ``u + d``).
"""

from __future__ import annotations

import logging
from collections.abc import Iterator, Sequence
from typing import Callable

import numpy as np

from netsim.control.controller_trigger import ControllerTrigger
from netsim.control.mrci import MrciController
from netsim.control.numre import Numre
from netsim.control.packets import ControlPacket, PlayoutBuffer

__all__ = ["ControlSide", "Decision", "CascadeActions"]

log = logging.getLogger(__name__)


class Decision:
    """What :meth:`ControlSide.on_measurement` returns."""

    __slots__ = ("k", "packet", "send", "N", "y_hat", "d_hat")

    def __init__(self, k: int, packet: ControlPacket, send: bool, N: int, y_hat: float, d_hat: float) -> None:
        self.k = k
        self.packet = packet
        self.send = send
        self.N = N
        self.y_hat = y_hat
        self.d_hat = d_hat


class _Cascade:
    """The h-step cascade (eq 14) of one arrival at ``k``, computed on demand (see the module docstring).

    Step ``l`` gives ``u_{k+l}`` (``us[l]``) and the states after it: ``xs[l+1]`` (model prediction with the
    computed action), the controller snapshot ``cs[l+1]``, the DOB snapshot ``ds[l+1]`` and ``ups[l+1]``
    (the action, the DOB's next ``u_prev``). Index 0 holds the states the cascade starts from.
    The controller and DOB objects are shared with the control side: every computation restores this
    cascade's own last state first, and leaves them in an undefined state.
    """

    __slots__ = ("side", "k", "h", "xs", "cs", "ds", "ups", "us", "y_hat0", "d_hat0")

    def __init__(self, side: "ControlSide", k: int, x: np.ndarray, c, d, u_prev: float) -> None:
        self.side = side
        self.k = k
        self.h = side.h
        self.xs = [x]
        self.cs = [c]
        self.ds = [d]
        self.ups = [u_prev]
        self.us: list[float] = []
        self.y_hat0 = self.d_hat0 = 0.0

    def compute(self, n_steps: int) -> None:
        """Make sure steps ``0 .. n_steps - 1`` are computed (at most ``h + 1``)."""
        us = self.us
        start = len(us)
        stop = min(n_steps, self.h + 1)
        if start >= stop:
            return
        side = self.side
        est, ctrl, dob, ref = side.est, side.ctrl, side.dob, side.reference
        assert est is not None  # a cascade is made only with an estimator (ControlSide._estimated)
        xs, cs, ds, ups = self.xs, self.cs, self.ds, self.ups
        ctrl.restore(cs[-1])
        if dob is not None:
            dob.restore(ds[-1])
        x = xs[-1]
        u = ups[-1]
        b = est._b
        M, n = est._fused, est.n
        has_d = est.Cbar is not None
        k = self.k
        # per step l: y_hat, d_hat (eq 15, or the DOB) and A x from one product (Numre.step_outputs), the MRCI
        # on r - y_hat minus d_hat gives u_{k+l}, and x(k+l+1|k) = A x + B u (eq 14, = Numre.predict_step)
        for l in range(start, stop):
            j = k + l
            if M is not None:  # est.step_outputs inlined
                ax = M @ x
                yh = float(ax[n])
                dh = float(ax[n + 1]) if has_d else 0.0
                ax = ax[:n]
            else:
                ax, yh, dh = est.step_outputs(x)
            if dob is not None:
                dh = dob.step(u, yh)
            if l == 0:
                self.y_hat0, self.d_hat0 = yh, dh
            u = ctrl.step(j, ref(j) - yh) - dh
            us.append(u)
            x = ax + b * u
            xs.append(x)
            cs.append(ctrl.snapshot())
            ds.append(dob.snapshot() if dob is not None else None)
            ups.append(u)

    def state(self, i: int) -> tuple:
        """``(x, controller snapshot, DOB snapshot, u_prev)`` after ``i`` steps (``0 <= i <= h + 1``)."""
        if i >= len(self.xs):
            self.compute(i)
        return self.xs[i], self.cs[i], self.ds[i], self.ups[i]


class CascadeActions(Sequence):
    """The actions ``u_k .. u_{k+h}`` of a cascade as a read-only sequence, each computed when first read.

    Behaves like the tuple of the eagerly computed values (indexing, slices, ``len``, iteration, equality
    and hash with tuples).
    """

    __slots__ = ("_c",)

    def __init__(self, cascade: _Cascade) -> None:
        self._c = cascade

    def __len__(self) -> int:
        return self._c.h + 1

    def __getitem__(self, index):
        c = self._c
        n = c.h + 1
        if isinstance(index, slice):
            return tuple(self[i] for i in range(*index.indices(n)))
        i = int(index)
        if i < 0:
            i += n
        if not 0 <= i < n:
            raise IndexError(f"cascade action index {index} out of range (h + 1 = {n} values)")
        if i >= len(c.us):
            c.compute(i + 1)
        return c.us[i]

    def __iter__(self) -> Iterator[float]:
        for i in range(len(self)):
            yield self[i]

    def __eq__(self, other: object) -> bool:
        if isinstance(other, (CascadeActions, tuple, list)):
            return len(self) == len(other) and all(a == b for a, b in zip(self, other))
        return NotImplemented

    def __hash__(self) -> int:
        return hash(tuple(self))

    def __repr__(self) -> str:
        return f"CascadeActions(k={self._c.k}, {len(self._c.us)} of {len(self)} computed)"


class ControlSide:
    """Control-side algorithm: see the module docstring.

    Parameters
    ----------
    controller
        The MRCI (or any object with ``step(k, e)``, ``snapshot()``, ``restore(s)``).
    reference
        ``r(k) -> float``, the reference at fast instant ``k``.
    estimator
        A :class:`Numre`, or None for the no-estimator mode.
    dob
        Optional disturbance observer with ``step(u_prev, y_hat) -> d_hat``, ``snapshot``, ``restore``
        (see :mod:`netsim.control.dob`); used instead of ``Cbar x`` for ``d_hat``.
    trigger
        Controller-side eq (22) (default: always send).
    h
        Number of future actions per packet (forced to 0 without estimator).
    """

    def __init__(self, controller: MrciController, reference: Callable[[int], float], *,
                 estimator: Numre | None = None, dob=None, trigger: ControllerTrigger | None = None,
                 h: int | None = None, x0: np.ndarray | None = None) -> None:
        self.ctrl = controller
        self.reference = reference
        self.est = estimator
        self.dob = dob
        self.trigger = trigger or ControllerTrigger(enabled=False)
        if estimator is None:
            self.h = 0
        else:
            self.h = estimator.h if h is None else int(h)
        self.mirror = PlayoutBuffer()  # what the actuator plays (no loss assumed)
        self.k_ls: int | None = None
        self.horizon_violations = 0
        self.N_max = 0
        n = 0 if estimator is None else estimator.n
        self._x0 = np.zeros(n) if x0 is None else np.asarray(x0, float)
        self._casc: _Cascade | None = None  # the cascade of the last arrival
        self._traj_x: list[np.ndarray] | None = None  # held-back packet: x(k_ls + l | k_ls), see _traj_state
        self._u_prev = 0.0
        self.steps = 0  # controller steps computed (cost accounting)

    # ------------------------------------------------------------------------------------------
    def on_measurement(self, k: int, y: float) -> Decision:
        """Process measurement ``y`` sensed at fast instant ``k``; return the packet and the send decision."""
        if self.est is None:
            return self._direct(k, y)
        return self._estimated(k, y)

    def on_period(self, k: int, y: float, k_y: int) -> Decision:
        """Step the controller at fast instant ``k`` on the last received measurement ``y`` (sensed at ``k_y``).

        The "runs every T" reading of Case 2 (no estimator only): the MRCI steps at every ``k`` and eq (22)
        is checked at every ``k``; ``Decision.N`` is the age ``k - k_y + 1`` of the measurement used
        (1 when it was sensed in this period).
        """
        if self.est is not None:
            raise ValueError("ControlSide.on_period is the no-estimator reading; with a NUMRE use on_measurement")
        return self._direct(k, y, N=k - k_y + 1)

    def _direct(self, k: int, y: float, N: int | None = None) -> Decision:
        if N is None:
            N = k - self.k_ls if self.k_ls is not None else k + 1
        self.k_ls = k
        u = self.ctrl.step(k, self.reference(k) - y)
        self.steps += 1
        pkt = ControlPacket(k, (u,))
        send = self.trigger.should_send(u)
        if send:
            self.mirror.receive(pkt)
        return Decision(k, pkt, send, N, y, 0.0)

    def _state_at(self, k: int) -> tuple[np.ndarray, int]:
        """Prior at ``k`` (and leave controller/DOB states as they were at ``k``)."""
        est = self.est
        assert est is not None  # the estimated mode (on_measurement)
        if self.k_ls is None:  # first measurement: the initial guess propagated with the initial action
            x = self._x0.copy()
            for j in range(k):
                x = est.predict_step(x, self.mirror.value(j))
            return x, 1
        N = k - self.k_ls
        casc = self._casc
        assert casc is not None  # set with k_ls by _estimated
        L = casc.h + 1
        i = min(N, L)
        # everything that may compute (older) cascades first: they use the shared controller and DOB
        x = self._traj_state(i)
        _, c, d, up = casc.state(i)
        held = [self.mirror.value(self.k_ls + l) for l in range(L, N)]
        self.ctrl.restore(c)
        if self.dob is not None:
            self.dob.restore(d)
        self._u_prev = up
        if N <= L:
            return x, N
        # past the packet: continue with the held action (h < N)
        for l in range(L, N):
            j = self.k_ls + l
            yh, dh = est.outputs(x)
            dh = self._dob_step(self._u_prev, yh) if self.dob is not None else dh
            self._u_prev = self.ctrl.step(j, self.reference(j) - yh) - dh
            x = est.predict_step(x, held[l - L])
        return x, N

    def _traj_state(self, i: int) -> np.ndarray:
        """``x(k_ls + i | k_ls)``: the cascade's prediction, or with a held-back packet the prediction with
        the actions the actuator applies.

        After a packet was held back (eq 22) only ``x(k_ls|k_ls)`` is stored; the predictions with the
        playing packet (``mirror``) are computed here up to the step the next arrival asks for, with the
        same arithmetic as :meth:`Numre.predict_step`. The mirror cannot change in between: it changes only
        after the next arrival has taken its prior.
        """
        xs = self._traj_x
        casc, est = self._casc, self.est
        assert casc is not None and est is not None  # called by _state_at, after the first arrival
        if xs is None:
            return casc.state(i)[0]
        if i >= len(xs):
            A, b, value, k0 = est.A, est._b, self.mirror.value, casc.k
            x = xs[-1]
            for l in range(len(xs) - 1, i):
                x = A @ x + b * value(k0 + l)
                xs.append(x)
        return xs[i]

    def _dob_step(self, u_prev: float, y_hat: float) -> float:
        if self.dob is None:
            return 0.0
        return self.dob.step(u_prev, y_hat)

    def _estimated(self, k: int, y: float) -> Decision:
        est = self.est
        assert est is not None  # on_measurement's estimated branch
        prior, N = self._state_at(k)
        if self.k_ls is not None and N > self.h:
            self.horizon_violations += 1
            if self.horizon_violations == 1:
                log.warning("NUMRE: multiplicity N=%d at k=%d exceeds the horizon h=%d (need h >= N_max); "
                            "predicting on with the held last action", N, k, self.h)
        self.N_max = max(self.N_max, N)
        x = est.correct(prior, y, min(N, 10**6))
        self.k_ls = k
        casc = _Cascade(self, k, x, self.ctrl.snapshot(), self.dob.snapshot() if self.dob is not None else None,
                        self._u_prev)
        casc.compute(1)
        self.steps += self.h + 1
        values = CascadeActions(casc)
        pkt = ControlPacket(k, values)
        send = self.trigger.should_send(casc.us[0])
        if send:
            self.mirror.receive(pkt)
        self._casc = casc
        # with a held-back packet the actuator keeps playing the older one: predict with what it applies
        self._traj_x = None if send else [x]
        y_hat0, d_hat0 = casc.y_hat0, casc.d_hat0
        return Decision(k, pkt, send, N, y_hat0, d_hat0)
