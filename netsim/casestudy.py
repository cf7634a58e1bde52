"""The harness of the case-study reports (``netsim report hdd|cart|pendulum|unicycle``).

One place for what every reproduction report needs besides its own study:

* :func:`run_all` -- a list of points through one function, in one process pool (or in this process), in
  order, with progress (:func:`log_progress`); :func:`sweep` -- a sweep file through
  :func:`netsim.sweep.run.run_sweep`, every run required to give a result;
* :class:`RunCache` -- rows of runs already made, one JSON file per run named by its scenario hash
  (:func:`scenario_key`: the hash :func:`netsim.sweep.points.point_hash` gives a sweep's run), in a folder
  named by a fingerprint of the study's own code (:func:`code_fingerprint`);
* :class:`Quotes` -- the numbers a report's prose quotes (``key, value, text, source``), each formatted once,
  filling ``{key}`` templates (:meth:`Quotes.fill`) or marked inline (:meth:`Quotes.mark`);
* :func:`fmt` -- the one number formatter (significant digits, text for a missing value);
* :func:`load_templates` and :func:`fill` -- a report's prose is data: named templates in a text file next to its
  module (``models/**/*.md``, package data), ``{key}`` placeholders filled with quoted texts and nothing run
  from a template; a missing quote is an error naming the placeholder (:class:`MissingQuote`).

:func:`digits_outside_labels` is the check the reports' tests make on their templates: a template holds no
digit besides ``{key}`` placeholders and labels (equation, figure and section numbers).
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import os
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any, TypeVar

__all__ = ["fmt", "Quotes", "fill", "MissingQuote", "placeholders", "unused_quotes", "load_templates", "Templates",
           "digits_outside_labels", "md_table", "splice", "run_all", "log_progress",
           "Progress", "sweep", "RunCache", "scenario_key", "code_fingerprint"]

log = logging.getLogger(__name__)

T = TypeVar("T")
R = TypeVar("R")
#: ``progress(done, total, what)``, called after each run.
Progress = Callable[[int, int, str], None]


# ------------------------------------------------------------------------------------------------ numbers
def fmt(x: Any, digits: int = 3, *, missing: str = "nan", sci: bool = False) -> str:
    """``x`` with ``digits`` significant digits.

    Parameters
    ----------
    x
        A number (or ``None``).
    digits
        Significant digits (``:g`` format).
    missing
        The text of ``None`` and NaN. Infinities print as ``inf`` / ``-inf``; zero as ``0``.
    sci
        Outside ``1e-3 <= |x| < 1e5``: exponent notation with ``digits - 1`` decimals (``1.23e-05``).
    """
    if x is None:
        return missing
    v = float(x)
    if math.isnan(v):
        return missing
    if v == 0:
        return "0"
    if sci and math.isfinite(v) and not 1e-3 <= abs(v) < 1e5:
        return f"{v:.{digits - 1}e}"
    return f"{v:.{digits}g}"


#: A placeholder: ``{key}`` with letters, digits, ``_`` and ``.`` (other braces are text: ``{model: inband}``).
PLACEHOLDER = re.compile(r"\{([A-Za-z0-9_.]+)\}")
#: The line that starts a named template in a template file (:func:`load_templates`).
TEMPLATE_START = re.compile(r"^\[\[([A-Za-z0-9_.-]+)\]\]$")


class MissingQuote(KeyError):
    """A placeholder of a template without a quoted text (its message names the placeholder and the template)."""

    def __str__(self) -> str:
        return str(self.args[0])


def fill(template: str, texts: Mapping[str, str], where: str = "template") -> str:
    """``template`` with each ``{key}`` replaced by ``texts[key]``; nothing else of the template is read (no
    expression, no format spec, no code). A text is put in as it is, so it is never filled again.

    Texts no placeholder names are left unused without complaint: one set of quotes fills several templates
    (:func:`unused_quotes` lists those no template names).

    Raises
    ------
    MissingQuote
        A placeholder without a text: ``"<where>: no quoted value for the placeholder {key}"``.
    """
    def one(m: re.Match[str]) -> str:
        key = m.group(1)
        if key not in texts:
            raise MissingQuote(f"{where}: no quoted value for the placeholder {{{key}}}")
        return texts[key]

    return PLACEHOLDER.sub(one, template)


def placeholders(template: str) -> list[str]:
    """The keys ``template`` names, in order, each once."""
    return list(dict.fromkeys(PLACEHOLDER.findall(template)))


def unused_quotes(templates: Iterable[str], texts: Iterable[str]) -> list[str]:
    """The keys of ``texts`` that none of ``templates`` names (in the order of ``texts``)."""
    named = {k for t in templates for k in PLACEHOLDER.findall(t)}
    return [k for k in texts if k not in named]


class Templates(dict[str, str]):
    """The named templates of the file ``path`` (:func:`load_templates`), filled by name (:meth:`fill`)."""

    def __init__(self, path: Path) -> None:
        super().__init__(load_templates(path))
        self.where = f"{Path(path).parent.name}/{Path(path).name}"

    def fill(self, name: str, texts: Mapping[str, str] | None = None, /, **more: str) -> str:
        """Template ``name`` filled with ``texts`` and ``more`` (:func:`fill`; a missing quote names the file and
        the template)."""
        return fill(self[name], {**(texts or {}), **more}, f"{self.where} [[{name}]]")


def load_templates(path: Path) -> dict[str, str]:
    """The named templates of the text file ``path`` (a report's prose, kept as data next to its module).

    A line ``[[name]]`` starts the template ``name``; it runs to the next such line, without its trailing blank
    lines. Lines before the first name are a comment for the reader.

    Raises
    ------
    ValueError
        A name given twice, or a file without any.
    """
    out: dict[str, list[str]] = {}
    current: list[str] | None = None
    for line in Path(path).read_text(encoding="utf-8").split("\n"):
        m = TEMPLATE_START.match(line)
        if m:
            if m.group(1) in out:
                raise ValueError(f"{path}: template [[{m.group(1)}]] is given twice")
            current = out.setdefault(m.group(1), [])
        elif current is not None:
            current.append(line)
    if not out:
        raise ValueError(f"{path}: no template (a line [[name]] starts one)")
    return {k: "\n".join(v).rstrip("\n") for k, v in out.items()}


def digits_outside_labels(template: str, labels: Iterable[str]) -> list[str]:
    """The digits left in ``template`` once its ``{key}`` placeholders and the ``labels`` (regular
    expressions, matched per line) are taken out: a template whose numbers are all quoted gives ``[]``."""
    s = re.sub(r"\{[A-Za-z0-9_.]+\}", "", template)
    for pat in labels:
        s = re.sub(pat, "", s, flags=re.MULTILINE)
    return re.findall(r"\d+", s)


def md_table(frame: Any, columns: Sequence[str] | None = None, cell: Callable[[Any], str] = str) -> list[str]:
    """The lines of a Markdown table of ``frame``'s ``columns`` (default: all), each value written by ``cell``."""
    cols = list(frame.columns if columns is None else columns)
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for _, row in frame.iterrows():
        lines.append("| " + " | ".join(cell(row[c]) for c in cols) + " |")
    return lines


def splice(lines: list[str], marks: tuple[str, str], section: list[str], before: str) -> list[str]:
    """``lines`` with ``section`` in place of the lines from ``marks[0]`` to ``marks[1]`` and the line after it;
    without the marks, ``section`` goes in before the first line starting with ``before``.

    Raises
    ------
    ValueError
        Neither the marks nor a line starting with ``before`` are in ``lines``.
    """
    out = list(lines)
    if marks[0] in out:
        i, j = out.index(marks[0]), out.index(marks[1])
        out[i:j + 2] = section
        return out
    at = next((n for n, line in enumerate(out) if line.startswith(before)), None)
    if at is None:
        raise ValueError(f"no line starts with {before!r} (nor is {marks[0]!r} there) to put the section at")
    out[at:at] = section
    return out


#: Markers of a quote inside a text (:meth:`Quotes.mark`): open, key/text separator, close.
OPEN, SEP, CLOSE = "\u2983", "\u2982", "\u2984"


class Quotes:
    """The numbers a report's prose quotes, in the order quoted: ``key -> (value, text, source)``.

    Parameters
    ----------
    digits, missing, sci
        The defaults of :func:`fmt` for a value quoted without a format.
    """

    def __init__(self, digits: int = 3, *, missing: str = "nan", sci: bool = False) -> None:
        self.rows: dict[str, tuple[Any, str, str]] = {}
        self.digits, self.missing, self.sci = digits, missing, sci

    def text(self, value: Any, spec: str | None = None) -> str:
        """How ``value`` is quoted: a string as it is; ``spec`` ``"d"`` rounds to an integer, another
        ``spec`` is a :func:`format` spec (``".2g"``); without one, :func:`fmt` with this object's defaults."""
        if isinstance(value, str):
            return value
        if spec == "d":
            return str(int(round(float(value))))
        if spec is not None:
            return format(float(value), spec)
        return fmt(value, self.digits, missing=self.missing, sci=self.sci)

    def add(self, key: str, value: Any, spec: str | None = None, source: str = "", *, text: str | None = None) -> str:
        """Quote ``value`` under ``key`` (``text`` given, or :meth:`text`); returns the text."""
        t = self.text(value, spec) if text is None else text
        self.rows[key] = (value, t, source)
        return t

    def mark(self, key: str, value: Any, text: str) -> str:
        """Quote ``value`` as ``text`` and return it between markers, for :meth:`unmark` / :meth:`template`."""
        self.rows[key] = (value, text, "")
        return f"{OPEN}{key}{SEP}{text}{CLOSE}"

    @staticmethod
    def unmark(marked: str) -> str:
        """The text with every marked quote replaced by its text."""
        return re.sub(f"{OPEN}[^{SEP}]*{SEP}([^{CLOSE}]*){CLOSE}", r"\1", marked)

    @staticmethod
    def template(marked: str) -> str:
        """The text with every marked quote replaced by ``{key}``."""
        return re.sub(f"{OPEN}([^{SEP}]*){SEP}[^{CLOSE}]*{CLOSE}", r"{\1}", marked)

    def texts(self) -> dict[str, str]:
        """``key -> text``."""
        return {k: t for k, (_v, t, _s) in self.rows.items()}

    def fill(self, template: str) -> str:
        """``template`` (``{key}`` placeholders) filled with the quoted texts (:func:`fill`)."""
        return fill(template, self.texts())

    def frame(self, value: Callable[[Any], Any] | None = None, source: bool = True) -> Any:
        """A DataFrame ``key, value, text[, source]``; ``value`` maps each value (default: a string's is NaN)."""
        import pandas as pd

        conv = value or (lambda v: math.nan if isinstance(v, str) else v)
        rows = [(k, conv(v), t, s) if source else (k, conv(v), t) for k, (v, t, s) in self.rows.items()]
        return pd.DataFrame(rows, columns=["key", "value", "text", "source"][:4 if source else 3])


# ------------------------------------------------------------------------------------------------ runs
def log_progress(logger: logging.Logger | str, label: str, every: float = 0.1) -> Progress:
    """A :data:`Progress` that logs ``"<label>: <what>: done/total runs"`` at INFO every ``every`` of the runs."""
    lg = logging.getLogger(logger) if isinstance(logger, str) else logger

    def progress(done: int, total: int, what: str) -> None:
        step = max(1, int(total * every))
        if done == total or done % step == 0:
            lg.info("%s: %s: %d/%d runs", label, what, done, total)

    return progress


def run_all(fn: Callable[[T], R], items: Sequence[T], *, workers: int | None = None, progress: Progress | None = None,
            what: str = "runs", chunksize: int = 1, each: Callable[[int, R], None] | None = None) -> list[R]:
    """``[fn(item) for item in items]``, on one process pool.

    Parameters
    ----------
    fn
        A module-level function (it is sent to the worker processes).
    items
        The points; the results come back in their order.
    workers
        Processes (default: one per CPU, no more than there are items); ``1`` runs in this process.
    progress
        Called as ``progress(done, len(items), what)`` after each result.
    chunksize
        Items sent to a worker at a time.
    each
        Called as ``each(index, result)`` as each result comes (before ``progress``): to keep it at once, in a
        cache, so that a run stopped half-way keeps what it made.
    """
    n = len(items)
    workers = workers or max(1, min(n, os.cpu_count() or 1))
    out: list[R] = []
    if workers <= 1 or n <= 1:
        results: Iterable[R] = map(fn, items)
        pool = None
    else:
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # one BLAS thread per worker
        pool = ProcessPoolExecutor(max_workers=workers)
        results = pool.map(fn, items, chunksize=max(1, chunksize))
    try:
        for r in results:
            if each is not None:
                each(len(out), r)
            out.append(r)
            if progress is not None:
                progress(len(out), n, what)
    finally:
        if pool is not None:
            pool.shutdown(cancel_futures=True)
    return out


def sweep(path: Path, out: Path, *, workers: int | None = None, progress: bool = False, complete: bool = True) -> Any:
    """Run (or resume) the sweep file ``path`` into ``out`` (:func:`netsim.sweep.run.run_sweep`) and return its
    result (``.summary``, ``.wall_time_s``, ``.n_executed``, ``.n_resumed``).

    Parameters
    ----------
    complete
        Refuse a sweep with a run that gave no result (status ``error``, ``interrupted`` or ``pending``:
        :func:`netsim.sweep.summary.require_results`), which a table would otherwise count as a failed run.
    """
    from netsim.sweep.run import run_sweep
    from netsim.sweep.summary import require_results

    res = run_sweep(path, out=out, workers=workers, progress=progress)
    if complete:
        require_results(res.summary, Path(path).stem)
    return res


# ------------------------------------------------------------------------------------------------ cache
def scenario_key(source: Any, overrides: Mapping[str, Any] | None = None, seed: int | None = None) -> str:
    """The scenario hash of a run of ``source`` with ``overrides`` and ``seed`` (as :func:`netsim.runner.run`
    applies them): the ``scenario_hash`` of the run's ``meta.json`` and of a sweep's point."""
    from netsim.scenario import load_scenario, scenario_hash

    ov = dict(overrides or {})
    if seed is not None:
        ov["seed"] = int(seed)
    return scenario_hash(load_scenario(source, overrides=ov or None))


def code_fingerprint(files: Iterable[Path], extra: str = "") -> str:
    """12 hex digits over the bytes of ``files`` and ``extra``: what a scenario hash does not cover (a study's
    own numeric modules, run lengths set in code)."""
    h = hashlib.sha256()
    for path in files:
        h.update(Path(path).read_bytes())
    h.update(extra.encode())
    return h.hexdigest()[:12]


def _plain(value: Any) -> Any:
    """A numpy scalar as the Python number it holds (for JSON)."""
    if hasattr(value, "item"):
        return value.item()
    raise TypeError(f"a run cache keeps numbers and strings, not {type(value).__name__}")


class RunCache:
    """Rows of runs made earlier with the same code: ``<folder>/<code>/<key>.json``, one file per run.

    Parameters
    ----------
    folder
        The cache folder (``None``: rows are kept in memory, for this object's life only).
    code
        The code's fingerprint (:func:`code_fingerprint`); another one starts an empty cache.

    A key is a run's scenario hash (:func:`scenario_key`), with a prefix where the same scenario is computed
    another way. Values are JSON (numbers, strings, NaN), written atomically; ``reused`` counts the hits. Arrays
    go beside them as ``<key>.npz`` (:meth:`put_arrays`), read back with ``allow_pickle=False``: nothing of the
    cache is unpickled.
    """

    def __init__(self, folder: Path | None, code: str = "") -> None:
        self.folder = None if folder is None else Path(folder) / (code or "any")
        self.reused = 0
        self._memory: dict[str, dict[str, Any]] = {}
        self._memory_arrays: dict[str, dict[str, Any]] = {}

    def _path(self, key: str) -> Path | None:
        if not re.fullmatch(r"[A-Za-z0-9_.-]+", key):
            raise ValueError(f"cache key {key!r}: use letters, digits, '_', '.' and '-'")
        return None if self.folder is None else self.folder / f"{key}.json"

    def get(self, key: str) -> dict[str, Any] | None:
        """The row kept under ``key``, or ``None``."""
        path = self._path(key)
        if path is None:
            row = self._memory.get(key)
            self.reused += row is not None
            return None if row is None else dict(row)
        if not path.is_file():
            return None
        try:
            row = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            log.warning("run cache: %s is unreadable; the run is made again", path)
            return None
        self.reused += 1
        return row

    def put(self, key: str, row: Mapping[str, Any]) -> None:
        """Keep ``row`` under ``key``."""
        path = self._path(key)
        if path is None:
            self._memory[key] = dict(row)
            return
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps(dict(row), allow_nan=True, default=_plain), encoding="utf-8")
        tmp.replace(path)

    def get_arrays(self, key: str) -> dict[str, Any] | None:
        """The arrays kept under ``key`` (``<key>.npz``, read without pickled objects), or ``None``."""
        import numpy as np

        path = self._path(key)
        if path is None:
            arrays = self._memory_arrays.get(key)
            return None if arrays is None else dict(arrays)
        path = path.with_suffix(".npz")
        if not path.is_file():
            return None
        try:
            with np.load(path, allow_pickle=False) as z:
                return {name: z[name] for name in z.files}
        except (OSError, ValueError):
            log.warning("run cache: %s is unreadable; the runs are made again", path)
            return None

    def put_arrays(self, key: str, arrays: Mapping[str, Any]) -> None:
        """Keep numeric ``arrays`` (name -> array) under ``key``, as ``<key>.npz``."""
        import numpy as np

        path = self._path(key)
        if path is None:
            self._memory_arrays[key] = {k: np.asarray(v) for k, v in arrays.items()}
            return
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f"{key}.{os.getpid()}.tmp.npz")
        named: dict[str, Any] = {k: np.asarray(v) for k, v in arrays.items()}  # Any: the stubs read a key as allow_pickle
        np.savez(tmp, **named)
        tmp.replace(path.with_suffix(".npz"))
