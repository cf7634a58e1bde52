"""Multi-rate controller with interlacing (MRCI), section 3.2.3 of Cuenca et al.

A discrete controller ``C(z)`` designed at the fast period ``T`` is split by partial fractions into
*slow* modes (the poles closest to the unit circle) and *fast* modes (the rest plus the direct term).
Each slow mode ``Cs_i(z) = C_i (zI - A_i)^-1 B_i + D_i`` is converted to the slow period ``m T`` by
eq (19)::

    Cs_i(z^m) = C_i (z^m I - A_i^m)^-1 (sum_{j=0}^{m-1} A_i^(m-1-j)) B_i + D_i

i.e. its input is down-sampled (held for ``m`` fast periods) and its output held by a ZOH. The slow
modes are *interlaced*: mode ``i`` (1-based) is updated only at the fast instants ``k = m j + i - 1``,
so that each fast instant updates one slow mode plus all fast modes. With ``m`` slow modes and ``n``
fast modes this saves eq (20) ``CS = (m - 1) / (m + n)`` of the computation.

Conventions (documented choices):

* a first-order section is one real pole; a complex-conjugate pair forms one real second-order section
  (one "mode"); repeated poles are refused (use a serial decomposition by hand);
* a slow mode updated at instant ``k`` outputs ``C x + D e_k`` from its state *before* the update and
  holds that output until its next update (ZOH);
* the direct term of ``C(z)`` belongs to the fast part.

Which error a slow mode sees (``wiring``, a reading of section 3.2.3):

``"delayed"`` (default)
    The text's wiring: "a down-sampling operator (down m) is required at the input of each Cs_i(z^m) to
    pick up the error signal e_k = r_k - y_k at every m instances of the fast rate, and later, the
    consequent signal is delayed z^-(i-1)". The down-sampler takes ``e`` at ``k = m j``; mode ``i``
    (phase ``i - 1``) is updated at ``k = m j + i - 1`` with that sample ``e_{m j}``, i.e. the error of
    ``i - 1`` fast periods ago (the delay is read at the fast rate: it is what places mode ``i``'s update
    at ``m j + i - 1``). If the controller does not step at ``k = m j`` (it steps only at arrivals), the
    last down-sampled error is used.
``"own_instant"``
    Mode ``i`` is fed ``e_k`` at its own update instant ``k = m j + i - 1`` (a down-sampler per phase, no
    delay). This was netsim's only wiring before the option existed.

:func:`decompose` is build-time code; :class:`MrciController` is the per-sample numeric object.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from netsim.errors import ConfigError

__all__ = ["Section", "MrciDesign", "MrciController", "decompose", "computation_saving", "WIRINGS"]

#: The readings of the interlacing wiring (see the module docstring); the first is the default.
WIRINGS = ("delayed", "own_instant")

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Section:
    """One real state-space section ``x+ = A x + B e, u = C x + D e`` (1 or 2 states)."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: float
    poles: tuple[complex, ...]

    def tf(self) -> tuple[np.ndarray, np.ndarray]:
        """Numerator and denominator (descending powers of z) of this section."""
        import scipy.signal as sps  # lazy: scipy.signal costs ~1 s to import

        num, den = sps.ss2tf(self.A, self.B.reshape(-1, 1), self.C.reshape(1, -1), [[self.D]])
        return np.atleast_1d(np.squeeze(num)), np.atleast_1d(den)

    def lifted(self, m: int) -> "Section":
        """This section converted to the slow period ``m T`` by eq (19) (input held m periods)."""
        Am = np.linalg.matrix_power(self.A, m)
        acc = np.zeros_like(self.A)
        for j in range(m):
            acc = acc + np.linalg.matrix_power(self.A, m - 1 - j)
        return Section(Am, acc @ self.B, self.C.copy(), self.D, tuple(p**m for p in self.poles))


def computation_saving(m: int, n: int) -> float:
    """Eq (20): fraction of computation saved, ``(m - 1) / (m + n)`` (not in %)."""
    if m < 1 or n < 0:
        raise ConfigError(f"computation saving needs m >= 1 and n >= 0, got m={m}, n={n}")
    return (m - 1) / (m + n)


