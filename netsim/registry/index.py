"""Which module registers which plugin, read from the sources without importing them (lazy plugin loading).

Importing every plugin module at the first lookup cost each run and each ``netsim validate`` about half a
second, and more with every model added (issue 19). Instead, :func:`plugin_index` reads the source of every
module below :data:`netsim.registry.PLUGIN_MODULES` with :mod:`ast` and collects its literal
``register("kind", "name")`` calls (the ``@register(...)`` decorators); :func:`netsim.registry.lookup` then
imports only the modules that declare the name asked for.

A module the index cannot read completely is *opaque* and imported whenever a lookup misses: a source that
does not parse (a syntax error is then reported as the import failure it is), a module without Python source,
or a ``register(...)`` call whose kind or name is not a string literal. ``tests/test_registry_index.py`` checks
that the index equals what importing every module registers, so a new ``@register`` line can never be missed.

Parsing costs about 90 ms for netsim and the models, so the result is cached per source file, keyed on the
file's modification time and size, in ``$NETSIM_CACHE_DIR`` (default ``$XDG_CACHE_HOME/netsim`` or
``~/.cache/netsim``): a file changed or added since is parsed again, and the cache is rewritten atomically.
A cache that cannot be read or written is ignored (the index is then parsed in full, never wrong).
"""

from __future__ import annotations

import ast
import importlib.util
import json
import logging
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Iterator

__all__ = ["Declaration", "PluginIndex", "plugin_index", "declarations_in", "cache_path"]

log = logging.getLogger(__name__)

#: Bumped when the cached per-file record changes shape.
_FORMAT = 1


@dataclass(frozen=True)
class Declaration:
    """One literal ``register(kind, name)`` call: the module it is in and the line."""

    kind: str
    name: str
    module: str
    line: int


@dataclass
class PluginIndex:
    """The plugin declarations of the plugin modules, and the modules that must be imported to be known.

    Attributes
    ----------
    declarations
        Every literal ``register(kind, name)`` call found, in module order.
    opaque
        Modules whose declarations cannot be read from source (see the module docstring), in module order.
    """

    declarations: list[Declaration] = field(default_factory=list)
    opaque: list[str] = field(default_factory=list)

    def modules_for(self, kind: str, name: str) -> list[str]:
        """The modules declaring ``kind``/``name`` (usually one)."""
        return [d.module for d in self.declarations if d.kind == kind and d.name == name]

    def names(self, kind: str) -> list[str]:
        """Every declared name of ``kind``, sorted."""
        return sorted({d.name for d in self.declarations if d.kind == kind})


def declarations_in(source: str, kinds: Iterable[str]) -> tuple[list[tuple[str, str, int]], bool]:
    """The ``(kind, name, line)`` of each ``register("kind", "name", ...)`` call in ``source``, and opacity.

    A call of a function or method named ``register`` whose first argument is a string literal counts when
    it names one of ``kinds``; the module is opaque when such a call's name is not a string literal, or when
    the first argument is not a literal while the call has two or more arguments (``register(KIND, name)``).
    Calls such as ``atexit.register(fn)`` (one argument) are not plugin declarations.

    Raises
    ------
    SyntaxError
        When ``source`` does not parse.
    """
    known = set(kinds)
    found: list[tuple[str, str, int]] = []
    opaque = False
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.Call):
            continue
        func = node.func
        called = func.id if isinstance(func, ast.Name) else func.attr if isinstance(func, ast.Attribute) else ""
        if called != "register":
            continue
        if not node.args:
            opaque = opaque or bool(node.keywords)  # register(kind=..., name=...)
            continue
        first = node.args[0]
        if isinstance(first, ast.Constant) and isinstance(first.value, str):
            if first.value not in known:
                continue
            second = node.args[1] if len(node.args) > 1 else None
            if isinstance(second, ast.Constant) and isinstance(second.value, str):
                found.append((first.value, second.value, node.lineno))
            else:
                opaque = True
        elif len(node.args) >= 2 or node.keywords:
            opaque = True
    return found, opaque


def cache_path() -> Path:
    """The index cache file (``$NETSIM_CACHE_DIR``, ``$XDG_CACHE_HOME/netsim`` or ``~/.cache/netsim``)."""
    base = os.environ.get("NETSIM_CACHE_DIR")
    if not base:
        xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
        base = str(Path(xdg) / "netsim")
    tag = f"{sys.implementation.cache_tag or 'py'}"
    return Path(base) / f"plugin-index-{tag}.json"


def _locate(dotted: str) -> tuple[str | None, bool]:
    """(absolute source file or package directory, is_package) of ``dotted``, found without importing it.

    The top-level name is found by :func:`importlib.util.find_spec` (which imports nothing for a top-level
    name); the rest is looked up in the package directories. ``(None, False)`` when it does not exist.
    """
    top, *rest = dotted.split(".")
    try:
        spec = importlib.util.find_spec(top)
    except (ImportError, ValueError):
        return None, False
    if spec is None:
        return None, False
    dirs = [os.path.abspath(p) for p in (spec.submodule_search_locations or [])]
    if not rest:
        if dirs:
            return dirs[0], True
        return (os.path.abspath(spec.origin) if spec.origin and spec.origin.endswith(".py") else None), False
    for i, part in enumerate(rest):
        nxt = [os.path.join(d, part) for d in dirs if os.path.isdir(os.path.join(d, part))]
        if i == len(rest) - 1:
            for d in dirs:
                if not nxt and os.path.isfile(os.path.join(d, part + ".py")):
                    return os.path.join(d, part + ".py"), False
        if not nxt:
            # a package mapped from another folder (``netsim.models`` is the checkout's ``models/`` in an
            # editable install): ask the import system, which imports the already-loaded parent only
            mapped = _mapped_dirs(".".join([top, *rest[: i + 1]]))
            if not mapped:
                return None, False
            nxt = mapped
        dirs = nxt
    return dirs[0], True


