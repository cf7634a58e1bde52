"""Expected quadratic cost of a sampled LTI loop under random delay and sampling jitter (Jitterbug-style).

The loop
--------
A continuous plant driven by white process noise of intensity ``R1``::

    dx = (A x + B u) dt + dv,      y(t_k) = C x(t_k) + e_k,   e_k ~ N(0, R2)

is sampled at ``t_k = k h + o_k``: the nominal grid plus an offset ``o_k`` drawn independently each period
from a discrete distribution (sampling jitter). A discrete controller

    u_k = Cc xc_k + Dc y_k,        xc_{k+1} = Ac xc_k + Bc y_k

computes ``u_k`` from that sample; it reaches the plant ``tau_k`` later (the input-output delay, drawn
independently each period, ``0 <= tau_k <= t_{k+1} - t_k``) and is held until the next output arrives.
The cost is the long-run average ``J = lim 1/T E int_0^T (x' Q1 x + u' Q2 u) dt``.

The computation
---------------
Over one period the loop state ``z_k = [x(t_k); xc_k; u held at t_k]`` moves linearly: the sample and the
controller update, a first plant segment of length ``tau`` under the old input, the switch to ``u_k``, a
second segment of length ``t_{k+1} - t_k - tau`` under ``u_k``. Each segment is a zero-order-hold step of the
plant augmented with its held input, ``xi = [x; u]``, ``dxi = Abar xi dt + [dv; 0]``, with the transition
``e^(Abar s)``, the noise covariance ``int_0^s e^(Abar r) R1bar e^(Abar' r) dr``, the cost matrix
``int_0^s e^(Abar' r) Qbar e^(Abar r) dr`` and the noise's own cost ``int_0^s tr(Qbar W(r)) dr`` (matrix
exponentials of block matrices, Van Loan's construction). Given the period's timing ``(o_k, o_{k+1},
tau_k)`` this gives ``z_{k+1} = F z_k + w_k`` and a period cost ``z_k' Qz z_k + c``.

Since the timing is independent of the state, the second moment ``P_a = E[z_k z_k' 1(o_k = a)]`` (one per
offset value ``a``: a Markov jump linear system whose mode is the current offset) obeys a linear recursion;
its fixed point is a generalised Lyapunov equation, solved here as one linear system (Kronecker form). The
loop is mean-square stable when the recursion's operator has spectral radius below 1; otherwise the cost is
infinite. ``J = E[period cost] / h``: the average period is ``h``.

With one delay value and no jitter this is the ordinary sampled-data cost (Astrom & Wittenmark,
*Computer-Controlled Systems*, ch. 11); with one delay equal to the period it is a one-sample delay loop.
Why this module is long: the stationary cost, the finite-horizon cost and the period maps they share (with
the segment integrals and the timing checks) are one computation; split, each part would need the others.

The same idea underlies Lincoln, Cervin et al.'s Jitterbug; this module is written from the mathematics
above, not from that toolbox.

Examples
--------
>>> import numpy as np
>>> loop = SampledLoop(A=[[0.0]], B=[[1.0]], C=[[1.0]], Dc=[[-2.0]], period_s=0.1, Q1=[[1.0]], Q2=[[0.0]],
...                    R1=[[1.0]])
>>> round(lqg_cost(loop).cost, 4)   # integrator, u = -2 y, no delay
0.2759
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
from scipy.linalg import expm

from netsim.errors import ConfigError

__all__ = ["TimingDistribution", "SampledLoop", "LQGCost", "lqg_cost", "transient_cost", "segment_matrices", "pid_controller"]


@dataclass(frozen=True)
class TimingDistribution:
    """A discrete distribution of a time (seconds): ``values`` with probabilities ``weights`` (normalised).

    Examples
    --------
    >>> TimingDistribution.constant(0.002).values
    (0.002,)
    >>> d = TimingDistribution.uniform(0.0, 0.004, 5)
    >>> d.values, round(sum(d.weights), 12)
    ((0.0, 0.001, 0.002, 0.003, 0.004), 1.0)
    """

    values: tuple[float, ...]
    weights: tuple[float, ...]

    def __post_init__(self) -> None:
        v = tuple(float(x) for x in self.values)
        w = np.asarray(self.weights, dtype=float)
        if len(v) == 0 or len(v) != len(w):
            raise ConfigError(f"a timing distribution needs as many weights as values, got {len(v)} and {len(w)}")
        if not np.all(np.isfinite(v)) or not np.all(np.isfinite(w)) or np.any(w < 0) or w.sum() <= 0:
            raise ConfigError("timing distribution: values must be finite and weights non-negative, not all 0")
        object.__setattr__(self, "values", v)
        object.__setattr__(self, "weights", tuple(float(x) for x in w / w.sum()))

    @classmethod
    def constant(cls, value_s: float) -> "TimingDistribution":
        """One value with probability 1."""
        return cls((value_s,), (1.0,))

    @classmethod
    def uniform(cls, low_s: float, high_s: float, n: int = 11) -> "TimingDistribution":
        """``n`` equally likely values spread evenly over ``[low_s, high_s]`` (a discretised uniform law)."""
        if n < 1 or high_s < low_s:
            raise ConfigError(f"uniform timing: need n >= 1 and high >= low, got n={n}, [{low_s}, {high_s}]")
        vals = np.linspace(low_s, high_s, n) if n > 1 else np.array([0.5 * (low_s + high_s)])
        return cls(tuple(vals), (1.0,) * n)

    @classmethod
    def empirical(cls, samples_s: Sequence[float] | np.ndarray,
                  resolution_s: float = 1e-6) -> "TimingDistribution":
        """The distribution of measured times, each rounded to ``resolution_s`` (equal values merged)."""
        s = np.asarray(samples_s, dtype=float)
        if s.size == 0 or not np.all(np.isfinite(s)):
            raise ConfigError("empirical timing: give at least one sample, all finite (drop unfinished jobs)")
        keys, counts = np.unique(np.round(s / resolution_s).astype(np.int64), return_counts=True)
        return cls(tuple(keys * resolution_s), tuple(counts.astype(float)))

    @property
    def mean(self) -> float:
        """Expected value (s)."""
        return float(np.dot(self.values, self.weights))


def _mat(value: Any, name: str, shape: tuple[int, int] | None = None) -> np.ndarray:
    arr = np.atleast_2d(np.asarray(value, dtype=float))
    if shape is not None and arr.shape != shape:
        raise ConfigError(f"SampledLoop.{name} must be {shape[0]} x {shape[1]}, got {arr.shape[0]} x {arr.shape[1]}")
    if not np.all(np.isfinite(arr)):
        raise ConfigError(f"SampledLoop.{name} contains NaN or infinite entries")
    return arr


@dataclass
class SampledLoop:
    """A continuous LTI plant, a discrete controller and the quadratic cost (see the module docstring).

    Parameters
    ----------
    A, B, C
        Plant ``n x n``, ``n x m`` and measured outputs ``p x n``.
    Ac, Bc, Cc, Dc
        Controller ``xc+ = Ac xc + Bc y``, ``u = Cc xc + Dc y`` (``nc`` states, possibly 0: a static gain ``Dc``).
        Omitted matrices are empty; ``Dc`` defaults to zeros.
    period_s
        Nominal sampling period ``h`` (s).
    Q1, Q2
        Cost weights on the state (``n x n``) and on the applied input (``m x m``), per second.
    R1
        Process noise intensity (``n x n``; default zero).
    R2
        Measurement noise covariance at each sample (``p x p``; default zero).
    """

    A: Any
    B: Any
    C: Any
    period_s: float
    Q1: Any
    Q2: Any
    Ac: Any = None
    Bc: Any = None
    Cc: Any = None
    Dc: Any = None
    R1: Any = None
    R2: Any = None
    n: int = field(init=False)
    m: int = field(init=False)
    p: int = field(init=False)
    nc: int = field(init=False)

    def __post_init__(self) -> None:
        self.A = _mat(self.A, "A")
        n = self.A.shape[0]
        if self.A.shape != (n, n):
            raise ConfigError(f"SampledLoop.A must be square, got {self.A.shape}")
        self.B = _mat(self.B, "B")
        if self.B.shape[0] != n:
            raise ConfigError(f"SampledLoop.B must have {n} rows (the states of A), got {self.B.shape[0]}")
        m = self.B.shape[1]
        self.C = _mat(self.C, "C")
        if self.C.shape[1] != n:
            raise ConfigError(f"SampledLoop.C must have {n} columns (the states of A), got {self.C.shape[1]}")
        p = self.C.shape[0]
        nc = 0 if self.Ac is None else np.atleast_2d(np.asarray(self.Ac, dtype=float)).shape[0]
        self.Ac = np.zeros((0, 0)) if nc == 0 else _mat(self.Ac, "Ac", (nc, nc))
        self.Bc = np.zeros((0, p)) if nc == 0 else _mat(self.Bc, "Bc", (nc, p))
        self.Cc = np.zeros((m, 0)) if nc == 0 else _mat(self.Cc, "Cc", (m, nc))
        self.Dc = np.zeros((m, p)) if self.Dc is None else _mat(self.Dc, "Dc", (m, p))
        self.Q1 = _mat(self.Q1, "Q1", (n, n))
        self.Q2 = _mat(self.Q2, "Q2", (m, m))
        self.R1 = np.zeros((n, n)) if self.R1 is None else _mat(self.R1, "R1", (n, n))
        self.R2 = np.zeros((p, p)) if self.R2 is None else _mat(self.R2, "R2", (p, p))
        if not (np.isfinite(self.period_s) and self.period_s > 0):
            raise ConfigError(f"SampledLoop.period_s must be a positive time in seconds, got {self.period_s}")
        self.n, self.m, self.p, self.nc = n, m, p, nc


@dataclass(frozen=True)
class LQGCost:
    """Result of :func:`lqg_cost`.

    Attributes
    ----------
    cost
        Long-run average cost per second (``inf`` when the loop is not mean-square stable).
    period_cost
        Expected cost of one period (``cost * h``).
    spectral_radius
        Of the second-moment recursion; below 1 means mean-square stable.
    covariance
        Stationary ``E[z z']`` of ``z = [x; xc; u]`` at the sampling instants (``None`` when unstable).
    """

    cost: float
    period_cost: float
    spectral_radius: float
    covariance: np.ndarray | None


def segment_matrices(
    A: np.ndarray, B: np.ndarray, Q1: np.ndarray, Q2: np.ndarray, R1: np.ndarray, s: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """One zero-order-hold segment of ``s`` seconds for ``xi = [x; u]`` (``u`` held).

    Returns
    -------
    Phi, W, Q, j
        Transition ``e^(Abar s)``, noise covariance ``int_0^s e^(Abar r) R1bar e^(Abar' r) dr``, cost matrix
        ``int_0^s e^(Abar' r) Qbar e^(Abar r) dr`` and the noise cost ``int_0^s tr(Qbar W(r)) dr``, with
        ``Abar = [[A, B], [0, 0]]``, ``Qbar = blkdiag(Q1, Q2)``, ``R1bar = blkdiag(R1, 0)``.
    """
    n, m = B.shape
    N = n + m
    Ab = np.zeros((N, N))
    Ab[:n, :n] = A
    Ab[:n, n:] = B
    Qb = np.zeros((N, N))
    Qb[:n, :n] = Q1
    Qb[n:, n:] = Q2
    Rb = np.zeros((N, N))
    Rb[:n, :n] = R1
    if s == 0.0:
        return np.eye(N), np.zeros((N, N)), np.zeros((N, N)), 0.0
    # [[-Abar', Qbar, 0], [0, Abar, R1bar], [0, 0, -Abar']] s: its blocks give e^(Abar s), the cost matrix, the
    # noise covariance and, in the corner, the double integral that carries the noise's own cost.
    M = np.zeros((3 * N, 3 * N))
    M[:N, :N] = -Ab.T
    M[:N, N : 2 * N] = Qb
    M[N : 2 * N, N : 2 * N] = Ab
    M[N : 2 * N, 2 * N :] = Rb
    M[2 * N :, 2 * N :] = -Ab.T
    E = expm(M * s)
    Phi = E[N : 2 * N, N : 2 * N]
    Q = Phi.T @ E[:N, N : 2 * N]
    W = E[N : 2 * N, 2 * N :] @ Phi.T
    # E[:N, 2N:] = int_0^s int_0^r e^(-Abar'(s-r)) Qbar e^(Abar(r-q)) R1bar e^(-Abar' q) dq dr; multiplying by
    # e^(Abar' s) on the left gives int int e^(Abar' r) Qbar e^(Abar (r-q)) R1bar e^(-Abar' q) ..., whose trace
    # after the substitution is int_0^s tr(Qbar W(r)) dr.
    j = float(np.trace(Phi.T @ E[:N, 2 * N :]))
    return Phi, 0.5 * (W + W.T), 0.5 * (Q + Q.T), j


def _period_maps(
    loop: SampledLoop,
    length: float,
    tau: float,
    jumps: Sequence[tuple[float, np.ndarray]] = (),
    sample: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """``F, Wz, Qz, c`` of one period of ``length`` s with input-output delay ``tau``: ``z+ = F z + w``,
    ``E[w w'] = Wz``, period cost ``z' Qz z + c`` (all for ``z = [x; xc; u]``).

    ``jumps`` are ``(s, J)``: at ``s`` seconds into the period the plant state becomes ``J x`` (a reference
    step carried as a plant state); a jump at ``s = 0`` comes before the sample. ``sample=False`` is a stretch without a sample (before the first one). An
    actuation after ``length``, or a jump at or after it, does not happen in this stretch.
    """
    n, m, nc = loop.n, loop.m, loop.nc
    nz = n + nc + m
    nv = nz + m  # v = [x; xc; u_held; u_new]
    ix, ic, ih, iu = slice(0, n), slice(n, n + nc), slice(n + nc, nz), slice(nz, nv)
    S = np.zeros((nv, nz))
    S[ix, ix] = np.eye(n)
    S[ih, ih] = np.eye(m)
    G = np.zeros((nv, loop.p))
    if sample:
        S[ic, ix] = loop.Bc @ loop.C
        S[ic, ic] = loop.Ac
        S[iu, ix] = loop.Dc @ loop.C
        S[iu, ic] = loop.Cc
        G[ic, :] = loop.Bc
        G[iu, :] = loop.Dc
    else:
        S[ic, ic] = np.eye(nc)
        S[iu, ih] = np.eye(m)
    Sel = np.zeros((n + m, nv))  # xi = [x; u_held]
    Sel[:n, ix] = np.eye(n)
    Sel[n:, ih] = np.eye(m)
    xi = np.r_[0:n, n + nc : nz]

    def lift(s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        Phi, W, Q, j = segment_matrices(loop.A, loop.B, loop.Q1, loop.Q2, loop.R1, s)
        T = np.eye(nv)
        T[np.ix_(xi, xi)] = Phi
        return T, Sel.T @ W @ Sel, Sel.T @ Q @ Sel, j

    switch = np.eye(nv)
    switch[ih, ih] = 0.0
    switch[ih, iu] = np.eye(m)
    events: list[tuple[float, np.ndarray | None]] = []  # (time, jump of v); None: the end of the period
    if tau <= length:
        events.append((tau, switch))
    pre = np.eye(nz)  # a jump at the very start comes before the sample (the sample sees the new reference)
    for s_j, J in jumps:
        if s_j == 0.0:
            Jz = np.eye(nz)
            Jz[ix, ix] = J
            pre = Jz @ pre
        elif 0.0 < s_j < length:
            jump = np.eye(nv)
            jump[ix, ix] = J
            events.append((s_j, jump))
    events.sort(key=lambda e: e[0])
    M = np.eye(nv)  # v now = M v(sample) + noise of covariance Wacc
    Wacc = np.zeros((nv, nv))
    Qacc = np.zeros((nv, nv))  # cost so far = v' Qacc v + c, v at the sample (noise-free part)
    c = 0.0
    t = 0.0
    for te, E in [*events, (length, None)]:
        if te > t:
            T, Wseg, Qseg, j = lift(te - t)
            Qacc += M.T @ Qseg @ M
            c += float(np.sum(Qseg * Wacc)) + j
            M = T @ M
            Wacc = T @ Wacc @ T.T + Wseg
            t = te
        if E is not None:
            M = E @ M
            Wacc = E @ Wacc @ E.T
    Drop = np.zeros((nz, nv))
    Drop[:, :nz] = np.eye(nz)
    noise_v = G @ loop.R2 @ G.T
    S = S @ pre
    F = Drop @ M @ S
    Wz = Drop @ (M @ noise_v @ M.T + Wacc) @ Drop.T
    Qz = S.T @ Qacc @ S
    c += float(np.sum(Qacc * noise_v))
    return F, 0.5 * (Wz + Wz.T), 0.5 * (Qz + Qz.T), c


def _timing(
    delay: TimingDistribution | Sequence[TimingDistribution] | float | None,
    offset: TimingDistribution | None,
    h: float,
) -> tuple[np.ndarray, np.ndarray, list[TimingDistribution]]:
    """Offsets, their probabilities and the delay distribution given each offset, checked against ``h``."""
    if offset is None:
        offset = TimingDistribution.constant(0.0)
    o, po = np.array(offset.values), np.array(offset.weights)
    if delay is None:
        delay = TimingDistribution.constant(0.0)
    elif isinstance(delay, (int, float)):
        delay = TimingDistribution.constant(float(delay))
    if isinstance(delay, TimingDistribution):
        delays = [delay] * len(o)
    else:
        delays = list(delay)
        if len(delays) != len(o) or not all(isinstance(d, TimingDistribution) for d in delays):
            raise ConfigError(f"give one delay distribution per offset value ({len(o)}), got {len(delays)}")
    for a, d in enumerate(delays):
        if min(d.values) < 0:
            raise ConfigError(f"delays must be >= 0 s, got {min(d.values)}")
        room = h + o.min() - o[a]
        if max(d.values) > room * (1 + 1e-12):
            raise ConfigError(
                f"a delay of {max(d.values):.6g} s after a sample at offset {o[a]:.6g} s reaches past the earliest "
                f"next sample ({room:.6g} s later; period {h:.6g} s): this computation needs every output to reach "
                "the plant before the next sample; shorten the delay or the jitter, or lengthen the period")
    return o, po, delays


def lqg_cost(
    loop: SampledLoop,
    delay: TimingDistribution | Sequence[TimingDistribution] | float | None = None,
    offset: TimingDistribution | None = None,
) -> LQGCost:
    """Stationary expected cost per second of ``loop`` under the delay and sampling-offset distributions.

    Parameters
    ----------
    loop
        Plant, controller, period, cost and noise.
    delay
        Input-output delay ``tau`` from the (actual) sampling instant to the actuation; a number is a constant
        delay; default 0. A list holds one distribution per offset value: the delay given that offset (timing
        measured in a schedule, where a late start often comes with a short execution window).
    offset
        Sampling offset from the nominal grid ``k h``, drawn independently each period (sampling jitter);
        default none.

    Returns
    -------
    LQGCost

    Raises
    ------
    ConfigError
        A delay that could reach past the next sample: this computation needs the output of a sample to reach the
        plant before the next sample (``offset + delay <= h + min offset`` for every pair).
    """
    h = loop.period_s
    o, po, delays = _timing(delay, offset, h)
    nz = loop.n + loop.nc + loop.m
    na = len(o)
    K = nz * nz
    # vec(P_b') = sum_a sum_tau po[b] pt (F kron F) vec(P_a) + po[b] po[a] pt vec(W)
    Op = np.zeros((na * K, na * K))
    rhs = np.zeros(na * K)
    costQ = np.zeros((na, nz, nz))
    cost_c = 0.0
    cache: dict[tuple[float, float], tuple[np.ndarray, np.ndarray, np.ndarray, float]] = {}
    for a in range(na):
        for b in range(na):
            length = h + o[b] - o[a]
            for tau, pt in zip(delays[a].values, delays[a].weights):
                key = (round(length, 15), round(min(tau, length), 15))
                if key not in cache:
                    cache[key] = _period_maps(loop, length, min(tau, length))
                F, Wz, Qz, c = cache[key]
                w = po[b] * pt
                Op[b * K : (b + 1) * K, a * K : (a + 1) * K] += w * np.kron(F, F)
                rhs[b * K : (b + 1) * K] += w * po[a] * Wz.reshape(-1)
                costQ[a] += w * Qz
                cost_c += w * po[a] * c
    rho = float(max(abs(np.linalg.eigvals(Op)))) if Op.size else 0.0
    if rho >= 1.0:
        return LQGCost(float("inf"), float("inf"), rho, None)
    vecP = np.linalg.solve(np.eye(na * K) - Op, rhs)
    Ps = [vecP[a * K : (a + 1) * K].reshape(nz, nz) for a in range(na)]
    period_cost = cost_c + sum(float(np.sum(costQ[a] * Ps[a])) for a in range(na))
    P = sum(Ps, np.zeros((nz, nz)))  # the same additions as sum(Ps), which starts from int 0
    return LQGCost(float(period_cost / h), float(period_cost), rho, 0.5 * (P + P.T))


def transient_cost(
    loop: SampledLoop,
    duration_s: float,
    x0: Any,
    delay: TimingDistribution | Sequence[TimingDistribution] | float | None = None,
    offset: TimingDistribution | None = None,
    jumps: Sequence[tuple[float, Any]] = (),
    xc0: Any = None,
    u0: Any = None,
) -> float:
    """Expected cost ``E int_0^T (x' Q1 x + u' Q2 u) dt`` of ``loop`` started at ``x0`` (finite horizon).

    The same period maps as :func:`lqg_cost`, iterated from ``E[z z'] = z0 z0'`` instead of solved for the
    stationary point: the response to an initial state or to reference steps, with noise if the loop has any.
    A reference is carried as a plant state with no dynamics (``A`` row zero), its steps as ``jumps``.

    Parameters
    ----------
    loop
        Plant, controller, period, cost (and noise).
    duration_s
        Horizon ``T`` (s).
    x0, xc0, u0
        Initial plant state, controller state (default zeros) and held input (default zeros).
    delay, offset
        As in :func:`lqg_cost`; sample ``k`` is taken at ``k h + o_k`` (the first at ``o_0``, ``u0`` held before).
    jumps
        ``(t, J)``: at time ``t`` (s) the plant state becomes ``J x``.

    Returns
    -------
    float
        The expected cost over ``[0, duration_s]``.
    """
    h = loop.period_s
    o, po, delays = _timing(delay, offset, h)
    if o.min() < 0:
        raise ConfigError(f"sampling offsets must be >= 0 s in a transient, got {o.min()}")
    J = [(float(t), _mat(Jm, "jump", (loop.n, loop.n))) for t, Jm in jumps]
    z0 = np.concatenate([
        np.asarray(x0, dtype=float).reshape(-1),
        np.zeros(loop.nc) if xc0 is None else np.asarray(xc0, dtype=float).reshape(-1),
        np.zeros(loop.m) if u0 is None else np.asarray(u0, dtype=float).reshape(-1),
    ])
    if z0.shape[0] != loop.n + loop.nc + loop.m:
        raise ConfigError(f"x0, xc0, u0 must have {loop.n}, {loop.nc} and {loop.m} entries")
    T = float(duration_s)
    cache: dict[tuple[float, float], tuple[np.ndarray, np.ndarray, np.ndarray, float]] = {}

    def maps(start: float, length: float, tau: float, sample: bool = True) -> tuple[Any, ...]:
        inside = [(t - start, Jm) for t, Jm in J if start <= t < start + length]
        if inside or start + length > T or not sample:
            return _period_maps(loop, min(length, T - start), tau, inside, sample)
        key = (round(length, 15), round(tau, 15))
        if key not in cache:
            cache[key] = _period_maps(loop, length, tau)
        return cache[key]

    cost = 0.0
    P: list[np.ndarray] = []
    Z0 = np.outer(z0, z0)
    for a in range(len(o)):
        F, W, Q, c = maps(0.0, o[a], 0.0, sample=False)
        cost += po[a] * (float(np.sum(Q * Z0)) + c)
        P.append(po[a] * (F @ Z0 @ F.T + W))
    k = 0
    while k * h + o.min() < T:
        nxt = [np.zeros_like(P[0]) for _ in o]
        for a in range(len(o)):
            start = k * h + o[a]
            if start >= T:
                continue
            for b in range(len(o)):
                length = h + o[b] - o[a]
                for tau, pt in zip(delays[a].values, delays[a].weights):
                    F, W, Q, c = maps(start, length, tau)
                    w = po[b] * pt
                    cost += w * (float(np.sum(Q * P[a])) + po[a] * c)
                    if start + length < T:
                        nxt[b] += w * (F @ P[a] @ F.T + po[a] * W)
        P = nxt
        k += 1
    return float(cost)


def pid_controller(
    K: float, Ti: float | None, Td: float, N: float, h: float, b: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(Ac, Bc, Cc, Dc)`` of netsim's discrete PID (:class:`netsim.control.pid.PID`).

    ``D = ad D - bd (y - y_prev)`` with ``ad = Td / (Td + N h)``, ``bd = K N ad``; ``u = K (b r - y) + I + D``;
    then ``I += K h / Ti (r - y)`` (``Ti=None``: no integral). States ``[I; D; y_prev]``. With ``b=None`` the
    input is ``y`` alone (regulation to ``r = 0``); with a set-point weight ``b`` it is ``[r; y]``.
    """
    ad = Td / (Td + N * h) if Td > 0 else 0.0
    bd = K * N * ad
    ki = 0.0 if Ti is None or Ti == 0 else K * h / Ti
    Ac = np.array([[1.0, 0.0, 0.0], [0.0, ad, bd], [0.0, 0.0, 0.0]])
    Cc = np.array([[1.0, ad, bd]])
    By = np.array([[-ki], [-bd], [1.0]])
    Dy = np.array([[-K - bd]])
    if b is None:
        return Ac, By, Cc, Dy
    return Ac, np.hstack([np.array([[ki], [0.0], [0.0]]), By]), Cc, np.hstack([np.array([[K * b]]), Dy])
