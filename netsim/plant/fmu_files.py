"""Finding, reading and building the FMU a ``type: fmu`` plant names (:mod:`netsim.plant.fmu`), with FMPy.

An FMU is given as a ``.fmu`` archive or as its unpacked folder (``modelDescription.xml``, ``binaries/``,
``sources/``). :func:`read_description` reads ``modelDescription.xml`` only (no code runs); :func:`binary_folder`
returns an unpacked folder holding the shared library for this platform:

* a folder with the library: used where it is;
* an archive: unpacked once into the cache folder (keyed by the archive's SHA-256);
* a *source* FMU (``sources/`` and no library for this platform, FMPy's source FMUs): copied into the cache
  folder and compiled there once with FMPy's CMake project (:func:`fmpy.build.create_cmake_settings`, the
  ``cmake`` that FMPy installs, and the machine's C compiler), keyed by the SHA-256 of the description and the
  sources. FMI 2.0 lists its source files in ``modelDescription.xml``, FMI 3.0 in
  ``sources/buildDescription.xml``; FMPy's project compiles both against the FMI headers it ships. A machine
  without a C compiler gets an error that says so.

The cache folder is ``$NETSIM_CACHE_DIR/fmu`` (default ``$XDG_CACHE_HOME/netsim/fmu`` or ``~/.cache/netsim/fmu``),
beside the plugin index (:func:`netsim.registry.index.cache_path`). A build goes to a temporary folder renamed
into place, so processes building the same FMU at once (sweep workers) do not see half a build.
"""

from __future__ import annotations

import hashlib
import logging
import os
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any

from netsim.errors import ConfigError

__all__ = ["NO_FMPY", "binary_folder", "cache_folder", "compiler", "has_binary", "identifier", "read_description",
           "supported"]

_log = logging.getLogger(__name__)

#: What to do when FMPy is missing.
NO_FMPY = "the fmu plant needs FMPy: pip install 'netsim[fmu]' (or pip install fmpy)"


def _fmpy() -> Any:
    try:
        import fmpy
    except ImportError:
        raise ConfigError(NO_FMPY) from None
    return fmpy


def cache_folder() -> Path:
    """``<netsim cache>/fmu``: unpacked archives and compiled source FMUs."""
    from netsim.registry.index import cache_path

    return cache_path().parent / "fmu"


def read_description(path: Path) -> Any:
    """FMPy's ``ModelDescription`` of the FMI 2.0 or 3.0 FMU at ``path`` (archive or folder), checked against the
    FMI schema (FMPy's validation); reads XML only (an FMI 3.0 source FMU's ``sources/buildDescription.xml`` too).

    Raises
    ------
    ConfigError
        When the file is missing, its description cannot be read (FMPy's reason, in one line), or it is neither
        an FMI 2.0 nor an FMI 3.0 FMU (FMI 1.0).
    """
    fmpy = _fmpy()
    if not path.exists():
        raise ConfigError(f"FMU not found: {path}; give the path of a .fmu file or an unpacked FMU folder "
                          "(relative to the scenario file)")
    if path.is_dir() and not (path / "modelDescription.xml").is_file():
        raise ConfigError(f"{path} is a folder without modelDescription.xml: not an unpacked FMU")
    try:
        version, interfaces = _kind(path)
        if supported(version) and interfaces:
            return fmpy.read_model_description(str(path))  # with FMPy's checks against the FMI schema
    except Exception as exc:  # noqa: BLE001 - FMPy's reasons (bad zip, schema errors) reported in one line
        text = " ".join(str(exc).split())
        raise ConfigError(f"cannot read the FMU's modelDescription.xml ({path}): {text[:300]}") from None
    if not supported(version):
        raise ConfigError(f"the FMU {path.name} is FMI {version}; the fmu plant runs FMI 2.0 and 3.0 FMUs "
                          "(co-simulation or model exchange): export the model as FMI 2.0 or 3.0")
    raise ConfigError(f"the FMU {path.name} declares neither co-simulation nor model exchange")


def supported(version: str) -> bool:
    """True for the FMI versions the fmu plant runs: 2.0 and 3.x (FMPy's reader takes every 3.x)."""
    return version == "2.0" or version.startswith("3.")


def _kind(path: Path) -> tuple[str, bool]:
    """``(fmiVersion, has a CoSimulation or ModelExchange element)`` from the root of ``modelDescription.xml``."""
    import zipfile

    from lxml import etree  # type: ignore[import-untyped]  # lxml ships no types; lxml-stubs is not a dependency

    if path.is_dir():
        root = etree.parse(str(path / "modelDescription.xml")).getroot()
    else:
        with zipfile.ZipFile(path) as zf, zf.open("modelDescription.xml") as fh:
            root = etree.parse(fh).getroot()
    return str(root.get("fmiVersion")), root.find("CoSimulation") is not None or root.find("ModelExchange") is not None


