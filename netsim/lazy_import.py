"""A module imported at its first use, for heavy libraries a module needs only in some of its functions.

``pd = lazy_module("pandas")`` at the top of a module reads like ``import pandas as pd``, but pandas is
imported only when an attribute of ``pd`` is first read (a case-study report module is imported by
``netsim list`` and ``netsim docs``, which never build a table; issue 19: nothing imported that a command
does not use). Annotations are unaffected under ``from __future__ import annotations``.
"""

from __future__ import annotations

import importlib
from types import ModuleType
from typing import Any

__all__ = ["lazy_module"]


class _LazyModule:
    """Stands for the module ``name`` and imports it at the first attribute read."""

    __slots__ = ("_name",)

    def __init__(self, name: str) -> None:
        self._name = name

    def __getattr__(self, attr: str) -> Any:
        return getattr(importlib.import_module(self._name), attr)

    def __repr__(self) -> str:
        return f"<lazy module {self._name!r}>"


def lazy_module(name: str) -> ModuleType:
    """A stand-in for ``import name`` that imports the module when one of its attributes is first read.

    Parameters
    ----------
    name
        The module's dotted name (``"pandas"``, ``"scipy.sparse"``).

    Examples
    --------
    >>> np_later = lazy_module("math")
    >>> np_later.sqrt(4.0)
    2.0
    """
    return _LazyModule(name)  # type: ignore[return-value]  # duck-typed: attribute access is all it offers
