"""netsim.lazy_import: a package's names imported from their modules at first use, and lazily imported modules."""

from __future__ import annotations

import subprocess
import sys
import types

import pytest

from netsim.lazy_import import lazy_exports, lazy_module


def test_a_lazy_export_is_imported_at_first_read_then_kept_in_the_package() -> None:
    pkg = types.ModuleType("fake_pkg")
    sys.modules["fake_pkg"] = pkg
    try:
        pkg.__getattr__, pkg.__dir__ = lazy_exports("fake_pkg", {"sqrt": "math", "dumps": "json"})
        assert "dumps" not in vars(pkg) and "dumps" in pkg.__dir__()
        import json

        assert pkg.dumps is json.dumps and vars(pkg)["dumps"] is json.dumps  # kept: the next read is plain
        with pytest.raises(AttributeError, match="'fake_pkg' has no attribute 'loads'"):
            pkg.loads  # noqa: B018 - the read is the test
    finally:
        del sys.modules["fake_pkg"]


def test_importing_one_medium_or_one_law_imports_no_other() -> None:
    # issue 19: the package __init__ of netsim.network and netsim.control imports nothing by itself
    code = ("import sys, netsim.network.link, netsim.control.pid; "
            "print(sorted(m for m in ('netsim.network.can', 'netsim.network.wireless', 'netsim.control.mpc', "
            "'netsim.control.kalman') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_a_lazy_module_imports_at_the_first_attribute_read() -> None:
    assert lazy_module("math").sqrt(9.0) == 3.0
