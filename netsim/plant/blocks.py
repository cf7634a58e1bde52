"""Independent blocks of an LTI plant, each propagated only when one of its own signals is read or written.

A plant made of many uncoupled parts (``dc_servo`` with ``count: 200`` is 200 servos in one block-diagonal model)
would otherwise advance every state at every ADC read and take the matrix exponential of the whole augmented
model, ``(2N + N)``-square, for every new step length. :func:`independent_parts` splits the model into its
connected parts (states, inputs and outputs linked by a nonzero entry of ``A``, ``B``, ``C`` or ``D``);
:class:`Blocks` keeps one time per part, steps a part with its own small transition (one ``expm`` per distinct
part model and step length, shared by identical parts) and reads an output from its part alone. The cost of a
read or a write is then that of one part, whatever the number of parts.

:class:`~netsim.plant.lti.LTIPlant` uses blocks when the plant has at least :data:`MIN_BLOCKS` parts and nothing
couples them in time: no disturbance or noise source, no process noise, no state recording, no input-change
listener (an exact encoder). Anything that needs the whole state (a full ``advance_to``: the record grid, the end
of the run, ``state()``, ``output()``) first brings every part to that instant. Below :data:`MIN_BLOCKS` parts the
joint propagation is kept: its product costs about one part's there, and its floating-point sums (one BLAS
product over the joint vector) are the ones the shipped three-servo scenarios were pinned with. A full advance
updates the parts that share a model and a step length with one matrix product (rows of a batched product may
differ from a single part's product in the last bit; both stay within 1e-12 of the joint model).
"""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from netsim.plant.base import Plant
from netsim.plant.shared import matvec

__all__ = ["MIN_BLOCKS", "Blocks", "PartwiseLTI", "independent_parts"]

Transition = Callable[[np.ndarray, np.ndarray, float], tuple[np.ndarray, np.ndarray]]

#: Fewest independent parts for which an LTI plant propagates them separately. Below it the joint product is about
#: as cheap as one part's step (per read: 4.6 us either way at 10 servos, 7.2 against 4.6 at 50), and a record grid's
#: full advance (one product jointly, a grouped update of every part here) favours the joint model.
MIN_BLOCKS = 32


