"""Matrix parameters of the control parts as typed values: parsed once from YAML, converted once at design.

``Q: [0, 0.01]`` in a scenario becomes a :class:`Weight` when the scenario is validated (the one parse:
numbers, at most two levels of lists, square); the estimator or law makes the one conversion to the matrix of
the model's size where that size is known (:func:`~netsim.control.design_checks.check_weight`: a number times
the identity, a list the diagonal; size, symmetry and definiteness checked with messages naming the parameter).
"""

from __future__ import annotations

from typing import Annotated, Any, ClassVar

import numpy as np
from pydantic import PlainSerializer, PlainValidator, WithJsonSchema

__all__ = ["MatrixField", "Matrix", "WeightField", "Weight"]


class Matrix:
    """A matrix parameter as parsed from YAML, once: a number, a list or a list of rows of finite floats.

    ``given`` is the value as written (what the resolved scenario shows), ``array`` the parsed float array
    (0-D, 1-D or 2-D, read-only). ``np.asarray(value)`` gives ``array``, so the constructors of
    :mod:`netsim.control` take it where they take a list; they make the one conversion to the matrix of the
    model's size (:func:`~netsim.control.design_checks.check_weight`, ``as_matrix``), where ``n`` is known.
    :data:`parses` counts the parses (the tests count them per run).
    """

    __slots__ = ("given", "array")
    #: Parses made in this process (by :func:`_parse_matrix`).
    parses: ClassVar[int] = 0

    def __init__(self, given: Any, array: np.ndarray) -> None:
        self.given = given
        array.setflags(write=False)
        self.array = array

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        return self.array if dtype is None else self.array.astype(dtype)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.given!r})"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Matrix) and self.given == other.given

    def __hash__(self) -> int:
        return hash(repr(self.given))


class Weight(Matrix):
    """A weight or covariance as parsed: a number (times the identity), a list (the diagonal) or a square matrix."""

    __slots__ = ()


def _plain(value: Any) -> Any:
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def _parse_matrix(value: Any, square: bool) -> np.ndarray:
    Matrix.parses += 1
    if isinstance(value, bool) or (isinstance(value, (list, tuple)) and any(isinstance(v, bool) for v in value)):
        raise ValueError(f"expected numbers, got {str(value)[:60]!r}")
    what = "a number (times the identity), a list (the diagonal) or a square matrix" if square else "a matrix"
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"must be {what} of numbers (a list of rows), got {str(value)[:60]!r}") from None
    if arr.ndim > 2:
        raise ValueError(f"must be {what} (at most two levels of lists), got an array of shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("contains NaN or infinite entries")
    if square and arr.ndim == 2 and arr.shape[0] != arr.shape[1]:
        raise ValueError(f"must be square (n x n), got {arr.shape[0]}x{arr.shape[1]}")
    return arr


def _weight(value: Any) -> Weight:
    if isinstance(value, Matrix):
        return Weight(value.given, value.array)
    return Weight(_plain(value), _parse_matrix(value, square=True))


def _matrix(value: Any) -> Matrix:
    if isinstance(value, Matrix):
        return value
    return Matrix(_plain(value), _parse_matrix(value, square=False))


_NUMBERS = {"type": "array", "items": {"type": "number"}}
#: A weight or covariance: a number (times the identity), a list (the diagonal) or a square matrix (rows),
#: parsed once into a :class:`Weight` (finite numbers, at most 2-D, square); its size and definiteness are
#: checked where the model's size is known (:func:`~netsim.control.design_checks.check_weight`).
WeightField = Annotated[Weight, PlainValidator(_weight), PlainSerializer(lambda w: w.given),
                   WithJsonSchema({"anyOf": [{"type": "number"}, _NUMBERS, {"type": "array", "items": _NUMBERS}]})]
#: A gain or cross weight: a number, a list (one row) or a matrix of finite numbers, parsed once.
MatrixField = Annotated[Matrix, PlainValidator(_matrix), PlainSerializer(lambda m: m.given),
                   WithJsonSchema({"anyOf": [{"type": "number"}, _NUMBERS, {"type": "array", "items": _NUMBERS}]})]