def _mapped_dirs(dotted: str) -> list[str]:
    """The package directories of ``dotted`` found by the import system (its parent package is imported)."""
    try:
        spec = importlib.util.find_spec(dotted)
    except (ImportError, ValueError):
        return []
    if spec is None:
        return []
    return [os.path.abspath(p) for p in (spec.submodule_search_locations or [])]


def _walk(dotted: str) -> Iterator[tuple[str, Any]]:
    """``(module name, source file or None)`` of ``dotted`` and, for a package, every module below it, in the
    order :func:`netsim.registry.load_plugins` imports them (sorted, ``__main__`` excepted). The source is a path
    or an :class:`os.DirEntry`; a module without Python source (an extension module, a stray ``.pyc``) comes
    with None: it must be imported to be known."""
    where, is_pkg = _locate(dotted)
    if where is None or not is_pkg:
        yield dotted, where
        return
    yield from _walk_dir(dotted, where)


def _walk_dir(dotted: str, where: str) -> Iterator[tuple[str, Any]]:
    from importlib.machinery import all_suffixes

    init = os.path.join(where, "__init__.py")
    yield dotted, init if os.path.isfile(init) else None
    children: dict[str, tuple[bool, Any]] = {}  # name -> (is_package, package path or source DirEntry)
    try:
        entries = list(os.scandir(where))
    except OSError:  # unreadable folder: its modules stay unknown here, and load_plugins reports their import
        return
    suffixes = sorted(all_suffixes(), key=len, reverse=True)
    for entry in entries:
        name = entry.name
        if entry.is_dir():
            if "." not in name and any(os.path.isfile(os.path.join(entry.path, "__init__" + x)) for x in suffixes):
                children.setdefault(name, (True, entry.path))
            continue
        suffix = next((x for x in suffixes if name.endswith(x)), None)
        if suffix is None:
            continue
        stem = name[: -len(suffix)]
        if stem in ("__init__", "__main__") or not stem.isidentifier():
            continue
        if suffix == ".py":
            if not children.get(stem, (False, None))[0]:  # a package beats a module of the same name, as in import
                children[stem] = (False, entry)
        else:
            children.setdefault(stem, (False, None))
    for name in sorted(children):
        is_pkg, where_or_entry = children[name]
        if is_pkg:
            yield from _walk_dir(f"{dotted}.{name}", where_or_entry)
        else:
            yield f"{dotted}.{name}", where_or_entry


def _read_cache(path: Path, kinds: tuple[str, ...]) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    if (not isinstance(data, dict) or data.get("format") != _FORMAT or data.get("kinds") != list(kinds)
            or not isinstance(data.get("files"), dict)):
        return {}
    return data["files"]


def _write_cache(path: Path, kinds: tuple[str, ...], files: dict[str, Any]) -> None:
    import tempfile  # only when something changed: a start-up with a valid cache does not import it

    kept = {name: rec for name, rec in files.items() if os.path.exists(name)}  # files deleted since: dropped
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".plugin-index-", dir=path.parent)
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            json.dump({"format": _FORMAT, "kinds": list(kinds), "files": kept}, fh)
        os.replace(tmp, path)
    except OSError as exc:  # a read-only home: the index is parsed again next time, never wrong
        log.debug("could not write the plugin index cache %s: %s", path, exc)
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)


def _file_record(src: str, stat: os.stat_result, kinds: tuple[str, ...]) -> dict[str, Any]:
    try:
        with open(src, encoding="utf-8") as fh:
            found, opaque = declarations_in(fh.read(), kinds)
    except (SyntaxError, ValueError, UnicodeDecodeError, OSError):
        found, opaque = [], True  # imported on a miss, where its error is reported
    return {"mtime_ns": stat.st_mtime_ns, "size": stat.st_size, "decl": [list(d) for d in found], "opaque": opaque}


_MEMO: dict[tuple[tuple[str, ...], tuple[str, ...]], PluginIndex] = {}


def plugin_index(roots: Iterable[str], kinds: Iterable[str], *, refresh: bool = False) -> PluginIndex:
    """The declarations of every module in and below ``roots`` (memoised per process; ``refresh`` re-reads).

    Parameters
    ----------
    roots
        Module or package names (:data:`netsim.registry.PLUGIN_MODULES`).
    kinds
        The registry kinds a declaration may name.
    refresh
        Stat the files again even when this process already built the index for the same roots.
    """
    key = (tuple(roots), tuple(kinds))
    if not refresh and key in _MEMO:
        return _MEMO[key]
    cpath = cache_path()
    cached = _read_cache(cpath, key[1])
    files: dict[str, Any] = dict(cached)
    changed = False
    index = PluginIndex()
    for root in key[0]:
        for module, src in _walk(root):
            if src is None:
                index.opaque.append(module)  # no source (missing, extension module): import to know
                continue
            fname = src if isinstance(src, str) else src.path
            try:
                st = os.stat(src) if isinstance(src, str) else src.stat()  # a DirEntry's stat needs no path lookup
            except OSError:
                index.opaque.append(module)
                continue
            rec = files.get(fname)
            if not (isinstance(rec, dict) and rec.get("mtime_ns") == st.st_mtime_ns and rec.get("size") == st.st_size):
                rec = _file_record(fname, st, key[1])
                files[fname] = rec
                changed = True
            if rec["opaque"]:
                index.opaque.append(module)
            index.declarations.extend(Declaration(k, n, module, line) for k, n, line in rec["decl"])
    if changed:
        _write_cache(cpath, key[1], files)
    _MEMO[key] = index
    return index
