"""Checks of the matrices a control design is built from, with messages that name the parameter.

Every estimator and control law in :mod:`netsim.control` runs these at construction, so a wrong dimension, a
weight that is not positive (semi)definite, or a mode the input cannot move or the output cannot see is
reported once, before a run starts, as a :class:`~netsim.errors.ConfigError` whose message names the parameter
(and, for stabilisability and detectability, the eigenvalue of the offending mode).

Stabilisability and detectability use the Popov-Belevitch-Hautus test: the discrete pair ``(A, B)`` is
stabilisable when ``rank [A - lambda I, B] = n`` for every eigenvalue ``lambda`` of ``A`` with
``|lambda| >= 1``; ``(A, C)`` is detectable when ``(A', C')`` is stabilisable.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from netsim.errors import ConfigError

__all__ = [
    "as_input_matrix",
    "as_matrix",
    "as_vector",
    "check_weight",
    "check_stabilizable",
    "check_detectable",
    "check_poles",
    "uncontrollable_modes",
]

# relative tolerance of the rank decisions (singular values below it times the largest are taken as zero)
RANK_RTOL = 1e-9
# relative tolerance of the symmetry and definiteness checks of weights and covariances
PSD_RTOL = 1e-10


def as_matrix(name: str, value: Any, shape: tuple[int | None, int | None] | None = None) -> np.ndarray:
    """A finite 2-D float array from ``value`` (a scalar or a 1-D list becomes a 1x1 or 1xn matrix).

    Parameters
    ----------
    name
        Parameter name used in the error message.
    value
        Anything :func:`numpy.asarray` accepts.
    shape
        Expected ``(rows, cols)``; ``None`` in either place accepts any size.

    Raises
    ------
    ConfigError
        When ``value`` is not numeric, has more than two dimensions, contains NaN/Inf or has the wrong shape.
    """
    try:
        M = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"{name} must be a numeric matrix, got {value!r:.80}") from exc
    if M.ndim == 0:
        M = M.reshape(1, 1)
    elif M.ndim == 1:
        M = M.reshape(1, -1)
    elif M.ndim > 2:
        raise ConfigError(f"{name} must be a matrix (2-D), got an array of shape {M.shape}")
    if not np.all(np.isfinite(M)):
        raise ConfigError(f"{name} contains NaN or infinite entries")
    if shape is not None:
        rows, cols = shape
        if (rows is not None and M.shape[0] != rows) or (cols is not None and M.shape[1] != cols):
            want = f"{'any' if rows is None else rows}x{'any' if cols is None else cols}"
            raise ConfigError(f"{name} must be {want}, got {M.shape[0]}x{M.shape[1]}")
    return M


def as_input_matrix(name: str, value: Any, n: int) -> np.ndarray:
    """An ``n x m`` input matrix; a 1-D list of ``n`` numbers is one column (a single input).

    Raises
    ------
    ConfigError
        When the value is not numeric or has not ``n`` rows.
    """
    if np.ndim(value) == 1 and n > 1:
        value = np.reshape(np.asarray(value, dtype=object), (-1, 1)).tolist()
    return as_matrix(name, value, (n, None))


def as_vector(name: str, value: Any, size: int) -> np.ndarray:
    """A finite 1-D float array of length ``size`` (a scalar is accepted when ``size`` is 1).

    Raises
    ------
    ConfigError
        When the value is not numeric, not finite or of the wrong length.
    """
    try:
        v = np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"{name} must be a numeric vector of length {size}, got {value!r:.80}") from exc
    if v.size != size:
        raise ConfigError(f"{name} must have {size} entries, got {v.size}")
    if not np.all(np.isfinite(v)):
        raise ConfigError(f"{name} contains NaN or infinite entries")
    return v


def check_square(name: str, M: np.ndarray) -> int:
    """Return the size of a square matrix; raise :class:`ConfigError` naming ``name`` otherwise."""
    if M.shape[0] != M.shape[1]:
        raise ConfigError(f"{name} must be square (n x n), got {M.shape[0]}x{M.shape[1]}")
    return M.shape[0]


def check_weight(name: str, value: Any, size: int, *, definite: bool) -> np.ndarray:
    """A symmetric ``size x size`` weight or covariance, positive definite or semidefinite.

    A scalar is taken as ``value * I`` and a vector as a diagonal matrix, so ``Q: [1, 0, 1, 0]`` works.

    Parameters
    ----------
    name
        Parameter name used in messages.
    value
        Scalar, vector of length ``size``, or ``size x size`` matrix.
    size
        Required dimension.
    definite
        ``True`` requires positive definite, ``False`` positive semidefinite.

    Raises
    ------
    ConfigError
        Wrong size, not symmetric, or an eigenvalue below zero (or at zero when ``definite``).
    """
    try:
        arr = np.array(value, dtype=float) if not isinstance(value, np.ndarray) else value.astype(float)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number (times the identity), a list (the diagonal) or a {size}x{size} "
                          f"matrix of numbers, got {str(value)[:60]!r}") from None
    if arr.ndim == 0:
        W = float(arr) * np.eye(size)
    elif arr.ndim == 1:
        if arr.size != size:
            raise ConfigError(f"{name} given as a diagonal must have {size} entries, got {arr.size}")
        W = np.diag(arr)
    else:
        W = as_matrix(name, arr, (size, size))
    if not np.all(np.isfinite(W)):
        raise ConfigError(f"{name} contains NaN or infinite entries")
    scale = max(1.0, float(np.max(np.abs(W))))
    if np.max(np.abs(W - W.T)) > PSD_RTOL * scale:
        raise ConfigError(f"{name} must be symmetric (largest asymmetry {np.max(np.abs(W - W.T)):.3g})")
    W = 0.5 * (W + W.T)
    low = float(np.min(np.linalg.eigvalsh(W)))
    if definite and not low > PSD_RTOL * scale:
        raise ConfigError(f"{name} must be positive definite (smallest eigenvalue {low:.3g}); increase its diagonal")
    if not definite and low < -PSD_RTOL * scale:
        raise ConfigError(f"{name} must be positive semidefinite (smallest eigenvalue {low:.3g})")
    return W


def _rank_deficient(M: np.ndarray) -> bool:
    s = np.linalg.svd(M, compute_uv=False)
    n = min(M.shape)
    return s.size < n or s[n - 1] <= RANK_RTOL * max(1.0, s[0])


def uncontrollable_modes(A: np.ndarray, B: np.ndarray, *, only_unstable: bool = True) -> list[complex]:
    """Eigenvalues of ``A`` whose mode the input ``B`` cannot move (PBH test).

    Parameters
    ----------
    A, B
        The discrete pair.
    only_unstable
        List only modes with ``|lambda| >= 1`` (the ones that make the pair unstabilisable).
    """
    n = A.shape[0]
    out: list[complex] = []
    for lam in np.linalg.eigvals(A):
        if only_unstable and abs(lam) < 1.0 - 1e-12:
            continue
        if _rank_deficient(np.hstack([A - lam * np.eye(n), B])):
            if not any(abs(lam - seen) < 1e-9 for seen in out):
                out.append(complex(lam))
    return out


def _fmt(lam: complex) -> str:
    return f"{lam.real:.6g}" if abs(lam.imag) < 1e-12 else f"{lam.real:.6g}{lam.imag:+.6g}j"


def check_stabilizable(A: np.ndarray, B: np.ndarray, *, what: str = "(A, B)") -> None:
    """Raise :class:`ConfigError` naming each unstable mode the input cannot move."""
    bad = uncontrollable_modes(A, B)
    if bad:
        modes = ", ".join(_fmt(m) for m in bad)
        raise ConfigError(
            f"the pair {what} is not stabilisable: the mode(s) at eigenvalue {modes} of A (|lambda| >= 1) cannot be "
            "moved by the input; add an actuator that reaches them or change the model"
        )


def check_detectable(A: np.ndarray, C: np.ndarray, *, what: str = "(A, C)") -> None:
    """Raise :class:`ConfigError` naming each unstable mode the measurement cannot see."""
    bad = uncontrollable_modes(A.T, C.T)
    if bad:
        modes = ", ".join(_fmt(m) for m in bad)
        raise ConfigError(
            f"the pair {what} is not detectable: the mode(s) at eigenvalue {modes} of A (|lambda| >= 1) do not show in "
            "the measurement; measure another output or change the model"
        )


def check_poles(name: str, poles: Sequence[complex] | np.ndarray, n: int) -> np.ndarray:
    """``n`` discrete poles strictly inside the unit circle, complex ones in conjugate pairs.

    Raises
    ------
    ConfigError
        Wrong count, a pole on or outside the unit circle, or a complex pole without its conjugate.
    """
    try:
        p = np.array(poles, dtype=complex).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"{name} must be a list of {n} numbers, got {poles!r:.80}") from exc
    if p.size != n:
        raise ConfigError(f"{name} must list {n} poles (one per state), got {p.size}")
    if not np.all(np.isfinite(p)):
        raise ConfigError(f"{name} contains NaN or infinite entries")
    outside = [q for q in p if abs(q) >= 1.0]
    if outside:
        raise ConfigError(
            f"{name} must lie strictly inside the unit circle for a discrete observer; "
            f"{', '.join(_fmt(q) for q in outside)} (|p| >= 1) would not converge"
        )
    for q in p:
        if abs(q.imag) > 1e-12 and not np.any(np.abs(p - np.conj(q)) < 1e-9):
            raise ConfigError(f"{name}: the complex pole {_fmt(q)} needs its conjugate in the list")
    return p