def independent_parts(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray
                      ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The connected parts of ``x' = A x + B u, y = C x + D u`` as ``(states, inputs, outputs)`` index arrays,
    ordered by their first state (parts without states last, by input then output)."""
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    parent = list(range(n + m + p))  # union-find over states, then inputs, then outputs

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    def join(i: int, j: int) -> None:
        ri, rj = root(i), root(j)
        if ri != rj:
            parent[max(ri, rj)] = min(ri, rj)

    for (i, j) in zip(*np.nonzero(A)):
        join(int(i), int(j))
    for (i, k) in zip(*np.nonzero(B)):
        join(int(i), n + int(k))
    for (r, i) in zip(*np.nonzero(C)):
        join(n + m + int(r), int(i))
    for (r, k) in zip(*np.nonzero(D)):
        join(n + m + int(r), n + int(k))
    groups: dict[int, list[int]] = {}
    for i in range(n + m + p):
        groups.setdefault(root(i), []).append(i)
    out = []
    for members in sorted(groups.values()):
        arr = np.array(members)
        out.append((arr[arr < n], arr[(arr >= n) & (arr < n + m)] - n, arr[arr >= n + m] - n - m))
    return out


class Blocks:
    """Per-part times and transitions of an LTI plant's independent parts (see the module docstring).

    Parameters
    ----------
    A, B, C, D
        The plant's matrices.
    parts
        :func:`independent_parts` of them.
    t0
        The instant every part starts at (ns).
    transition
        ``transition(A_part, B_part, h_s) -> (Ad, Bd)``, the exact zero-order-hold step.
    """

    def __init__(self, A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                 parts: list[tuple[np.ndarray, np.ndarray, np.ndarray]], t0: int,
                 transition: Transition) -> None:
        n, m = A.shape[0], B.shape[1]
        self.n_parts = len(parts)
        self.times = np.full(len(parts), int(t0), dtype=np.int64)  # each part's own instant (ns)
        self.gather: list[np.ndarray] = []  # indices of [z; u] a part's step reads: its states, then its inputs
        self.states: list[np.ndarray] = []
        self.models: list[tuple[np.ndarray, np.ndarray, bytes]] = []
        self.of_input = np.zeros(m, dtype=int)
        self.of_output = np.zeros(C.shape[0], dtype=int)
        self.rows: dict[int, Callable[[np.ndarray], np.ndarray]] = {}  # output -> product with its part's [z; u]
        for c, (xs, us, ys) in enumerate(parts):
            self.gather.append(np.concatenate((xs, n + us)).astype(int))
            self.states.append(xs)
            Ac, Bc = A[np.ix_(xs, xs)], B[np.ix_(xs, us)]
            self.models.append((Ac, Bc, Ac.tobytes() + b"|" + Bc.tobytes() + repr(Bc.shape).encode()))
            self.of_input[us] = c
            self.of_output[ys] = c
            for r in ys:
                self.rows[int(r)] = matvec(np.concatenate((C[r, xs], D[r, us]))[None, :])
        ids: dict[bytes, int] = {}
        self.model_id = np.array([ids.setdefault(key, len(ids)) for _, _, key in self.models], dtype=np.int64)
        widths = {g.size for g in self.gather}
        # every part's gather indices as one array (rows by part) when they all have one width: batched steps
        self.gather2d = np.array(self.gather) if len(widths) == 1 and parts and parts[0][0].size else None
        self._transition = transition
        # (model, step length) -> (product with a part's [z; u], the transition [Ad Bd] itself)
        self._cache: dict[tuple[bytes, int], tuple[Callable[[np.ndarray], np.ndarray], np.ndarray]] = {}
        self.sq = np.zeros(len(parts))  # squared norm of each part's state at its own time
        self.expm_count = 0

    def _entry(self, c: int, h: int) -> tuple[Callable[[np.ndarray], np.ndarray], np.ndarray]:
        Ac, Bc, key = self.models[c]
        entry = self._cache.get((key, h))
        if entry is None:
            Ad, Bd = self._transition(Ac, Bc, h / 1e9)
            self.expm_count += 1
            G = np.ascontiguousarray(np.hstack((Ad, Bd)))
            if len(self._cache) >= 4096:
                self._cache.clear()
            entry = self._cache[(key, h)] = (matvec(G), G)
        return entry

    def step(self, c: int, t: int, zu: np.ndarray) -> float:
        """Propagate part ``c`` to ``t`` (``t`` after its time) in ``zu`` (the plant's ``[z; u]``); returns the
        sum of every part's squared state norm (the divergence check)."""
        xs = self.states[c]
        if xs.size:
            z = self._entry(c, t - int(self.times[c]))[0](zu[self.gather[c]])
            zu[xs] = z
            self.sq[c] = z.dot(z)
        self.times[c] = t
        return float(self.sq.sum())

    def sync(self, t: int, zu: np.ndarray) -> float:
        """Bring every part to ``t`` (at or after each part's time); returns :meth:`step`'s sum.

        Parts of one model with the same step length (after a record-grid sample, all that were not read or written
        since) take one matrix product together, found with numpy: a full advance costs a few products and no
        Python work per part.
        """
        behind = np.flatnonzero(self.times < t)
        if behind.size < 4 or self.gather2d is None:
            for c in behind.tolist():
                self.step(c, t, zu)
            return float(self.sq.sum())
        if behind.size < 64:  # grouped in Python: cheaper than numpy's sort for a few dozen parts
            groups: dict[tuple[int, int], list[int]] = {}
            times, mid = self.times.tolist(), self.model_id.tolist()
            for c in behind.tolist():
                groups.setdefault((mid[c], t - times[c]), []).append(c)
            batches = [np.array(cs) for cs in groups.values()]
        else:  # grouped by numpy: a sort by (model, step length), cut where either changes
            h, mids = t - self.times[behind], self.model_id[behind]
            order = np.lexsort((h, mids))
            h, mids, behind = h[order], mids[order], behind[order]
            batches = np.split(behind, np.flatnonzero((np.diff(h) != 0) | (np.diff(mids) != 0)) + 1)
        n_x = self.states[0].size
        for cs in batches:
            if cs.size < 4:
                for c in cs.tolist():
                    self.step(c, t, zu)
                continue
            idx = self.gather2d[cs]
            Z = zu[idx] @ self._entry(int(cs[0]), t - int(self.times[cs[0]]))[1].T  # one row per part: its new state
            zu[idx[:, :n_x]] = Z
            self.sq[cs] = np.einsum("ij,ij->i", Z, Z)
            self.times[cs] = t
        return float(self.sq.sum())

    def output(self, r: int, zu: np.ndarray) -> float:
        """Output ``r`` from its part's states and inputs (the part must be at the instant wanted)."""
        return float(self.rows[r](zu[self.gather[int(self.of_output[r])]])[0])


class PartwiseLTI(Plant):
    """The part of :class:`~netsim.plant.lti.LTIPlant` that reads and writes one independent part at a time
    (a base class of it, placed before the LTI machinery so that its ``output_value``/``set_input`` come first).

    While :attr:`_blocks` is set, ``_zu`` holds every part's state at that part's own time (``Blocks.times``) and
    ``_t`` the latest of them; a full advance brings every part to one instant.
    """

    _blocks: Blocks | None = None
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    _zu: np.ndarray
    _nz: int
    _noisy: bool

    def _make_blocks(self, transition: Transition) -> Blocks | None:
        """Per-part propagation when the plant has at least MIN_BLOCKS uncoupled parts and nothing else."""
        if self._sources or self._noisy or self._record_events or self._listeners or self._nz != self.n_states:
            return None
        parts = independent_parts(self.A, self.B, self.C, self.D)
        return Blocks(self.A, self.B, self.C, self.D, parts, self._t, transition) if len(parts) >= MIN_BLOCKS else None

    def _unblock(self) -> None:
        """Bring every part to the plant's time and propagate jointly from now on."""
        if self._blocks is not None:
            self._advance_blocks(self._t)
            self._blocks = None

    def _advance_part(self, c: int, t: int) -> None:
        blocks = self._blocks
        assert blocks is not None
        if t < self._t:  # as a joint plant: no instant before the latest read or write of any part
            self._backwards(t)
        tc = int(blocks.times[c])
        if t > tc:
            if not (blocks.step(c, t, self._zu) <= self._bound2):
                self._diverged(t, self._zu[: self._nz])
            if t > self._t:
                self._t = t
            self._y = None

    def _advance_blocks(self, t: int) -> None:
        if t < self._t:
            self._backwards(t)
        blocks = self._blocks
        assert blocks is not None
        if not (blocks.sync(t, self._zu) <= self._bound2):
            self._diverged(t, self._zu[: self._nz])
        self._t = t
        self._y = None

    def output_value(self, index: int, t_ns: int | None = None) -> float:
        blocks = self._blocks
        if blocks is None:
            return super().output_value(index, t_ns)
        self._advance_part(int(blocks.of_output[index]), self._now(None) if t_ns is None else int(t_ns))
        return blocks.output(index, self._zu)

    def set_input(self, key: int | str, value: float, t_ns: int | None = None) -> None:
        blocks = self._blocks
        v = float(value)
        if blocks is None or not math.isfinite(v):
            return super().set_input(key, value, t_ns)
        i = key if type(key) is int and 0 <= key < self.n_inputs else self.input_index(key)
        self._advance_part(int(blocks.of_input[i]), self._now(None) if t_ns is None else int(t_ns))
        if self._u[i] != v:
            self._u[i] = v
            self._zu[self._nz + i] = v  # the effective input: a plant with blocks has no disturbance sources
            self._y = None

    def bind(self, env: Any, **kwargs: Any) -> "Plant":
        out = super().bind(env, **kwargs)
        if self._record_events:  # the state is recorded at every advance: one time for the whole state
            self._unblock()
        return out

    def on_input_change(self, callback: Callable[[int], None]) -> Callable[[], None]:
        self._unblock()  # a listener (an exact encoder) predicts from the whole state
        return super().on_input_change(callback)
