"""The scenarios shipped with netsim, by name: ``netsim run dc_servo_can`` and ``netsim scenarios``.

The checkout's ``scenarios/`` folder installs as the package data ``netsim.scenarios`` (setup.py maps it), so
the same files are found through :mod:`importlib.resources` in an editable install (the checkout's folder)
and in a wheel (``site-packages/netsim/scenarios``). A scenario's name is its file name without ``.yaml``;
sweep files are shipped scenarios too (``netsim sweep hdd_gpi_sweep``), and their ``base:`` files sit
beside them, so they resolve as they do in the checkout.

Examples
--------
>>> from netsim import shipped
>>> shipped.scenario_path("dc_servo_can").name
'dc_servo_can.yaml'
>>> "hdd_case1" in shipped.names()
True
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path

from netsim.errors import ConfigError

__all__ = ["PACKAGE", "ShippedScenario", "folder", "names", "scenario_path", "catalogue", "resolve"]

#: The package whose data files are the shipped scenarios.
PACKAGE = "netsim.scenarios"
_SUFFIX = ".yaml"
_DESCRIPTION = re.compile(r"^description:\s*(.*)$", re.MULTILINE)
_SWEEP = re.compile(r"^sweep\s*:", re.MULTILINE)


@dataclass(frozen=True)
class ShippedScenario:
    """One shipped file: its name (``dc_servo_can``), path, whether it is a sweep, and a one-line summary."""

    name: str
    path: Path
    is_sweep: bool
    summary: str


@lru_cache(maxsize=1)
def folder() -> Path:
    """The folder of the shipped scenario files (a real folder: netsim is not installed zipped).

    Raises
    ------
    ConfigError
        When the installation has no shipped scenarios (a broken or hand-made install).
    """
    try:
        path = Path(str(resources.files(PACKAGE)))
    except ModuleNotFoundError:
        raise ConfigError("this netsim installation has no shipped scenarios (package netsim.scenarios is "
                          "missing): reinstall netsim") from None
    return path


def names() -> list[str]:
    """The names of the shipped scenarios and sweeps (file names without ``.yaml``), sorted."""
    return sorted(p.stem for p in folder().glob(f"*{_SUFFIX}") if p.is_file())


def scenario_path(name: str) -> Path:
    """The file of the shipped scenario ``name`` (``"dc_servo_can"``; ``"dc_servo_can.yaml"`` also works).

    Raises
    ------
    ConfigError
        When no shipped scenario has that name (the message names the closest one).
    """
    stem = name[: -len(_SUFFIX)] if name.endswith(_SUFFIX) else name
    path = folder() / f"{stem}{_SUFFIX}"
    if stem and "/" not in stem and "\\" not in stem and path.is_file():
        return path
    from netsim.scenario.paths import did_you_mean

    hint = did_you_mean(stem, names()) or "; `netsim scenarios` lists them"
    raise ConfigError(f"'{name}' is not a shipped scenario{hint}")


def _summary(text: str) -> str:
    """The file's ``description:`` (first line of it), else its first comment line."""
    match = _DESCRIPTION.search(text)
    if match:
        value = match.group(1).strip()
        if value in (">", "|", ">-", "|-", ""):  # a block scalar: its first indented line
            rest = text[match.end():].lstrip("\n").splitlines()
            value = rest[0].strip() if rest else ""
        return value.strip("\"'")
    for line in text.splitlines():
        if line.startswith("#"):  # a sentence that goes on in the next comment line loses its comma
            return line.lstrip("# ").strip().rstrip(",;:")
    return ""


def catalogue() -> list[ShippedScenario]:
    """Every shipped scenario and sweep with its one-line summary, sorted by name."""
    out = []
    for name in names():
        path = folder() / f"{name}{_SUFFIX}"
        text = path.read_text(encoding="utf-8")
        out.append(ShippedScenario(name, path, _SWEEP.search(text) is not None, _summary(text)))
    return out


def resolve(argument: str) -> str:
    """A command's scenario argument: a file as given, or the shipped scenario a bare name stands for.

    An existing file, or anything written with a folder (``scenarios/x.yaml``), is returned unchanged, so a file
    of that name in the working folder wins over a shipped scenario. A bare name (``dc_servo_can``, or
    ``dc_servo_can.yaml`` where no such file is) is looked up among the shipped scenarios; a missing
    ``other.yaml`` is returned unchanged, for the loader's "file not found".

    Raises
    ------
    ConfigError
        A bare name that is neither a file nor a shipped scenario, in one line with the closest name.
    """
    text = str(argument)
    if Path(text).exists() or "/" in text or "\\" in text:
        return text
    if text.endswith((".yaml", ".yml")):
        candidate = folder() / text
        return str(candidate) if candidate.is_file() else text
    try:
        return str(scenario_path(text))
    except ConfigError:
        from netsim.scenario.paths import did_you_mean

        hint = did_you_mean(text, names()) or "; `netsim scenarios` lists the shipped ones"
        raise ConfigError(f"'{text}' is neither a file nor a shipped scenario{hint}") from None