def identifier(description: Any, interface: str = "co_simulation") -> str:
    """The model identifier (the library's name) of ``interface`` (``co_simulation`` or ``model_exchange``)."""
    kind = description.coSimulation if interface == "co_simulation" else description.modelExchange
    return str(kind.modelIdentifier)


def has_binary(folder: Path, description: Any, interface: str = "co_simulation") -> bool:
    """True when the unpacked FMU ``folder`` holds the library of ``interface`` for this platform."""
    fmpy = _fmpy()
    ident = identifier(description, interface)
    return (folder / "binaries" / _platform(description) / f"{ident}{fmpy.sharedLibraryExtension}").is_file()


def _platform(description: Any) -> str:
    """The ``binaries/`` subfolder of this platform: ``x86_64-linux`` (FMI 3.0's tuple) or ``linux64`` (FMI 2.0)."""
    fmpy = _fmpy()
    return str(fmpy.platform if description.fmiVersion == "2.0" else fmpy.platform_tuple)


def compiler() -> str | None:
    """The C compiler CMake would find (``$CC``, ``cc``, ``gcc``, ``clang``), or None."""
    for name in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if name and shutil.which(name):
            return name
    return None


def _cmake() -> str:
    found = shutil.which("cmake")
    if found:
        return found
    try:
        import cmake  # the wheel FMPy depends on; its bin folder is not on PATH outside an activated venv

        return str(Path(cmake.CMAKE_BIN_DIR) / "cmake")
    except ImportError:
        raise ConfigError("building a source FMU needs CMake (pip install cmake)") from None


def _digest(paths: list[Path]) -> str:
    h = hashlib.sha256()
    for p in paths:
        h.update(p.name.encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:24]


def _unpacked(path: Path) -> Path:
    """The unpacked folder of the archive ``path`` (in the cache, unpacked once)."""
    fmpy = _fmpy()
    target = cache_folder() / f"unzip-{_digest([path])}"
    if not target.is_dir():
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=target.parent, prefix=".unzip-"))
        fmpy.extract(str(path), unzipdir=str(tmp))
        _publish(tmp, target)
    return target


def _publish(tmp: Path, target: Path) -> None:
    try:
        os.replace(tmp, target)
    except OSError:  # another process published the same content first
        shutil.rmtree(tmp, ignore_errors=True)


def _source_files(folder: Path) -> list[Path]:
    return sorted(p for p in (folder / "sources").rglob("*") if p.is_file())


def binary_folder(path: Path, description: Any, interface: str = "co_simulation") -> Path:
    """An unpacked FMU folder with the library of ``path`` for ``interface`` and this platform (see the module).

    Raises
    ------
    ConfigError
        When there is neither a library for this platform nor sources, when no C compiler is found, or when
        the build fails (the compiler's last lines).
    """
    folder = _unpacked(path) if path.is_file() else path
    if has_binary(folder, description, interface):
        return folder
    sources = _source_files(folder) if (folder / "sources").is_dir() else []
    if not sources:
        raise ConfigError(f"the FMU {path.name} has no binary for this platform ({_platform(description)}) and no "
                          "sources to build one from")
    target = cache_folder() / f"build-{_digest([folder / 'modelDescription.xml', *sources])}"
    if target.is_dir() and has_binary(target, description, interface):
        return target
    if compiler() is None:
        raise ConfigError(f"the FMU {path.name} is a source FMU and this machine has no C compiler to build it "
                          "(install gcc or clang, or set CC)")
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=target.parent, prefix=".build-"))
    try:
        shutil.copy2(folder / "modelDescription.xml", tmp / "modelDescription.xml")
        shutil.copytree(folder / "sources", tmp / "sources")
        if (folder / "resources").is_dir():
            shutil.copytree(folder / "resources", tmp / "resources")
        _compile(tmp, path)
        if not has_binary(tmp, description, interface):
            raise ConfigError(f"building the source FMU {path.name} made no library for this platform")
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    _publish(tmp, target)
    _log.info("built the source FMU %s into %s", path, target)
    return target


def _compile(unzipdir: Path, path: Path) -> None:
    """FMPy's CMake project (``fmpy/c-code``) configured by :func:`fmpy.build.create_cmake_settings`, built quietly."""
    fmpy = _fmpy()
    from fmpy.build import create_cmake_settings

    cmake = _cmake()
    with tempfile.TemporaryDirectory() as build:
        create_cmake_settings(unzipdir, build)
        source = Path(fmpy.__file__).parent / "c-code"
        for args in ([cmake, "-S", str(source), "-B", build], [cmake, "--build", build, "--target", "install",
                                                                 "--config", "Release"]):
            done = subprocess.run(args, capture_output=True, text=True, check=False)
            if done.returncode != 0:
                tail = " | ".join((done.stderr or done.stdout).strip().splitlines()[-3:])
                raise ConfigError(f"building the source FMU {path.name} failed: {tail[:400]}")
