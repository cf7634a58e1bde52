"""Sweep files: the schema, loading, and the expansion into points with order-independent seeds.

A sweep file names a base scenario and *factors*. A factor is one column of ``summary.csv``; it sets one
or more dotted paths of the base scenario (tied paths, e.g. ``delta_s = sigma_s``) to each of its values.
``mode: product`` runs the cartesian product of the factor values (the first factor varies slowest);
``mode: list`` runs the explicit ``points``. Every point runs ``replicates`` times.

Each run's seed is a hash of the sweep seed, the point's factor values and the replicate number, never of the
order in which runs execute, so 1 worker, N workers and a Dask cluster give the same numbers.

Examples
--------
>>> spec = SweepSpec.model_validate({"sweep": "demo", "base": "case.yaml",
...     "factors": {"gain": {"paths": ["plant.params.gain"], "values": [1, 2]}}})
>>> [p.values for p in expand_points(spec)]
[{'gain': 1}, {'gain': 2}]
"""

from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import Field, ValidationError, field_validator, model_validator

from netsim.errors import ConfigError
from netsim.scenario.paths import plain_copy
from netsim.units import StrictModel

__all__ = [
    "Grid",
    "LogGrid",
    "Factor",
    "SurfaceSpec",
    "SweepSpec",
    "Point",
    "Sweep",
    "load_sweep",
    "expand_points",
    "derive_seed",
    "canonical_json",
    "grid_value",
]


#: Significant digits a generated grid value is rounded to (see :func:`grid_value`).
GRID_DIGITS = 12


def grid_value(value: float) -> float:
    """A generated grid value rounded to :data:`GRID_DIGITS` significant digits.

    ``np.logspace(-9, -1, 11)[5]`` is ``1e-05`` with one numpy build and ``9.999999999999999e-06`` with
    another (its power function differs in the last bit). A point's seed is derived from the exact text of
    its values (:func:`derive_seed`), so that last bit would change the noise a point draws. Rounded, the
    grid's points are the round decimal values themselves (``1e-05``), the same with every numpy, and a
    point gets the same seed as the same value written in ``values:``.
    """
    return float(f"{float(value):.{GRID_DIGITS}g}")


class Grid(StrictModel):
    """``linspace``: ``num`` evenly spaced values from ``start`` to ``stop`` (both included), each rounded to
    12 significant digits (:func:`grid_value`)."""

    start: float
    stop: float
    num: int = Field(ge=1)

    def values(self) -> list[float]:
        """The grid values as Python floats (12 significant digits)."""
        return [grid_value(v) for v in np.linspace(self.start, self.stop, self.num)]


class LogGrid(Grid):
    """``logspace``: ``base**x`` for ``num`` evenly spaced exponents ``x`` from ``start`` to ``stop``, each
    rounded to 12 significant digits (:func:`grid_value`)."""

    base: float = Field(default=10.0, gt=0)

    def values(self) -> list[float]:
        """The grid values as Python floats (12 significant digits)."""
        return [grid_value(v) for v in np.logspace(self.start, self.stop, self.num, base=self.base)]


class Factor(StrictModel):
    """One factor: the scenario paths it sets (tied) and its values (one of three forms)."""

    paths: list[str] = Field(min_length=1)
    values: list[Any] | None = None
    linspace: Grid | None = None
    logspace: LogGrid | None = None

    @field_validator("paths", mode="before")
    @classmethod
    def _one_path(cls, v: Any) -> Any:
        return [v] if isinstance(v, str) else v

    def levels(self) -> list[Any]:
        """The values this factor takes (empty when the sweep lists its points explicitly)."""
        if self.values is not None:
            return list(self.values)
        if self.linspace is not None:
            return self.linspace.values()
        if self.logspace is not None:
            return self.logspace.values()
        return []

    @property
    def is_log(self) -> bool:
        """True when the factor is log-spaced (the surface figure then uses log axes)."""
        return self.logspace is not None

    @model_validator(mode="after")
    def _one_form(self) -> "Factor":
        given = [k for k in ("values", "linspace", "logspace") if getattr(self, k) is not None]
        if len(given) > 1:
            raise ValueError(f"give only one of values/linspace/logspace, got {', '.join(given)}")
        if self.values is not None and not self.values:
            raise ValueError("'values' is empty; give at least one value")
        return self


