"""meta.json names the version of every installed package that can change a number (issue 27 section 1)."""

from __future__ import annotations

import json
from importlib import metadata
from pathlib import Path

import netsim

ROOT = Path(__file__).resolve().parents[1]

#: Packages whose version can move a number of a run: the kernel (simpy), the numerics (numpy, scipy, control and
#: its slycot Riccati solvers), the QP solvers (daqp for MPC, clarabel for the cart's JMAP), tables (pandas),
#: parsing (pydantic, pyyaml) and the figures (matplotlib). All are core dependencies, so all are installed.
NUMBER_PACKAGES = ("simpy", "numpy", "scipy", "control", "slycot", "pandas", "pydantic", "pyyaml", "daqp",
                   "clarabel", "matplotlib")


def test_meta_json_records_the_version_of_every_package_that_can_change_a_number(tmp_path):
    netsim.run(ROOT / "scenarios" / "dc_servo_ideal.yaml", out=tmp_path / "run", overrides={"duration": "20 ms"})
    versions = json.loads((tmp_path / "run" / "meta.json").read_text())["versions"]
    for package in NUMBER_PACKAGES:  # the expected value read from the installed metadata, not from netsim
        assert versions.get(package) == metadata.version(package), package
    assert versions["netsim"] == netsim.__version__
