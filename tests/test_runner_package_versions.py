"""meta.json's package versions are read from each distribution's metadata header without the e-mail parser
(issue 29, start-up); they must equal what ``importlib.metadata.version`` says."""

from __future__ import annotations

from importlib import metadata

import pytest

from netsim import runner


def test_every_version_equals_importlib_metadata_version():
    versions = runner.package_versions()
    checked = 0
    for package in runner._VERSION_PACKAGES:
        try:
            expected = metadata.version(package)  # the e-mail parser's reading of the same header
        except metadata.PackageNotFoundError:
            assert package not in versions or package == "netsim"
            continue
        assert versions[package] == expected, package
        checked += 1
    assert checked >= 5  # netsim, simpy, numpy, scipy, pydantic are always installed


class _FakeDist:
    def __init__(self, files: dict[str, str], version: str) -> None:
        self.files, self.version = files, version

    def read_text(self, name: str) -> str | None:
        return self.files.get(name)


@pytest.mark.parametrize("files, expected", [
    ({"METADATA": "Metadata-Version: 2.1\nName: x\nversion:  1.2.3 \n\nVersion: 9 (in the body)\n"}, "1.2.3"),
    ({"PKG-INFO": "Metadata-Version: 1.0\nName: x\nVersion: 0.4\n"}, "0.4"),
    # no Version line in the header (only in the body): the e-mail parser's answer
    ({"METADATA": "Name: x\n\nVersion: 9\n"}, "parsed"),
    ({}, "parsed"),
])
def test_the_version_line_of_the_header_is_read_and_anything_else_falls_back(monkeypatch, files, expected):
    monkeypatch.setattr(runner.metadata, "distribution", lambda name: _FakeDist(files, "parsed"))
    assert runner._version("x") == expected