class SurfaceSpec(StrictModel):
    """The surface figure and arg-min of a two-factor sweep: ``z`` over ``x`` and ``y``."""

    x: str
    y: str
    z: str = "GPI"
    logx: bool | None = None
    logy: bool | None = None


class SweepSpec(StrictModel):
    """A sweep file (see the module docstring and the README section "Sweep files")."""

    sweep: str = Field(pattern=r"^[A-Za-z0-9_-]+$", max_length=100)  # a folder name (issue 14)
    base: str
    description: str = ""
    seed: int = Field(default=0, ge=0)
    mode: Literal["product", "list"] = "product"
    factors: dict[str, Factor]
    replicates: int = Field(default=1, ge=1)
    points: list[dict[str, Any]] | None = None
    surface: SurfaceSpec | None = None
    #: What each run's folder under ``points/`` holds: ``full`` (the whole run folder: scenario.yaml, signals,
    #: jobs, messages, metrics, meta.json) or ``metrics`` (metrics.csv and meta.json only: a sweep read through its
    #: summary.csv, as the GPI surface, writes about a sixth of the bytes and runs faster).
    runs: Literal["full", "metrics"] = "full"

    @model_validator(mode="after")
    def _consistent(self) -> "SweepSpec":
        if not self.factors:
            raise ValueError("'factors' is empty; name at least one factor with its paths and values")
        reserved = {"index", "replicate", "seed", "status", "error", "folder"}
        clash = sorted(reserved & set(self.factors))
        if clash:
            raise ValueError(f"factor name(s) {clash} are reserved summary.csv columns; rename them")
        if self.mode == "product":
            if self.points is not None:
                raise ValueError("'points' is only used with mode: list")
            missing = [name for name, f in self.factors.items() if not f.levels()]
            if missing:
                raise ValueError(f"factor(s) {missing} have no values/linspace/logspace (needed for mode: product)")
        else:
            if not self.points:
                raise ValueError("mode: list needs a non-empty 'points' list, e.g. [{factor: value, ...}]")
            names = set(self.factors)
            for i, p in enumerate(self.points):
                unknown, missing = sorted(set(p) - names), sorted(names - set(p))
                if unknown or missing:
                    raise ValueError(
                        f"points[{i}]: " + "; ".join(
                            ([f"unknown factor(s) {unknown}"] if unknown else [])
                            + ([f"missing factor(s) {missing}"] if missing else [])
                        )
                    )
        if self.surface is not None:
            for axis in ("x", "y"):
                name = getattr(self.surface, axis)
                if name not in self.factors:
                    raise ValueError(f"surface.{axis}: '{name}' is not a factor (factors: {', '.join(self.factors)})")
        return self

    def surface_problem(self) -> tuple[str, str] | None:
        """``(path, message)`` when a surface axis names a factor with non-numeric values, else None.

        The surface is drawn after every point has run; this check lets ``load_sweep`` (so ``netsim validate``
        and ``netsim sweep``) refuse such a sweep before anything runs.
        """
        if self.surface is None:
            return None
        for axis in ("x", "y"):
            name = getattr(self.surface, axis)
            levels = self.factors[name].levels() if self.mode == "product" else [p[name] for p in self.points or []]
            bad = [v for v in levels if isinstance(v, bool) or not isinstance(v, (int, float))]
            if bad:
                shown = ", ".join(repr(v) for v in bad[:3]) + (", ..." if len(bad) > 3 else "")
                return (f"surface.{axis}", f"factor '{name}' has non-numeric values ({shown}); a surface needs "
                        "numbers on both axes: choose a numeric factor or remove 'surface:'")
        return None


