"""Every global name a case-study report function reads exists in its module.

The reports run for many minutes and are opt-in, so a name that only exists through a module ``__getattr__``
(read from outside as ``module.NAME``, but a NameError inside the module) would surface at the very end of a
long run; this reads the bytecode instead.
"""

from __future__ import annotations

import builtins
import dis
import importlib
import types

import pytest

import netsim  # noqa: F401 - pins BLAS before numpy is imported by the models

REPORT_MODULES = ["netsim.models.hdd_report", "netsim.models.pendulum.report", "netsim.models.unicycle.report", "netsim.models.cart.report"]


def _code_objects(code: types.CodeType):
    yield code
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            yield from _code_objects(const)


@pytest.mark.parametrize("name", REPORT_MODULES)
def test_every_global_a_report_function_reads_is_defined(name: str) -> None:
    module = importlib.import_module(name)
    defined = set(vars(module)) | set(vars(builtins))
    missing = set()
    for obj in vars(module).values():
        if isinstance(obj, types.FunctionType) and obj.__module__ == name:
            for code in _code_objects(obj.__code__):
                for ins in dis.get_instructions(code):
                    if ins.opname == "LOAD_GLOBAL" and ins.argval not in defined:
                        missing.add(f"{obj.__name__}: {ins.argval}")
    assert not missing, sorted(missing)
