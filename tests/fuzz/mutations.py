"""Malformed scenarios made from the shipped ones, and how ``netsim validate`` / ``netsim run`` treat each.

A :class:`Mutation` is one edit of one shipped scenario (delete a key, retype a value, duplicate a node or a
task, an extreme number, an unknown unit, a bad reference, an absurd name) with what the edit must give:
``must_refuse=True`` when the result is malformed whatever the scenario (a deleted required key, NaN, an
unknown unit, ...), ``None`` when it may be fine (a negative number where negatives can be legal): then only
"no traceback, no hang, run refuses exactly what validate refuses" is asked.

:func:`evaluate` runs one mutated file through the real command line (``netsim.cli.main``) in this process:
``validate`` as written, then ``validate`` and ``run`` with the same short duration override (unless the edit
is the duration itself), each under a time limit, and classifies what came out (:class:`Outcome`).
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import io
import math
import re
import signal
import warnings
from pathlib import Path
from typing import Any, Iterator

from netsim.scenario.safe_yaml import dump_text, load_file

ROOT = Path(__file__).resolve().parents[2]
def _is_sweep(path: Path) -> bool:
    with open(path, encoding="utf-8") as fh:
        return any(line.startswith(("base:", "factors:")) for line in fh)


#: Shipped scenarios (sweep files, with 'base:' and 'factors:', are left out: they are another format).
SCENARIOS = sorted(p for p in (ROOT / "scenarios").glob("*.yaml") if not _is_sweep(p))
#: The duration the run phase uses (keeps a case under a second).
SHORT = "30 ms"
#: Placeholder replaced in the text by an integer with more digits than Python converts by default.
HUGE_INT_TOKEN = "HUGE_INT_PLACEHOLDER"
HUGE_INT_TEXT = "9" * 5000

Path_ = tuple[Any, ...]


@dataclasses.dataclass(frozen=True)
class Mutation:
    """One edit of a scenario: ``kind``, the YAML ``path`` it touches, and whether it must be refused."""

    scenario: str
    kind: str
    path: str
    detail: str
    must_refuse: bool | None
    data: Any = dataclasses.field(repr=False, compare=False, default=None)
    raw_text: str | None = dataclasses.field(repr=False, compare=False, default=None)

    @property
    def text(self) -> str:
        """The mutated scenario as YAML text (dumped when first asked for)."""
        return self.raw_text if self.raw_text is not None else dump(self.data)


@dataclasses.dataclass
class Outcome:
    """What the command line did with one mutated file."""

    validate_exit: int | None = None
    validate_out: str = ""
    run_validate_exit: int | None = None
    run_exit: int | None = None
    run_out: str = ""
    traceback: str | None = None
    hang: str | None = None
    leaked_warnings: list[str] = dataclasses.field(default_factory=list)

    def error_lines(self) -> list[str]:
        """The problem lines validate printed (not 'valid', not warnings, not the closing count 'N problems')."""
        return [ln for ln in self.validate_out.splitlines()
                if ln.strip() and " warning: " not in ln and not ln.endswith(": valid") and "valid (" not in ln
                and not re.fullmatch(r"\d+ problems?( in total)?", ln.strip())]


# ------------------------------------------------------------------------------------------ reading/writing
def load(path: Path) -> dict[str, Any]:
    """A shipped scenario as plain data (read as netsim reads it)."""
    return load_file(path)[0]


def dump(raw: Any) -> str:
    """YAML text of ``raw`` (``HUGE_INT_TOKEN`` strings become a 5000-digit integer)."""
    text = dump_text(raw, width=4096)
    return text.replace(f"'{HUGE_INT_TOKEN}'", HUGE_INT_TEXT).replace(HUGE_INT_TOKEN, HUGE_INT_TEXT)


def _leaves(node: Any, prefix: Path_ = ()) -> Iterator[tuple[Path_, Any]]:
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _leaves(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _leaves(v, (*prefix, i))
    else:
        yield prefix, node


def _get(raw: Any, path: Path_) -> Any:
    for part in path:
        raw = raw[part]
    return raw


def _set(raw: Any, path: Path_, value: Any) -> Any:
    out = copy.deepcopy(raw)
    _get(out, path[:-1])[path[-1]] = value
    return out


def _delete(raw: Any, path: Path_) -> Any:
    out = copy.deepcopy(raw)
    del _get(out, path[:-1])[path[-1]]
    return out


def fmt(path: Path_) -> str:
    """``nodes.n.tasks[0].period`` from path parts."""
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


_TIME = re.compile(r"^\s*[-+]?[\d.]+(?:[eE][-+]?\d+)?\s*(ns|us|µs|ms|s|min|h)\s*$")
_RATE = re.compile(r"^\s*[\d.eE+-]+\s*[kKMG]?(bit/s|bps|b/s)\s*$")
_SKIP_TOP = ("description", "baseline")  # free text; overrides may hold anything
#: Keys whose text values are labels a scenario makes up, not references to something declared.
_LABEL_KEYS = ("tag", "record_as", "sensor_tag", "actuator_tag")


def _numeric(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


# ------------------------------------------------------------------------------------------ the edits
def _required(raw: dict[str, Any]) -> Iterator[Path_]:
    yield ("name",)
    yield ("duration",)
    if isinstance(raw.get("plant"), dict):
        yield ("plant", "model")
    for n, node in (raw.get("nodes") or {}).items():
        for kind in ("tasks", "handlers"):
            for i, item in enumerate(node.get(kind) or []):
                yield ("nodes", n, kind, i, "name")
                yield ("nodes", n, kind, i, "program")
                if kind == "tasks" and "period" in item and item.get("release", "periodic") == "periodic":
                    yield ("nodes", n, kind, i, "period")
    for n in raw.get("networks") or {}:
        yield ("networks", n, "type")
    for n, ch in (raw.get("io") or {}).items():
        yield ("io", n, "type")
        if ch.get("type") == "encoder":
            yield ("io", n, "step")
            yield ("io", n, "tick")
    for n in raw.get("signals") or {}:
        yield ("signals", n, "type")
    for i, _ in enumerate(raw.get("metrics") or []):
        yield ("metrics", i, "type")


def _declared_names(raw: dict[str, Any]) -> set[str]:
    names: set[str] = set()
    for key in ("nodes", "networks", "signals", "io"):
        names |= {k for k in (raw.get(key) or {}) if isinstance(k, str)}
    return names


def _duplicate_node(text: str, node: str) -> str:
    """The YAML text with the block of ``nodes.<node>`` written twice (a duplicate mapping key)."""
    lines = text.splitlines(keepends=True)
    start = lines.index("nodes:\n")
    head = next(i for i in range(start + 1, len(lines)) if lines[i].rstrip("\n") in (f"  {node}:", f"  '{node}':"))
    end = head + 1
    while end < len(lines) and lines[end].startswith("   "):
        end += 1
    return "".join(lines[:end] + lines[head:end] + lines[end:])


def mutations(path: Path) -> list[Mutation]:
    """Every edit this generator makes of the scenario at ``path`` (deterministic order)."""
    raw = load(path)
    sc = path.name
    out: list[Mutation] = []

    def add(kind: str, at: Path_, detail: str, must: bool | None, new: Any = None, text: str | None = None) -> None:
        out.append(Mutation(sc, kind, fmt(at), detail, must, new, text))

    for at in _required(raw):
        try:
            add("delete_required", at, "deleted", True, _delete(raw, at))
        except (KeyError, IndexError):
            continue
    names = _declared_names(raw)
    for at, value in _leaves(raw):
        if not at or at[0] in _SKIP_TOP:
            continue
        add("delete_any", at, "deleted", None, _delete(raw, at))
        add("retype", at, "value -> mapping", True, _set(raw, at, {"bogus": 1}))
        if _numeric(value):
            add("retype", at, "number -> text", True, _set(raw, at, "abc"))
            for bad, label in ((math.nan, "nan"), (math.inf, "inf"), (-math.inf, "-inf"), (1e308, "1e308")):
                add("extreme", at, label, True, _set(raw, at, bad))
            add("extreme", at, "huge int", True, _set(raw, at, HUGE_INT_TOKEN))
            add("extreme", at, "negative", None, _set(raw, at, -abs(value) - 1))
            add("extreme", at, "zero", None, _set(raw, at, 0))
        elif isinstance(value, str) and _TIME.match(value):
            number = value.split()[0] if " " in value.strip() else re.sub(r"[a-zµ]+$", "", value.strip())
            add("unit", at, "unknown unit", True, _set(raw, at, f"{number} parsecs"))
            add("unit", at, "no unit", None if float(number) == 0 else True, _set(raw, at, float(number)))
            for bad in ("3e10 s", "1e300 s", "1e20 ns", "99999999999999999999 s"):
                add("extreme", at, f"time {bad}", True, _set(raw, at, bad))
            add("extreme", at, "time nan", True, _set(raw, at, "nan s"))
            add("extreme", at, "time -1 s", None, _set(raw, at, "-1 s"))
        elif isinstance(value, str) and _RATE.match(value):
            add("unit", at, "unknown rate unit", True, _set(raw, at, "1 Mbyte/s"))
        elif isinstance(value, str) and value in names and at[-1] != "name":
            # a message tag, a record_as name and a record entry only happen to equal a declared name: they are
            # labels (record names are checked after the run, in meta.json), so 'ghost_ref' may be fine there
            label = at[-1] in _LABEL_KEYS or at[0] == "record"
            add("reference", at, f"'{value}' -> ghost", None if label else True, _set(raw, at, "ghost_ref"))
    for n, node in (raw.get("nodes") or {}).items():
        tasks = node.get("tasks") or []
        if tasks:
            dup = copy.deepcopy(raw)
            dup["nodes"][n]["tasks"].append(copy.deepcopy(tasks[0]))
            add("duplicate", ("nodes", n, "tasks", len(tasks)), "task duplicated", True, dup)
            if not node.get("handlers"):
                add("empty", ("nodes", n, "tasks"), "tasks: []", True, _set(raw, ("nodes", n, "tasks"), []))
        add("duplicate", ("nodes", n), "node duplicated (YAML key)", True, text=_duplicate_node(dump(raw), n))
        renamed = copy.deepcopy(raw)
        renamed["nodes"] = {("n" * 10**6 if k == n else k): v for k, v in raw["nodes"].items()}
        add("name", ("nodes", n), "10^6-character node name", True, renamed)
        break  # one node per scenario is enough for these
    if raw.get("nodes"):
        add("empty", ("nodes",), "nodes: {}", True, _set(raw, ("nodes",), {}))
    add("name", ("name",), "10^6-character name", True, _set(raw, ("name",), "s" * 10**6))
    add("name", ("name",), "empty name", True, _set(raw, ("name",), ""))
    return out


def all_mutations() -> list[Mutation]:
    """The edits of every shipped scenario."""
    return [m for path in SCENARIOS for m in mutations(path)]


# ------------------------------------------------------------------------------------------ running a case
class Hang(BaseException):
    """Raised by the alarm when a command takes longer than its limit."""


@contextlib.contextmanager
def _limit(seconds: float) -> Iterator[None]:
    def _raise(signum: int, frame: Any) -> None:
        raise Hang(f"no answer after {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, _raise)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _cli(argv: list[str], seconds: float, outcome: Outcome, phase: str) -> tuple[int | None, str]:
    """Run ``netsim <argv>`` in this process; returns (exit code, stdout + stderr)."""
    import logging
    import traceback

    from netsim.cli import main

    buf = io.StringIO()
    code: int | None = None
    root = logging.getLogger()
    handlers = list(root.handlers)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf), _limit(seconds):
                code = main(argv)
        except Hang as exc:
            outcome.hang = outcome.hang or f"{phase}: {exc}"
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        except BaseException as exc:  # noqa: BLE001 - every escaping exception is a traceback shown to the user
            if isinstance(exc, KeyboardInterrupt):
                raise
            outcome.traceback = outcome.traceback or f"{phase}: " + "".join(
                traceback.format_exception_only(type(exc), exc)).strip()[:300]
        finally:
            for h in list(root.handlers):
                if h not in handlers:
                    root.removeHandler(h)
    for w in caught:
        if issubclass(w.category, RuntimeWarning):
            outcome.leaked_warnings.append(f"{phase}: {w.category.__name__}: {w.message} ({Path(w.filename).name})")
    return code, buf.getvalue()


def evaluate(m: Mutation, workdir: Path, seconds: float = 20.0, run: bool = True) -> Outcome:
    """Run ``m`` through ``netsim validate`` and (unless ``run=False``) ``netsim run`` with a short duration."""
    workdir.mkdir(parents=True, exist_ok=True)
    file = workdir / f"{m.scenario.removesuffix('.yaml')}_case.yaml"
    file.write_text(m.text, encoding="utf-8")
    outcome = Outcome()
    outcome.validate_exit, outcome.validate_out = _cli(["validate", str(file)], seconds, outcome, "validate")
    if not run:
        return outcome
    short = [] if m.path == "duration" else ["--set", f"duration={SHORT}"]
    outcome.run_validate_exit, _ = _cli(["validate", str(file), *short], seconds, outcome, "validate --set")
    outcome.run_exit, outcome.run_out = _cli(
        ["run", str(file), "-q", "--no-progress", "--out", str(workdir / "out"), *short], seconds, outcome, "run")
    return outcome


_LINE = re.compile(r"^(?P<file>[^:]+):(?P<line>\d+|None)?:? ?(?P<rest>.*)$")
#: Words that tell the user what to change (a message without one of them "gives no fix").
FIX_WORDS = ("add ", "remove", "write", "use ", "set ", "did you mean", "expected", "must", "should", "give ",
             "e.g.", "between", "at most", "at least", "rename", "needs", "only ", "one of", "change", "put ",
             "input should", "field required", "shorten", "lower", "raise", "choose", "send ", "attach",
             "not allowed", "extra inputs", "valid", "fix ", "replace", "refused", "make ", "define ",
             "measure ", "declare ", "(known ", "(known: ")  # a list of the known names says what may be written


def message_has_path(line: str, file_name: str) -> bool:
    """True when ``file:line: path: message`` names a YAML path (a bare ``file: message`` does not)."""
    rest = line.split(f"{file_name}:", 1)[-1]
    rest = re.sub(r"^\d+: ", "", rest.strip())
    head = rest.split(": ", 1)[0]
    return ": " in rest and re.fullmatch(r"[A-Za-z0-9_\-\[\].]+", head or "") is not None


def message_has_fix(line: str) -> bool:
    """True when the message says what to change (see :data:`FIX_WORDS`)."""
    low = line.lower()
    return any(w in low for w in FIX_WORDS)


@dataclasses.dataclass
class Figures:
    """Counts over many cases (the report's fuzz figures)."""

    cases: int = 0
    must_refuse: int = 0
    tracebacks: int = 0
    hangs: int = 0
    exit0_on_bad_validate: int = 0
    exit0_on_bad_run: int = 0
    disagree: int = 0
    no_path: int = 0
    no_fix: int = 0
    leaked_warnings: int = 0
    examples: dict[str, list[str]] = dataclasses.field(default_factory=dict)

    def note(self, what: str, m: Mutation, extra: str = "") -> None:
        self.examples.setdefault(what, [])
        if len(self.examples[what]) < 8:
            self.examples[what].append(f"{m.scenario} {m.kind} {m.path} ({m.detail}) {extra}".strip()[:400])

    def add(self, m: Mutation, o: Outcome, file_name: str) -> list[str]:
        """Count one case; returns the defects found in it (empty when the case behaved)."""
        self.cases += 1
        self.must_refuse += bool(m.must_refuse)
        bad: list[str] = []
        if o.traceback:
            self.tracebacks += 1
            bad.append(f"traceback: {o.traceback}")
            self.note("traceback", m, o.traceback)
        if o.hang:
            self.hangs += 1
            bad.append(f"hang: {o.hang}")
            self.note("hang", m, o.hang)
        if m.must_refuse and o.validate_exit == 0:
            self.exit0_on_bad_validate += 1
            bad.append("validate exit 0 on bad input")
            self.note("exit0_validate", m)
        if m.must_refuse and o.run_exit == 0:
            self.exit0_on_bad_run += 1
            bad.append("run exit 0 on bad input")
            self.note("exit0_run", m)
        if o.run_validate_exit is not None and o.run_exit is not None and (o.run_validate_exit == 0) != (o.run_exit == 0):
            self.disagree += 1
            bad.append(f"run and validate disagree: validate={o.run_validate_exit} run={o.run_exit}: "
                       f"{o.run_out.strip()[-300:]}")
            self.note("disagree", m, f"validate={o.run_validate_exit} run={o.run_exit}: {o.run_out.strip()[-200:]}")
        lines = o.error_lines() if o.validate_exit else []
        if any(not message_has_path(ln, file_name) for ln in lines) and m.path:
            self.no_path += 1
            line = next(ln for ln in lines if not message_has_path(ln, file_name))
            bad.append(f"message without a path: {_after_file(line, file_name)[:300]}")
            self.note("no_path", m, line[:200])
        if any(not message_has_fix(ln) for ln in lines):
            self.no_fix += 1
            line = next(ln for ln in lines if not message_has_fix(ln))
            bad.append(f"message without a fix: {_after_file(line, file_name)[:300]}")
            self.note("no_fix", m, line[:200])
        if o.leaked_warnings:
            self.leaked_warnings += 1
            bad.append(f"python warning shown: {o.leaked_warnings[0]}")
            self.note("warnings", m, o.leaked_warnings[0])
        return bad


def _after_file(line: str, file_name: str) -> str:
    """``line`` from the character after the case file's name (the temporary folder differs per case)."""
    return line.split(f"{file_name}:", 1)[-1].strip()


def case_file_name(m: Mutation) -> str:
    """The name :func:`evaluate` gives the file of ``m``."""
    return f"{m.scenario.removesuffix('.yaml')}_case.yaml"