def _plain(value: Any) -> Any:
    """numpy scalars and tuples as plain JSON-able Python values."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    return value


def canonical_json(data: Any) -> str:
    """Compact JSON with sorted keys; floats written with ``repr`` (exact, platform-independent)."""
    return json.dumps(_plain(data), sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=True)


def derive_seed(sweep_seed: int, values: dict[str, Any], replicate: int) -> int:
    """The seed of one run: SHA-256 of the sweep seed, the point's factor values and the replicate.

    Returns a non-negative integer below ``2**63``; independent of the order in which points run.
    """
    text = canonical_json({"sweep_seed": int(sweep_seed), "values": values, "replicate": int(replicate)})
    return int.from_bytes(hashlib.sha256(text.encode()).digest()[:8], "big") >> 1


@dataclass(frozen=True)
class Point:
    """One run of a sweep: its position, factor values, replicate, seed and folder name."""

    index: int
    values: dict[str, Any]
    replicate: int
    seed: int
    key: str = field(default="")

    @property
    def folder(self) -> str:
        """``points/<index>-<key>`` relative to the sweep's output folder."""
        return f"points/{self.index:05d}-{self.key}"


def expand_points(spec: SweepSpec) -> list[Point]:
    """The sweep's runs in summary order: points in product (or list) order, replicates innermost."""
    names = list(spec.factors)
    if spec.mode == "product":
        grids = [spec.factors[n].levels() for n in names]
        combos = [dict(zip(names, map(_plain, c))) for c in _product(grids)]
    else:
        combos = [{n: _plain(p[n]) for n in names} for p in spec.points or []]
    out: list[Point] = []
    for values in combos:
        for r in range(spec.replicates):
            key = hashlib.sha256(canonical_json({"values": values, "replicate": r}).encode()).hexdigest()[:10]
            out.append(Point(len(out), values, r, derive_seed(spec.seed, values, r), key))
    return out


def _product(grids: list[list[Any]]) -> list[tuple[Any, ...]]:
    import itertools

    return list(itertools.product(*grids))


@dataclass
class Sweep:
    """A loaded sweep: the spec, its file, the base scenario (raw mapping) and the expanded points."""

    spec: SweepSpec
    path: Path | None
    base_path: Path | None
    base: dict[str, Any]
    points: list[Point]
    #: The shadow check's verdict per text-valued level (see :meth:`point_raw`): ``(removed, problems)``.
    _shadow: dict[str, tuple[list[tuple[Any, ...]], list[Any]]] = field(default_factory=dict, repr=False)

    def point_raw(self, point: Point) -> dict[str, Any]:
        """The base scenario with the point's factor values written at every tied path (a deep copy).

        The values are overrides like ``netsim run --set`` (:mod:`netsim.scenario.overrides`): a text level of a
        preset-like field (``plant.params.friction.model: modes6``) removes the siblings the base spells out with
        the old preset's defaults, so the new preset fills them; siblings the base gives values of their own
        shadow the level, and :meth:`point_problems` says so (check_sweep refuses the sweep).
        """
        return self._point(point)[0]

    def point_problems(self, point: Point) -> list[Any]:
        """The :class:`~netsim.scenario.problems.Problem` s of the point's overrides that the base shadows."""
        return self._point(point)[1]

    def _point(self, point: Point) -> tuple[dict[str, Any], list[Any]]:
        import copy

        from netsim.scenario.paths import get_path, parse_path, set_path

        raw = copy.deepcopy(self.base)
        values = {path: value for name, value in point.values.items() for path in self.spec.factors[name].paths}
        for path, value in values.items():
            set_path(raw, path, copy.deepcopy(value))
        texts = [tuple(parse_path(p)) for p, v in values.items() if isinstance(v, str) and _NAME.fullmatch(v)]
        if not texts:
            return raw, []  # only a name picks a preset: grids of numbers and times never pay for the check
        parents = {t[:-1] for t in texts}
        key = canonical_json(sorted((p, v) for p, v in values.items() if tuple(parse_path(p))[:-1] in parents))
        if key not in self._shadow:
            from netsim.scenario.loader import shadow_verdict

            verdict = shadow_verdict(self.base, values)
            if verdict is None:
                return raw, []  # the point does not validate: check_scenario reports why; nothing cached
            self._shadow[key] = verdict
        removed, problems = self._shadow[key]
        for parts in removed:  # siblings that spelled out the old preset: the new one fills them
            get_path(raw, list(parts[:-1])).pop(parts[-1], None)
        return raw, list(problems)

    @property
    def name(self) -> str:
        """The sweep name (the ``sweep:`` key)."""
        return self.spec.sweep


