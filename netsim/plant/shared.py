"""Validation helpers and constants shared by the plant modules of :mod:`netsim.plant`."""

from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np

from netsim.errors import ConfigError

__all__ = ["NEVER", "as_matrix", "matvec", "psd_factor"]

#: "Never" as an integer time (about 146 years in ns): larger than any simulated instant.
NEVER = 2**62


def as_matrix(name: str, value: Any, shape: tuple[int | None, int | None] | None = None) -> np.ndarray:
    """``value`` as a finite 2-D float array, or a :class:`ConfigError` naming the matrix ``name``.

    A scalar becomes 1x1. ``shape`` entries that are not None must match.
    """
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"matrix {name} is not numeric: {exc}") from None
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    if arr.ndim != 2:
        raise ConfigError(f"matrix {name} must be 2-D, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ConfigError(f"matrix {name} contains NaN or Inf; give finite numbers")
    if shape is not None:
        for axis, want in enumerate(shape):
            if want is not None and arr.shape[axis] != want:
                raise ConfigError(
                    f"matrix {name} has shape {arr.shape}, expected "
                    f"({'any' if shape[0] is None else shape[0]}, {'any' if shape[1] is None else shape[1]})"
                )
    return arr


def matvec(M: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """The product ``v -> M @ v`` with a 2-D ``M`` (bit for bit), as a bound method to keep and call.

    With two or more columns, ``M.dot`` calls the same BLAS routine as ``@`` (the same bits) at a fraction
    of its call overhead on the small arrays of a plant step (about 0.7 us against 3 us for a 10 x 10
    product). With one column ``dot`` multiplies by a scalar instead, which can differ from ``@`` in the
    sign of a zero result (and for ``0 * inf``), so the operator itself (``M.__matmul__``) is used there.
    """
    return M.dot if M.shape[1] > 1 else M.__matmul__


def _names(kind: str, given: Sequence[str] | None, n: int, prefix: str) -> list[str]:
    if given is None:
        return [f"{prefix}[{i}]" for i in range(n)]
    names = [str(g) for g in given]
    if len(names) != n:
        raise ConfigError(f"{kind} names: {len(names)} given for {n} {kind}s")
    if len(set(names)) != len(names):
        raise ConfigError(f"{kind} names must be unique, got {names}")
    return names


def _vector(name: str, value: Any, n: int) -> np.ndarray:
    arr = np.array(value, dtype=float).ravel()
    if arr.size == 1 and n != 1:
        arr = np.full(n, float(arr[0]))
    if arr.size != n:
        raise ConfigError(f"{name} must have {n} entries, got {arr.size}")
    if not np.all(np.isfinite(arr)):
        raise ConfigError(f"{name} contains NaN or Inf")
    return arr




def psd_factor(name: str, Q: np.ndarray) -> np.ndarray:
    """A square factor ``L`` with ``L @ L.T == Q`` for a symmetric positive semi-definite ``Q``."""
    Q = 0.5 * (Q + Q.T)
    w, V = np.linalg.eigh(Q)
    scale = max(float(np.max(np.abs(w))) if w.size else 0.0, 1e-300)
    if np.min(w) < -1e-9 * scale:
        raise ConfigError(f"{name} must be positive semi-definite (eigenvalue {np.min(w):.3g})")
    return V * np.sqrt(np.clip(w, 0.0, None))
