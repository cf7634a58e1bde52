"""Package layout that pyproject.toml cannot say by itself: folders of the checkout that install under netsim.

* ``models/`` installs as ``netsim.models`` (the case studies; a top-level ``models`` would collide with a
  user's own).
* ``scenarios/`` installs as ``netsim.scenarios``: the shipped scenario and sweep files, as package data (no
  Python in it), found by name through :mod:`netsim.shipped` (``netsim run dc_servo_can``).

Editable and wheel installs alike. Everything else (metadata, dependencies, entry points) is in pyproject.toml.
"""
from setuptools import find_packages, setup

_MAPPED = {"netsim.models": "models"}
# the source FMUs of the shipped FMU scenarios (C source and modelDescription.xml; built on first use)
_DATA = {"netsim.scenarios": ("scenarios", ["*.yaml", "fmu/*/modelDescription.xml", "fmu/*/sources/*"])}

packages = find_packages(include=["netsim", "netsim.*"])
for name, folder in _MAPPED.items():
    packages += [name] + [f"{name}.{sub}" for sub in find_packages(where=folder)]
packages += list(_DATA)

# the case-study reports' prose templates (models/**/*.md, read next to their modules)
_TEMPLATES = {name: ["*.md"] for name in packages if name.startswith("netsim.models")}

setup(
    packages=packages,
    package_dir={**_MAPPED, **{name: folder for name, (folder, _) in _DATA.items()}},
    package_data={**_TEMPLATES, **{name: patterns for name, (_, patterns) in _DATA.items()}},
)