#: A level that may name a preset (``modes6``, ``inband``): text that is not a number or a time ("5 ms").
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_-]*")


_FLOW_PATHS = re.compile(r"^(?P<head>\s*paths\s*:\s*)\[(?P<items>[^\"'#]*)\](?P<tail>\s*(?:#.*)?)$")


def quote_flow_paths(text: str) -> str:
    """Quote the items of ``paths: [a.b[0].c, ...]`` lines so YAML reads them as strings.

    In a YAML flow list, ``[`` and ``]`` are syntax, so the contract's ``paths: [nodes.s.tasks[0].x]`` is not
    valid YAML as written; the items of such lines (unquoted, no comments inside) are quoted here. Line
    numbers are kept.
    """
    out = []
    for line in text.splitlines(keepends=True):
        body = line.rstrip("\r\n")
        m = _FLOW_PATHS.match(body)
        if m and "[" in m.group("items"):
            items = [i.strip() for i in m.group("items").split(",") if i.strip()]
            quoted = ", ".join(json.dumps(i) for i in items)
            line = f"{m.group('head')}[{quoted}]{m.group('tail')}" + line[len(body):]
        out.append(line)
    return "".join(out)


def _read_yaml(path: Path, *, sweep_file: bool = False) -> Any:
    """The data of a sweep file or its base scenario, read as scenario files are (:mod:`netsim.scenario.safe_yaml`).

    Raises
    ------
    ConfigError
        For an unreadable or refused file (regular files only, bounded size, depth, tags and alias expansion,
        issue 14) and for invalid YAML, with the line.
    """
    from netsim.scenario.safe_yaml import YamlRefused, load_text, read_text

    try:
        text = read_text(str(path))
    except OSError as exc:
        raise ConfigError(f"cannot read '{path}': {exc.strerror or exc}") from None
    except YamlRefused as exc:
        raise _refusal(str(path), [("", exc.message, exc.line)]) from None
    if sweep_file:
        text = quote_flow_paths(text)
    try:
        return load_text(text)
    except YamlRefused as exc:
        if exc.syntax:
            raise _refusal(str(path), [("", f"not valid YAML: {exc.message.removeprefix('YAML syntax error: ')}; "
                                            "quote values that contain [ ] inside flow lists, e.g. "
                                            "paths: ['nodes.ctrl.tasks[0].params.k']", exc.line)]) from None
        raise _refusal(str(path), [("", exc.message, exc.line)]) from None


#: One problem of a sweep file: ``(path, message, line)``; the path is a dotted YAML path of the sweep file
#: ("" for the whole file), the line None when not known yet (:func:`netsim.sweep.check.check_sweep` looks it up).
SweepProblem = tuple[str, str, "int | None"]


def _refusal(where: str, problems: list[SweepProblem]) -> ConfigError:
    """One :class:`ConfigError` for the file ``where`` (a sweep file or its base scenario): every problem on its
    own line (``file:line: path: message``), the list itself as ``.problems`` and the file as ``.file``
    (:func:`netsim.sweep.check.check_sweep` makes one Problem of each, with its line)."""
    lines = []
    for path, message, line in problems:
        at = f"{where}:{line}" if line is not None else where
        lines.append(f"{at}: {path}: {message}" if path else f"{at}: {message}")
    exc = ConfigError("\n".join(lines))
    exc.problems = problems  # type: ignore[attr-defined]
    exc.file = where  # type: ignore[attr-defined]  # the sweep file, or its base scenario
    return exc


def _validation_problems(exc: ValidationError) -> list[SweepProblem]:
    out: list[SweepProblem] = []
    for err in exc.errors():
        loc = ""
        for part in err["loc"]:
            loc += f"[{part}]" if isinstance(part, int) else (f".{part}" if loc else str(part))
        msg = err["msg"].removeprefix("Value error, ")
        m = re.match(r"^((?:points|surface)(?:\[\d+\]|\.\w+)?): (.*)$", msg) if not loc else None
        if m:  # a check of the whole file that names its key in the message ("points[2]: unknown factor(s) ..")
            loc, msg = m.group(1), m.group(2)
        out.append((loc, msg, None))
    return out


