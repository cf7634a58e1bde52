"""File helpers shared by the CLI tests (importable: ``tests/cli`` is on pytest's path)."""

from __future__ import annotations

from pathlib import Path


def write(folder: Path, name: str, text: str) -> Path:
    """Write ``text`` to ``folder/name`` and return the path."""
    path = folder / name
    path.write_text(text)
    return path


def line_of(path: Path, needle: str) -> int:
    """1-based line of the first line containing ``needle`` (independent of the loader)."""
    for i, line in enumerate(path.read_text().splitlines(), start=1):
        if needle in line:
            return i
    raise AssertionError(needle)
