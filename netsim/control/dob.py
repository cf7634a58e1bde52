"""H-infinity disturbance observer (DOB), section 3.2.2 and Fig. 3 of Cuenca et al.

``d_hat = D1(z) u_hat + D2(z) y_hat`` (eq 16) with ``D1`` close to -1 and ``D2`` close to ``G^-1``,
obtained from the H-infinity problem (17) on the LFT of eq (18).

The generalized plant (our reading of eq 18)
--------------------------------------------
With the baseline loop ``u = -C(z) y + q`` (``q`` the compensation the DOB adds, ``q = -d_hat``) and
the plant input ``u + d``, eliminating the loop gives, with ``S = (1 + G C)^-1``::

    z   = d + q                                   (residual disturbance: M11 = 1, M12 = +1)
    u_m = -C S G d + (1 - C S G) q                (eq 18, 2nd row)
    y   =  S G d + S G q                          (eq 18, 3rd row)

which is eq (18) with the sign of ``M12`` flipped (with the printed ``-1`` the rows 2-3 imply
``u = -Cy + q`` while ``z = d - q``, which would *reward* doubling the disturbance). ``D`` of eq (16)
is ``-K`` for the H-infinity controller ``K: [u_m, y] -> q``.

Three additions make the problem well posed; each is standard and documented:

* ``u_m`` is measured one period late (``z^-1 u``): ``D22 = 0`` (no algebraic loop between the DOB output
  and its own input). No information is lost: ``y_k`` depends on ``u_{k-1}`` only (strictly proper G).
* a performance weight ``Wz(z)`` on ``z`` (first order, gain ``dc_gain`` at low frequency falling to
  ``hf_gain`` above ``bandwidth``): a causal observer cannot cancel the unpredictable part of ``d``, so an
  unweighted problem has ``gamma >= 1`` at every frequency;
* small measurement noises ``eps`` on both measurements (``D21`` full row rank; python-control issue #152:
  ``hinfsyn`` on a rank-deficient problem can spin for minutes).

python-control's ``hinfsyn`` (slycot ``sb10ad``) is continuous-time only: the discrete problem is mapped
by the bilinear transform (which preserves the H-infinity norm exactly), solved, and the controller mapped
back. Synthesis runs in a forked child process with a time limit.
"""

from __future__ import annotations

import logging
import multiprocessing as mp
from dataclasses import dataclass

import numpy as np

from netsim.errors import BuildError, ConfigError

__all__ = ["DobDesign", "DisturbanceObserver", "design_dob", "d2c_bilinear", "c2d_bilinear"]

log = logging.getLogger(__name__)


def d2c_bilinear(A, B, C, D, T: float):
    """Continuous system with ``Hc(s) = Hd((1 + sT/2)/(1 - sT/2))`` (inverse Tustin, exact)."""
    n = A.shape[0]
    a = 2.0 / T
    Ei = np.linalg.inv(A + np.eye(n))
    Ac = a * Ei @ (A - np.eye(n))
    g = np.sqrt(2.0 * a)
    return Ac, g * Ei @ B, g * C @ Ei, D - C @ Ei @ B


def c2d_bilinear(A, B, C, D, T: float):
    """Discrete system with ``Hd(z) = Hc(2/T (z-1)/(z+1))`` (Tustin, exact inverse of :func:`d2c_bilinear`)."""
    n = A.shape[0]
    a = 2.0 / T
    Fi = np.linalg.inv(a * np.eye(n) - A)
    g = np.sqrt(2.0 * a)
    return (a * np.eye(n) + A) @ Fi, g * Fi @ B, g * C @ Fi, D + C @ Fi @ B