def load_sweep(source: str | Path | dict[str, Any], *, base: dict[str, Any] | None = None) -> Sweep:
    """Read and check a sweep file (or mapping): schema, base scenario, factor paths, points.

    Parameters
    ----------
    source
        Path of the sweep YAML, or its content as a mapping (then ``base`` in it is read relative to the
        current folder unless ``base`` is given here).
    base
        The base scenario as a raw mapping, overriding the file named by the sweep's ``base:``.

    Raises
    ------
    ConfigError
        For schema errors, an unreadable base, an empty factor list, or a factor path that does not exist
        in the base scenario (with a "did you mean"); a last key that the base leaves at its default is
        accepted (see :func:`_check_paths`).
    """
    path = None if isinstance(source, dict) else Path(source)
    data = plain_copy(dict(source)) if isinstance(source, dict) else _read_yaml(path, sweep_file=True)  # type: ignore[arg-type]  # numpy values as lists (issue 26)
    where = str(path) if path else "sweep"
    if not isinstance(data, dict):
        raise _refusal(where, [("", "a sweep file is a mapping with keys sweep, base, factors, ...", None)])
    if "sweep" not in data and ("name" in data or "duration" in data):
        run_it = f"`netsim run {path}`" if path else "`netsim run FILE`"
        raise ConfigError(f"{where}: this is a scenario file (it has 'name:'/'duration:' and no 'sweep:'); "
                          f"run it with {run_it}, or give a sweep file (sweep:, base:, factors:)")
    if "factors" in data and not data["factors"]:
        raise _refusal(where, [("factors", "'factors' is empty; name at least one factor with its paths and values",
                                None)])
    try:
        spec = SweepSpec.model_validate(data)
    except ValidationError as exc:
        raise _refusal(where, _validation_problems(exc)) from None
    surface = spec.surface_problem()
    if surface is not None:
        raise _refusal(where, [(surface[0], surface[1], None)])
    base_path: Path | None = None
    if base is None:
        base_path = (path.parent if path else Path.cwd()) / spec.base
        raw = _read_yaml(base_path)
        if not isinstance(raw, dict):
            raise ConfigError(f"{where}: base scenario '{base_path}' is not a mapping")
        if isinstance(raw.get("plugins"), list):  # named relative to the base file; absolute for workers elsewhere
            raw["plugins"] = [str(base_path.parent.absolute() / f) if isinstance(f, str) else f for f in raw["plugins"]]
        from netsim.plant.fmu import absolute_fmu_path

        absolute_fmu_path(raw, base_path.parent)  # an fmu plant's file, for the same reason
    else:
        raw = base
    _check_paths(spec, raw, where)
    return Sweep(spec, path, base_path, raw, expand_points(spec))


def _check_paths(spec: SweepSpec, raw: dict[str, Any], where: str) -> None:
    """Every factor path must lead to a value of the base scenario, or name a key that the base leaves at
    its default: the last key may be missing from a mapping that exists, unless a key of that mapping is
    close to it (then it is taken as a typo). Whether such a key is a parameter at all is checked with the
    factor levels (the plugins' parameter models refuse unknown keys, with a "did you mean")."""
    from netsim.scenario.paths import did_you_mean, get_path, parse_path

    problems: list[SweepProblem] = []
    for name, factor in spec.factors.items():
        for i, p in enumerate(factor.paths):
            try:
                get_path(raw, p)
                continue
            except ConfigError as exc:
                message = exc.message
            parts = parse_path(p)
            last = parts[-1]
            if len(parts) > 1 and isinstance(last, str) and not last.startswith("["):
                try:
                    parent = get_path(raw, parts[:-1])
                except ConfigError:
                    parent = None
                if isinstance(parent, dict) and not did_you_mean(last, [k for k in parent if isinstance(k, str)]):
                    continue  # a parameter left at its default: set_path creates it at each point
            problems.append((f"factors.{name}.paths[{i}]", f"'{p}' is not in the base scenario: {message}", None))
    if problems:
        raise _refusal(where, problems)

