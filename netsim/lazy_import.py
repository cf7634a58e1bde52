"""A module imported at its first use, for heavy libraries a module needs only in some of its functions.

``pd = lazy_module("pandas")`` at the top of a module reads like ``import pandas as pd``, but pandas is
imported only when an attribute of ``pd`` is first read (a case-study report module is imported by
``netsim list`` and ``netsim docs``, which never build a table; issue 19: nothing imported that a command
does not use). Annotations are unaffected under ``from __future__ import annotations``; for the type checker
(.ci/mypy), which cannot take ``pd.DataFrame`` in an annotation from a variable, import the real module for it
alone::

    if TYPE_CHECKING:
        import pandas as pd
    else:
        pd = lazy_module("pandas")
"""

from __future__ import annotations

import importlib
import sys
import warnings
from collections.abc import Callable, Mapping
from types import ModuleType
from typing import Any

__all__ = ["callable_module", "lazy_exports", "lazy_module"]


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


def lazy_exports(package: str, where: Mapping[str, str]) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """A package's ``__getattr__`` and ``__dir__`` (PEP 562) for names imported from their modules at first use.

    Importing one submodule runs its package's ``__init__``; with these, that ``__init__`` imports nothing, and
    ``package.Name`` still works (issue 19: importing one control law or one medium must not import them all).

    Parameters
    ----------
    package
        The package's ``__name__``.
    where
        Exported name -> the dotted name of the module that defines it.

    Returns
    -------
    tuple
        ``(__getattr__, __dir__)``: assign them in the package (``__getattr__, __dir__ = lazy_exports(...)``).
        A name read once is stored in the package, so later reads are plain attribute reads.
    """
    import sys

    def __getattr__(name: str) -> Any:
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(where))

    return __getattr__, __dir__


class _CallableModule(ModuleType):
    """A module that can be called: it warns (``DeprecationWarning``) and calls the function it names.

    Before issue 27, ``netsim.sweep`` and ``netsim.report`` were functions until their module was first imported,
    and modules from then on. They are now always the modules; calling one still works, through this class.
    """

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        module, attr, instead = self.__dict__["__call_target__"]
        warnings.warn(f"calling the module {self.__name__} is deprecated: call {instead}(...) instead",
                      DeprecationWarning, stacklevel=2)
        return getattr(importlib.import_module(module), attr)(*args, **kwargs)


def callable_module(name: str, target: str, instead: str) -> None:
    """Make the (imported) module ``name`` callable, as a deprecated alias of the function ``target``.

    Parameters
    ----------
    name : str
        The module's ``__name__`` (call this at the end of the module itself, so that every import path gives
        the same callable module).
    target : str
        ``"package.module:function"``: what a call runs (imported at the call).
    instead : str
        The name the deprecation warning tells the caller to use (``"netsim.run_sweep"``).

    Examples
    --------
    >>> import types, sys
    >>> sys.modules["old_api"] = types.ModuleType("old_api")
    >>> callable_module("old_api", "math:sqrt", "math.sqrt")
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     sys.modules["old_api"](4.0)
    2.0
    """
    module, _, attr = target.partition(":")
    mod = sys.modules[name]
    mod.__dict__["__call_target__"] = (module, attr, instead)
    mod.__class__ = _CallableModule
