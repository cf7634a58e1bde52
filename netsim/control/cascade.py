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
The sign convention: ``u = C(e) - d_hat`` (``d`` enters the plant as ``u + d``).
"""

from __future__ import annotations

import logging
from typing import Callable

import numpy as np

from netsim.control.controller_trigger import ControllerTrigger
from netsim.control.mrci import MrciController
from netsim.control.numre import Numre
from netsim.control.packets import ControlPacket, PlayoutBuffer

__all__ = ["ControlSide", "Decision"]

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
        self._traj_x: list[np.ndarray] = []  # x(k_ls + l | k_ls), completed lazily by _traj_state
        self._traj_k = 0
        self._traj_c: list[np.ndarray] = []
        self._traj_d: list = []
        self._u_prev = 0.0
        self._traj_u_prev: list[float] = []
        self.steps = 0  # controller steps computed (cost accounting)

    # ------------------------------------------------------------------------------------------
    def on_measurement(self, k: int, y: float) -> Decision:
        """Process measurement ``y`` sensed at fast instant ``k``; return the packet and the send decision."""
        if self.est is None:
            return self._direct(k, y)
        return self._estimated(k, y)

    def _direct(self, k: int, y: float) -> Decision:
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
        if self.k_ls is None:  # first measurement: the initial guess propagated with the initial action
            x = self._x0.copy()
            for j in range(k):
                x = est.predict_step(x, self.mirror.value(j))
            return x, 1
        N = k - self.k_ls
        L = len(self._traj_c) - 1
        if N <= L:
            self.ctrl.restore(self._traj_c[N])
            if self.dob is not None:
                self.dob.restore(self._traj_d[N])
            self._u_prev = self._traj_u_prev[N]
            return self._traj_state(N), N
        # past the packet: continue with the held action (h < N)
        self.ctrl.restore(self._traj_c[L])
        if self.dob is not None:
            self.dob.restore(self._traj_d[L])
        self._u_prev = self._traj_u_prev[L]
        x = self._traj_state(L)
        for l in range(L, N):
            j = self.k_ls + l
            yh, dh = est.outputs(x)
            dh = self._dob_step(self._u_prev, yh) if self.dob is not None else dh
            self._u_prev = self.ctrl.step(j, self.reference(j) - yh) - dh
            x = est.predict_step(x, self.mirror.value(j))
        return x, N

    def _traj_state(self, i: int) -> np.ndarray:
        """``x(k_ls + i | k_ls)`` of the last cascade, predicted with the actions the actuator applies.

        After a packet was held back (eq 22) only ``x(k_ls|k_ls)`` is stored; the predictions with the
        playing packet (``mirror``) are computed here up to the step the next arrival asks for, with the
        same arithmetic as :meth:`Numre.predict_step`. The mirror cannot change in between: it changes only
        after the next arrival has taken its prior.
        """
        xs = self._traj_x
        if i >= len(xs):
            est = self.est
            A, b, value, k0 = est.A, est._b, self.mirror.value, self._traj_k
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
        prior, N = self._state_at(k)
        if self.k_ls is not None and N > self.h:
            self.horizon_violations += 1
            if self.horizon_violations == 1:
                log.warning("NUMRE: multiplicity N=%d at k=%d exceeds the horizon h=%d (need h >= N_max); "
                            "predicting on with the held last action", N, k, self.h)
        self.N_max = max(self.N_max, N)
        x = est.correct(prior, y, min(N, 10**6))
        self.k_ls = k
        h = self.h
        ctrl, dob, ref = self.ctrl, self.dob, self.reference
        b = est._b
        xs = [x]
        cs = [ctrl.snapshot()]
        ds = [dob.snapshot() if dob is not None else None]
        ups = [self._u_prev]
        us = []
        u = self._u_prev
        y_hat0 = d_hat0 = 0.0
        # per step l: y_hat, d_hat (eq 15, or the DOB) and A x from one product (step_outputs), the MRCI on
        # r - y_hat minus d_hat gives u_{k+l}, and x(k+l+1|k) = A x + B u (eq 14, = est.predict_step)
        M, n = est._fused, est.n
        has_d = est.Cbar is not None
        for l in range(h + 1):
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
                y_hat0, d_hat0 = yh, dh
            u = ctrl.step(j, ref(j) - yh) - dh
            us.append(u)
            x = ax + b * u
            xs.append(x)
            cs.append(ctrl.snapshot())
            if dob is not None:
                ds.append(dob.snapshot())
            else:
                ds.append(None)
            ups.append(u)
        self._u_prev = u
        self.steps += h + 1
        pkt = ControlPacket(k, tuple(us))
        send = self.trigger.should_send(us[0])
        if send:
            self.mirror.receive(pkt)
        else:  # the actuator keeps playing the older packet: predict with what it applies (lazily, as far
            xs = [xs[0]]  # as the next arrival needs: see _traj_state)
        self._traj_x, self._traj_c, self._traj_d, self._traj_u_prev = xs, cs, ds, ups
        self._traj_k = k
        return Decision(k, pkt, send, N, y_hat0, d_hat0)
