"""Writing run-folder files so that nothing finished is lost and nothing outside the folder is touched.

:func:`write_atomic` writes a file under a temporary name created exclusively (``O_EXCL``, and ``O_NOFOLLOW``
where the platform has it: a symlink planted under that name is never followed) and then renames it over the
final name. ``os.replace`` replaces a symlink planted at the final name by the file itself: its target is never
written. A reader therefore sees either the previous file or the whole new one, never half a CSV.

:func:`make_unique_dir` creates a new folder exclusively, adding ``-2``, ``-3`` ... to the name when it exists:
two runs started in the same second never share a folder.

A write that fails for lack of room (the file-size limit ``ulimit -f``, a full disk, a used-up quota) raises the
same :class:`OSError` with the final file's name and a fix in its message ("cannot write X: File too large; ...").
"""

from __future__ import annotations

import errno
import os
from pathlib import Path
from typing import Iterable

__all__ = ["write_atomic", "make_unique_dir"]

_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0)


def write_atomic(path: str | Path, data: str | bytes | Iterable[str], encoding: str = "utf-8") -> Path:
    """Write ``data`` to ``path`` atomically (temporary file in the same folder, then rename).

    Parameters
    ----------
    path
        Final file path; its folder must exist.
    data
        Text (encoded with ``encoding``, line ends written as given) or bytes; or an iterable of text chunks,
        written one by one (a long table never has to be held as one string).

    Returns
    -------
    Path
        ``path``.
    """
    final = Path(path)
    chunks: Iterable[str | bytes] = [data] if isinstance(data, (str, bytes)) else data
    tmp = final.with_name(f".{final.name}.{os.getpid()}.tmp")
    try:
        fd = os.open(tmp, _FLAGS, 0o644)
    except FileExistsError:  # a stale temporary (or a planted link) of the same name: remove it, never follow it
        os.unlink(tmp)
        fd = os.open(tmp, _FLAGS, 0o644)
    try:
        with os.fdopen(fd, "wb") as fh:
            for chunk in chunks:
                fh.write(chunk.encode(encoding) if isinstance(chunk, str) else chunk)
        os.replace(tmp, final)  # no fsync: a killed process leaves the old file or the new one (not power loss)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError) and exc.errno in _FIXES:  # the same error, naming the file and the fix
            raise OSError(exc.errno, f"{exc.strerror or os.strerror(exc.errno or 0)}; {_FIXES[exc.errno]}",
                          str(final)) from exc
        raise
    return final


_LESS = ("or write less: a shorter 'duration', a coarser 'plant.record_grid', fewer 'record:' signals, or "
         "'output: {jobs: summary, messages: summary}'")
#: What to do when a write fails for lack of room, by errno (the message the CLI prints after "cannot write X").
_FIXES = {
    errno.EFBIG: f"the file-size limit of this shell stops it (see 'ulimit -f'): raise it ('ulimit -f unlimited'), "
                 f"{_LESS}",
    errno.ENOSPC: f"free space on that disk, or write elsewhere with '--out DIR', {_LESS}",
    errno.EDQUOT: f"your disk quota is used up: free space, or write elsewhere with '--out DIR', {_LESS}",
}


def make_unique_dir(base: str | Path) -> Path:
    """Create ``base`` (or ``base-2``, ``base-3``, ... if taken) exclusively, with its parents; returns it."""
    base = Path(base)
    base.parent.mkdir(parents=True, exist_ok=True)
    out, k = base, 1
    while True:
        try:
            out.mkdir()
            return out
        except FileExistsError:
            k += 1
            out = base.with_name(f"{base.name}-{k}")