@dataclass(frozen=True)
class DobDesign:
    """The discrete DOB ``D(z) = [D1, D2]`` as a state space with inputs ``[u_{k-1}, y_k]``, output ``d_hat``."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    T: float
    gamma: float

    def freq(self, f_hz: float) -> np.ndarray:
        """``[D1, D2]`` at frequency ``f_hz`` (``D1`` including the one-period delay on ``u``)."""
        z = np.exp(1j * 2 * np.pi * f_hz * self.T)
        H = self.C @ np.linalg.solve(z * np.eye(self.A.shape[0]) - self.A, self.B) + self.D
        return np.array([H[0, 0] / z, H[0, 1]])


def _generalized_plant(Ap, Bp, Cp, cnum, cden, T, bandwidth, dc_gain, hf_gain, eps):
    import control as ct

    G = ct.ss(Ap, Bp, Cp, 0, T, inputs="v", outputs="y", name="G")
    Cn = ct.ss(ct.tf(-np.asarray(cnum, float), np.asarray(cden, float), T))
    Cn = ct.ss(Cn.A, Cn.B, Cn.C, Cn.D, T, inputs="y", outputs="uc", name="C")
    Dl = ct.ss([[0.0]], [[1.0]], [[1.0]], [[0.0]], T, inputs="uh", outputs="um0", name="delay")
    wb = 2 * np.pi * bandwidth
    # first-order weight: dc_gain at low frequency, hf_gain at high frequency, corner near `bandwidth`
    Wc = ct.tf([hf_gain, wb * dc_gain], [1.0, wb])
    Wd = ct.c2d(Wc, T, "tustin")
    Wz = ct.ss(Wd)
    Wz = ct.ss(Wz.A, Wz.B, Wz.C, Wz.D, T, inputs="e", outputs="z", name="Wz")
    sv = ct.summing_junction(["uc", "q", "d"], "v", name="sv", dt=T)
    su = ct.summing_junction(["uc", "q"], "uh", name="su", dt=T)
    se = ct.summing_junction(["d", "q"], "e", name="se", dt=T)
    m1 = ct.summing_junction(["um0", "nus"], "m1", name="m1s", dt=T)
    m2 = ct.summing_junction(["y", "nys"], "m2", name="m2s", dt=T)
    gu = ct.tf([eps], [1.0], T, inputs="nu", outputs="nus", name="gu")
    gy = ct.tf([eps], [1.0], T, inputs="ny", outputs="nys", name="gy")
    P = ct.interconnect([G, Cn, Dl, Wz, sv, su, se, m1, m2, ct.ss(gu), ct.ss(gy)],
                        inplist=["d", "nu", "ny", "q"], outlist=["z", "m1", "m2"])
    return P


def _synth_child(conn, Ac, Bc, Cc, Dc):
    try:
        import control as ct

        K, _CL, gam, _rc = ct.hinfsyn(ct.ss(Ac, Bc, Cc, Dc), 2, 1)
        conn.send(("ok", np.asarray(K.A), np.asarray(K.B), np.asarray(K.C), np.asarray(K.D), float(gam)))
    except Exception as exc:  # pragma: no cover - reported to the parent
        conn.send(("error", repr(exc)))
    finally:
        conn.close()


def _check_conditions(Ac, Bc, Cc, Dc, nz=1, nw=3, nmeas=2, ncon=1) -> None:
    n = Ac.shape[0]
    B2 = Bc[:, nw:]
    C2 = Cc[nz:, :]
    D12 = Dc[:nz, nw:]
    D21 = Dc[nz:, :nw]
    if np.linalg.matrix_rank(D12) < ncon:
        raise ConfigError("DOB H-infinity problem: D12 is rank deficient (the weighted residual does not see "
                          "the compensation directly); give the weight a nonzero high-frequency gain")
    if np.linalg.matrix_rank(D21) < nmeas:
        raise ConfigError("DOB H-infinity problem: D21 is rank deficient; use a measurement noise eps > 0")
    ev = np.linalg.eigvals(Ac)
    for lam in ev[np.real(ev) >= -1e-9]:
        M1 = np.hstack([Ac - lam * np.eye(n), B2])
        M2 = np.vstack([Ac - lam * np.eye(n), C2])
        if np.linalg.matrix_rank(M1, tol=1e-8 * max(1.0, np.abs(M1).max())) < n:
            raise ConfigError(f"DOB H-infinity problem: mode {lam:.4g} is not stabilizable from the DOB output")
        if np.linalg.matrix_rank(M2, tol=1e-8 * max(1.0, np.abs(M2).max())) < n:
            raise ConfigError(f"DOB H-infinity problem: mode {lam:.4g} is not detectable from the DOB inputs")


def design_dob(Ap, Bp, Cp, cnum, cden, T: float, *, bandwidth: float = 1000.0, dc_gain: float = 10.0,
               hf_gain: float = 0.5, eps: float = 1e-3, timeout_s: float = 60.0) -> DobDesign:
    """Solve problem (17) for the plant ``(Ap, Bp, Cp)`` (discrete, period ``T``) and controller ``C(z)``.

    Raises
    ------
    ConfigError
        If the rank/stabilizability conditions fail or the synthesis finds no solution.
    BuildError
        If synthesis does not finish within ``timeout_s``.
    """
    import control as ct

    if eps <= 0 or bandwidth <= 0 or dc_gain <= 0 or hf_gain <= 0:
        raise ConfigError("DOB: eps, bandwidth, dc_gain and hf_gain must all be > 0")
    P = _generalized_plant(np.asarray(Ap, float), np.asarray(Bp, float), np.asarray(Cp, float),
                           cnum, cden, T, bandwidth, dc_gain, hf_gain, eps)
    A, B, C, D = (np.asarray(M, float) for M in (P.A, P.B, P.C, P.D))
    if np.any(np.abs(np.linalg.eigvals(A)) >= 1.0):
        raise ConfigError("DOB: the baseline controller does not stabilize the plant model; the H-infinity "
                          "problem (17) has no stabilizing solution")
    Ac, Bc, Cc, Dc = d2c_bilinear(A, B, C, D, 2.0)  # frequency-normalised bilinear map (exact, well scaled)
    _check_conditions(Ac, Bc, Cc, Dc)
    ctx = mp.get_context("fork")
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_synth_child, args=(child, Ac, Bc, Cc, Dc), daemon=True)
    proc.start()
    child.close()
    if not parent.poll(timeout_s):
        proc.terminate()
        proc.join(1.0)
        raise BuildError(f"DOB: H-infinity synthesis did not finish within {timeout_s:g} s (ill-posed problem?); "
                         "check the weights and eps")
    msg = parent.recv()
    proc.join(1.0)
    if msg[0] != "ok":
        raise ConfigError(f"DOB: the H-infinity problem (17) has no solution: {msg[1]}")
    _, Ak, Bk, Ck, Dk, gam = msg
    Ad, Bd, Cd, Dd = c2d_bilinear(Ak, Bk, Ck, Dk, 2.0)
    # d_hat = -q
    return DobDesign(Ad, Bd, -Cd, -Dd, T, gam)


class DisturbanceObserver:
    """Runtime DOB: ``d_hat_k = step(u_{k-1}, y_hat_k)``; snapshot/restore for the NUMRE cascade."""

    def __init__(self, design: DobDesign) -> None:
        self.design = design
        self._A, self._B, self._C, self._D = design.A, design.B, design.C[0], design.D[0]
        self._x = np.zeros(design.A.shape[0])

    def reset(self) -> None:
        self._x = np.zeros_like(self._x)

    def snapshot(self) -> np.ndarray:
        return self._x.copy()

    def restore(self, snap) -> None:
        self._x = np.array(snap, dtype=float, copy=True)

    def step(self, u_prev: float, y_hat: float) -> float:
        inp = np.array([u_prev, y_hat])
        d = float(self._C @ self._x + self._D @ inp)
        self._x = self._A @ self._x + self._B @ inp
        return d
