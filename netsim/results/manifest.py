"""A sweep point folder's record and manifest: ``point.json`` (the worker's record) and ``manifest.json`` (the
sha256 of every other file, written last), and the check that a point folder is still what the sweep wrote.

:mod:`netsim.results.folder` reads run and sweep folders with these; :mod:`netsim.sweep.points` writes them.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

__all__ = ["RECORD_NAME", "MANIFEST_NAME", "json_object", "read_record", "manifest_digests", "tampered_reason",
           "verified_record"]

#: The per-point record written by the sweep worker when a point finishes (ok or error).
RECORD_NAME = "point.json"
#: Written last in a sweep point folder: ``{"files": {relative path: sha256}}`` of every other file in it.
MANIFEST_NAME = "manifest.json"


def json_object(path: Path) -> dict[str, Any] | None:
    """The JSON object in ``path``; None when it is missing, unreadable, not JSON or not an object."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):  # missing or torn: the caller treats the folder as incomplete
        return None
    return data if isinstance(data, dict) else None


def read_record(folder: Path) -> dict[str, Any] | None:
    """The ``point.json`` of a sweep point folder, or None when it is missing or unreadable."""
    return json_object(Path(folder) / RECORD_NAME)


def _digest(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _listing(folder: Path) -> dict[str, Path] | None:
    """Every file below ``folder`` by relative path (the manifest aside); None when ``folder`` is a symlink or
    holds one, or anything that is neither a file nor a folder."""
    if folder.is_symlink() or not folder.is_dir():
        return None
    files: dict[str, Path] = {}
    for root, dirs, names in os.walk(folder, followlinks=False):
        for name in [*dirs, *names]:
            path = Path(root) / name
            if path.is_symlink() or not (path.is_dir() or path.is_file()):
                return None
        for name in names:
            path = Path(root) / name
            rel = path.relative_to(folder).as_posix()
            if rel != MANIFEST_NAME:
                files[rel] = path
    return files


def manifest_digests(folder: Path) -> dict[str, str]:
    """The sha256 of every file of a point folder by relative path, as ``manifest.json`` records them (empty
    when the folder is a symlink or holds one)."""
    listing = _listing(Path(folder)) or {}
    return {rel: _digest(path) for rel, path in sorted(listing.items())}


def tampered_reason(folder: Path) -> str | None:
    """Why a point folder does not match its ``manifest.json`` (a few words), or None when it matches.

    A folder is trusted when it is a real folder (no symlink in it or as it) holding exactly the files its
    manifest lists, with the same sha256 each.
    """
    listing = _listing(Path(folder))
    if listing is None:
        return "it is, or holds, a symlink or a special file"
    manifest = json_object(Path(folder) / MANIFEST_NAME)
    files = manifest.get("files") if manifest is not None else None
    if not isinstance(files, dict):
        return f"no readable {MANIFEST_NAME} (the sweep stopped before the point finished)"
    extra, missing = sorted(set(listing) - set(files)), sorted(set(files) - set(listing))
    if extra or missing:
        return f"{(extra or missing)[0]} was {'added' if extra else 'removed'} after the sweep wrote it"
    for rel, path in listing.items():
        try:
            if _digest(path) != files[rel]:
                return f"{rel} was changed after the sweep wrote it"
        except OSError:  # a file gone while its digest is taken: not verified, the point is rerun
            return f"{rel} could not be read"
    return None


def verified_record(folder: Path) -> dict[str, Any] | None:
    """The point's ``point.json`` if the folder is exactly what its manifest says (same files, same sha256, no
    symlink); None otherwise (a point stopped before it finished, or a folder changed since)."""
    listing = _listing(Path(folder))
    if listing is None or RECORD_NAME not in listing:
        return None
    return read_record(folder) if tampered_reason(folder) is None else None
