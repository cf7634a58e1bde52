"""Package layout that pyproject.toml cannot say by itself: ``models/`` installs as ``netsim.models``.

Everything else (metadata, dependencies, entry points) is in pyproject.toml.
"""
from setuptools import find_packages, setup

_MAPPED = {"netsim.models": "models"}

packages = find_packages(include=["netsim", "netsim.*"])
for name, folder in _MAPPED.items():
    packages += [name] + [f"{name}.{sub}" for sub in find_packages(where=folder)]

setup(packages=packages, package_dir={name: folder for name, folder in _MAPPED.items()})