@dataclass(frozen=True)
class MrciDesign:
    """The decomposition of ``C(z)``: slow sections (fast-rate and lifted forms) and fast sections.

    Attributes
    ----------
    m
        Multi-rate ratio; slow mode ``i`` is updated at ``k = m j + (i - 1) mod m``.
    slow, slow_lifted
        Slow sections at the fast rate and converted by eq (19).
    fast
        Fast sections (at the fast rate); ``direct`` is the direct term of ``C(z)``.
    """

    m: int
    slow: tuple[Section, ...]
    slow_lifted: tuple[Section, ...]
    fast: tuple[Section, ...]
    direct: float
    dt: float | None = None
    meta: dict = field(default_factory=dict)

    @property
    def n_slow(self) -> int:
        return len(self.slow)

    @property
    def n_fast(self) -> int:
        return len(self.fast)

    @property
    def computation_saving(self) -> float:
        """Eq (20) generalised: ``1 - (n + n_slow/m) / (n + n_slow)``; equals (m-1)/(m+n) when n_slow = m."""
        total = self.n_slow + self.n_fast
        if total == 0:
            return 0.0
        return 1.0 - (self.n_fast + self.n_slow / self.m) / total

    def slow_tf(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """``Cs_i(z^m)`` as numerator/denominator in powers of ``z^m`` (eq 34 form)."""
        return self.slow_lifted[i].tf()

    def fast_tf(self) -> tuple[np.ndarray, np.ndarray]:
        """All fast sections plus the direct term as one transfer function of ``z``."""
        num, den = np.array([self.direct]), np.array([1.0])
        for s in self.fast:
            n2, d2 = s.tf()
            num = np.polyadd(np.polymul(num, d2), np.polymul(n2, den))
            den = np.polymul(den, d2)
        return num, den


def _section_from_pair(r: complex, p: complex) -> Section:
    """Real second-order section for ``r/(z-p) + conj(r)/(z-conj(p))``."""
    a1 = -2.0 * p.real
    a0 = abs(p) ** 2
    b1 = 2.0 * r.real
    b0 = -2.0 * (r * np.conj(p)).real
    # controllable canonical form of (b1 z + b0)/(z^2 + a1 z + a0)
    A = np.array([[-a1, -a0], [1.0, 0.0]])
    B = np.array([1.0, 0.0])
    C = np.array([b1, b0])
    return Section(A, B, C, 0.0, (p, np.conj(p)))


def _sections(num, den, tol: float) -> tuple[list[Section], float]:
    import scipy.signal as sps  # lazy: scipy.signal costs ~1 s to import

    r, p, k = sps.residue(np.asarray(num, float), np.asarray(den, float), tol=tol)
    direct = float(np.real(k[0])) if len(k) else 0.0
    if len(k) > 1:
        raise ConfigError("MRCI: the controller C(z) is improper (more zeros than poles); use a proper controller")
    ps = np.asarray(p)
    for i in range(len(ps)):
        for j in range(i + 1, len(ps)):
            if abs(ps[i] - ps[j]) < max(tol, 1e-9) * 10:
                raise ConfigError(
                    f"MRCI: C(z) has a repeated pole at z={ps[i]:.6g}; partial fractions with repeated "
                    "poles are not supported, give a controller with distinct poles"
                )
    out: list[Section] = []
    used = [False] * len(ps)
    for i, pi in enumerate(ps):
        if used[i]:
            continue
        used[i] = True
        if abs(pi.imag) <= 1e-12 * max(1.0, abs(pi)):
            out.append(Section(np.array([[pi.real]]), np.array([1.0]), np.array([float(np.real(r[i]))]), 0.0,
                               (complex(pi.real, 0.0),)))
        else:
            j = min((jj for jj in range(len(ps)) if not used[jj]), key=lambda jj: abs(ps[jj] - np.conj(pi)))
            used[j] = True
            out.append(_section_from_pair(complex(r[i]), complex(pi)))
    return out, direct


def decompose(num, den, *, m: int, n_slow: int | None = None, slow_radius: float | None = None,
              dt: float | None = None, tol: float = 1e-6) -> MrciDesign:
    """Split ``C(z) = num(z)/den(z)`` (descending powers of z) into slow and fast modes.

    Parameters
    ----------
    num, den
        Controller polynomials at the fast period.
    m
        Multi-rate ratio (the slow modes run ``m`` times slower, interlaced).
    n_slow
        Number of slow modes (sections with the largest pole modulus). Default: ``m``, as in the paper
        (one slow mode updated at each fast instant).
    slow_radius
        Alternative to ``n_slow``: sections whose poles have modulus >= ``slow_radius`` are slow.
    dt
        Fast period in seconds (kept for reference only).

    Raises
    ------
    ConfigError
        If ``m < 1``, if the number of slow modes is not a multiple of ``m`` (the interlacing would not
        distribute the load uniformly), or there are fewer modes than asked for.
    """
    if int(m) != m or m < 1:
        raise ConfigError(f"MRCI: the multi-rate ratio m must be a positive integer, got {m!r}")
    m = int(m)
    secs, direct = _sections(num, den, tol)
    order = sorted(range(len(secs)), key=lambda i: -max(abs(p) for p in secs[i].poles))
    if slow_radius is not None:
        slow_idx = [i for i in order if max(abs(p) for p in secs[i].poles) >= slow_radius]
    else:
        ns = m if n_slow is None else int(n_slow)
        if ns > len(secs):
            raise ConfigError(
                f"MRCI: asked for {ns} slow modes but C(z) has only {len(secs)} modes "
                f"(poles {[complex(p) for s in secs for p in s.poles]}); lower n_slow or m"
            )
        slow_idx = order[:ns]
    if len(slow_idx) % m != 0:
        raise ConfigError(
            f"MRCI: m={m} does not divide the controller structure: {len(slow_idx)} slow mode(s) cannot be "
            f"interlaced uniformly over {m} phases; choose m dividing the number of slow modes"
        )
    slow = tuple(secs[i] for i in slow_idx)
    fast = tuple(secs[i] for i in range(len(secs)) if i not in slow_idx)
    lifted = tuple(s.lifted(m) for s in slow)
    return MrciDesign(m=m, slow=slow, slow_lifted=lifted, fast=fast, direct=direct, dt=dt)


class MrciController:
    """Runtime MRCI: call :meth:`step` once per fast instant ``k`` with the error ``e_k``.

    The state is a flat list of floats (per slow section its states then its held output, then the fast
    states, then the last down-sampled error) so that :meth:`snapshot`/:meth:`restore` are cheap copies
    (the NUMRE cascade needs them). Sections are evaluated with plain float arithmetic (they have one or
    two states).

    Parameters
    ----------
    design
        The decomposition from :func:`decompose`.
    wiring
        ``"delayed"`` (the text of section 3.2.3, default) or ``"own_instant"``: which error a slow mode
        is fed (see the module docstring).
    """

    def __init__(self, design: MrciDesign, wiring: str = "delayed") -> None:
        if wiring not in WIRINGS:
            raise ConfigError(f"MRCI: wiring must be one of {', '.join(WIRINGS)}, got {wiring!r}")
        self.wiring = wiring
        self._delayed = wiring == "delayed"
        self.design = design
        self.m = design.m
        self.direct = float(design.direct)

        def flat(s: Section) -> tuple:
            q = s.A.shape[0]
            return (q, tuple(map(float, s.A.ravel())), tuple(map(float, s.B)), tuple(map(float, s.C)), float(s.D))

        self._slow = [flat(s) for s in design.slow_lifted]
        self._fast = [flat(s) for s in design.fast]
        self._phase = [i % design.m for i in range(len(self._slow))]
        self._size = sum(q + 1 for q, *_ in self._slow) + sum(q for q, *_ in self._fast) + 1
        self._x = [0.0] * self._size
        self.updates = 0  # mode updates performed (slow + fast), for cost accounting

    @property
    def n_states(self) -> int:
        return self._size - 1

    def reset(self) -> None:
        self._x = [0.0] * self._size

    def snapshot(self) -> list:
        return self._x.copy()

    def restore(self, snap) -> None:
        self._x = list(snap)

    def step(self, k: int, e: float) -> float:
        """Controller output ``u_k`` for error ``e_k`` at fast instant ``k`` (advances the state)."""
        x = self._x
        u = self.direct * e
        pos = 0
        ph = k % self.m
        upd = 0
        if self._delayed:
            if ph == 0:
                x[-1] = e  # the down-sampler's sample e_{m j}
            es = x[-1]
        else:
            es = e
        for idx, (q, A, B, C, D) in enumerate(self._slow):
            if ph == self._phase[idx]:
                upd += 1
                if q == 1:
                    x0 = x[pos]
                    x[pos + 1] = C[0] * x0 + D * es
                    x[pos] = A[0] * x0 + B[0] * es
                else:
                    x0, x1 = x[pos], x[pos + 1]
                    x[pos + 2] = C[0] * x0 + C[1] * x1 + D * es
                    x[pos] = A[0] * x0 + A[1] * x1 + B[0] * es
                    x[pos + 1] = A[2] * x0 + A[3] * x1 + B[1] * es
            u += x[pos + q]
            pos += q + 1
        for q, A, B, C, D in self._fast:
            upd += 1
            if q == 1:
                x0 = x[pos]
                u += C[0] * x0 + D * e
                x[pos] = A[0] * x0 + B[0] * e
            else:
                x0, x1 = x[pos], x[pos + 1]
                u += C[0] * x0 + C[1] * x1 + D * e
                x[pos] = A[0] * x0 + A[1] * x1 + B[0] * e
                x[pos + 1] = A[2] * x0 + A[3] * x1 + B[1] * e
            pos += q
        self.updates += upd
        return u
