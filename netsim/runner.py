"""Run a scenario: load and validate, build, simulate, collect the tables, compute metrics, write the run folder.

``run(source)`` is what ``netsim run FILE`` and ``netsim.run(...)`` call. The run folder goes to ``out`` (the
user's choice, anywhere), else ``reports/<output.dir>`` (a scenario's ``output.dir`` is relative to the output
root ``reports/`` and cannot leave it, issue 14), else ``reports/<scenario>/<run-id>/`` (run-id = UTC time stamp
+ the first 8 hex digits of the scenario hash) under the current directory.

Failures are recorded, never lost:

* a :class:`~netsim.errors.DivergenceError` (unstable loop) ends the simulation at that instant; the tables
  up to that time are written and ``meta.json`` says ``status: "diverged at t = ... s"``; ``run`` returns
  the result normally (``result.ok`` is False), as for a loop that left its operating region (``unstable``);
* any other exception during the simulation or the metrics writes what exists with ``status: "error"``
  and the error text, but no ``metrics.csv`` (a run that failed has no metrics), then re-raises;
* Ctrl-C (``KeyboardInterrupt``; the CLI turns SIGTERM into one) during the simulation writes the tables up to
  that instant with ``status: "interrupted at t = ... s"`` and no ``metrics.csv``, then re-raises. A process
  killed outright (SIGKILL) cannot write anything: ``meta.json`` is removed before the run and written last,
  so a folder without it is incomplete and ``netsim report`` refuses it.

A :class:`~netsim.errors.NetsimError` carries a user message; any other exception is a bug.

A scenario with ``baseline: {overrides: {...}}`` first runs the baseline (the same scenario with those
overrides, same seed, nothing written) and passes its result to every metric as ``baseline``.

Baseline results are kept in a small in-process cache (least recently used first out), so that the points of
a sweep, which share their baseline, run it once per worker process. The key is the hash of the resolved
baseline scenario without ``output`` and ``seed``, after each program's ``canonical_params`` (if it has one)
has reset the parameters its other settings make inert (e.g. the thresholds of a sensor in time-triggered
mode). An entry is reused for any seed when the baseline run did not use its seed (no random stream drawn
from, see :meth:`~netsim.build.builder.Simulation.used_seed`), else only for the same seed. Results are
identical with and without the cache; :func:`clear_baseline_cache` empties it.

Why this module is long: the run's stages (load, baseline, simulate, metrics, verdict, write) share one failure
policy (what is written, with which status, for each way a run can end); kept together it reads in one place.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import platform
import time
from collections import OrderedDict
from functools import lru_cache
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Mapping

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

from netsim.errors import DivergenceError  # noqa: E402
from netsim.results import Lazy, RunResult, check_out_dir  # noqa: E402
from netsim.results.collect import collect  # noqa: E402
from netsim.results.traces import attach_traces, trace_problems  # noqa: E402
from netsim.timebase import S  # noqa: E402

if TYPE_CHECKING:
    from netsim.build.simulation import Simulation
    from netsim.scenario.problems import Problem
    from netsim.scenario.schema import Scenario

__all__ = [
    "run",
    "run_point",
    "simulate",
    "default_out_dir",
    "check_out_dir",
    "package_versions",
    "clear_baseline_cache",
]

log = logging.getLogger(__name__)

#: Every installed package that can change a number in a run folder (an absent optional one is left out):
#: the QP solvers (MPC, the cart's JMAP), slycot (python-control's Riccati solvers), the YAML parser, and
#: matplotlib for the figures.
_VERSION_PACKAGES = ("netsim", "simpy", "numpy", "scipy", "control", "slycot", "pandas", "pydantic", "pyyaml",
                     "daqp", "clarabel", "osqp", "piqp", "matplotlib")


def package_versions() -> dict[str, str]:
    """Versions of Python and the packages a run depends on (without importing them)."""
    return dict(_package_versions())


@lru_cache(maxsize=1)
def _package_versions() -> dict[str, str]:
    # reading package metadata costs ~15 ms; the versions cannot change within a process
    out = {"python": platform.python_version()}
    for pkg in _VERSION_PACKAGES:
        try:
            out[pkg] = _version(pkg)
        except metadata.PackageNotFoundError:
            if pkg == "netsim":
                import netsim

                out[pkg] = netsim.__version__
    return out


def _version(package: str) -> str:
    """``importlib.metadata.version(package)``, read from the ``Version:`` line of the metadata's header.

    The header is parsed as e-mail by ``metadata.version``, which costs more than the rest of the look-up (issue
    29, start-up); a header without a plain ``Version:`` line still goes through it.
    """
    dist = metadata.distribution(package)
    text = dist.read_text("METADATA") or dist.read_text("PKG-INFO") or ""
    for line in text.splitlines():
        if not line.strip():  # the end of the header
            break
        key, sep, value = line.partition(":")
        if sep and key.strip().lower() == "version" and value.strip():
            return value.strip()
    return dist.version


def default_out_dir(name: str, scenario_hash: str, root: str | Path = "reports") -> Path:
    """``reports/<name>/<UTC stamp>-<hash8>``, created exclusively: a numeric suffix keeps two runs that start
    in the same second apart, also when they run at the same time (:func:`netsim.safe_write.make_unique_dir`)."""
    from netsim.safe_write import make_unique_dir

    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    return make_unique_dir(Path(root) / name / f"{stamp}-{scenario_hash[:8]}")


#: The output root: default run folders and a scenario's ``output.dir`` live below it.
OUTPUT_ROOT = "reports"


def scenario_out_dir(output_dir: str, root: str | Path = OUTPUT_ROOT) -> Path:
    """``root/output_dir`` for a scenario's ``output.dir``, refused when it would leave ``root``.

    The schema already refuses absolute paths and ``..``; this also catches a symlink inside ``root`` that
    points elsewhere.

    Raises
    ------
    ConfigError
        When the folder resolves outside ``root``.
    """
    from netsim.errors import ConfigError

    base = Path(root)
    folder = base / output_dir
    if not folder.resolve().is_relative_to(base.resolve()):
        raise ConfigError(f"output.dir '{output_dir[:80]}' resolves outside {root}/ (through a symlink?); a "
                          "scenario writes only below reports/: choose another output.dir, or the folder with --out")
    return folder


def _mark_folder(exc: BaseException, folder: Path) -> None:
    """Attach the (partial) run folder to an exception as ``exc.run_folder`` for the caller to report."""
    try:
        exc.run_folder = folder  # type: ignore[attr-defined]
    except (AttributeError, TypeError):  # an exception type that refuses attributes
        pass


def _event_count(env: Any) -> int | None:
    """Entries the event loop scheduled during the run (:meth:`netsim.env.EventLoop.events_scheduled`)."""
    counted = getattr(env.sim, "events_scheduled", None)
    return int(counted()) if counted is not None else None


def simulate(scenario: Scenario, progress: Callable[[int, int], None] | None = None, sim: Simulation | None = None
             ) -> tuple[RunResult, Any, BaseException | None]:
    """Build and run ``scenario`` (validated); returns (result without metrics, simulation, exception or None).

    ``progress(t_ns, t_end_ns)``, when given, is called about every 1 % of simulated time
    (:meth:`~netsim.build.builder.Simulation.run`). ``sim``: the scenario's build, when it is built already
    (never run). The result's ``meta`` has ``status``, ``error``, ``t_end_s``, ``wall_time_s`` and ``events``.
    """
    t0 = time.perf_counter()
    if sim is None:
        from netsim.build.builder import build

        sim = build(scenario)
    attach_traces(sim, scenario.output)  # jobs / messages: full | summary | off, schedule: on | off (issue 19)
    failure: BaseException | None = None
    status, error = "ok", ""
    try:
        t_end = sim.run(progress=progress)
    except DivergenceError as exc:
        t_end = int(getattr(exc, "time_ns", sim.env.now))
        status = f"diverged at t = {t_end / S:.9g} s"
        error = str(exc)
        failure = exc
    except KeyboardInterrupt as exc:  # Ctrl-C (or SIGTERM, which the CLI turns into one): keep what was simulated
        t_end = sim.env.now
        status, error = f"interrupted at t = {t_end / S:.9g} s", "interrupted by the user (Ctrl-C or SIGTERM)"
        failure = exc
    except MemoryError:  # the records are dropped so the folder can be written; one line with the fix (issue 31)
        from netsim.scenario.memory import out_of_memory, release

        release(sim)
        t_end = sim.env.now
        failure = out_of_memory(t_end)
        status, error = "error", str(failure)
    except Exception as exc:  # noqa: BLE001 - recorded, then re-raised by run()
        t_end = sim.env.now
        status, error = "error", f"{type(exc).__name__}: {exc}"
        failure = exc
    wall = time.perf_counter() - t0
    result = collect(sim, t_end)
    if failure is None:
        from netsim.results.divergence import find_divergence_chunked

        hit = find_divergence_chunked(result, sim.env.recorder, scenario.metrics)
        if hit is not None:  # unstable on its own scale though the plant's absolute bound was not reached
            status = f"diverged at t = {hit[0]:.9g} s"
            error = hit[1]
    from netsim.programs.design_summary import run_warnings as design_warnings  # D's hook (issue 26 s4)

    # the unstable-nominal-loop warnings go to meta.json only: they were logged already, by the run's build check
    # (_built) or by loading (validate's dry run, netsim.build.dry_run), and the console showed each twice
    said = design_warnings(sim)
    warnings = _unrecorded(scenario, sim.env.recorder)
    # a program's own warnings about its setting (e.g. netsim.models.unicycle's filter and plant disagreeing)
    warnings += [w for prog in getattr(sim, "programs", {}).values() for w in getattr(prog, "build_warnings", ())]
    from netsim.results.verdict import apply_finding, judge_signals  # is the loop stable?
    finding, notes = judge_signals(result, scenario, t_end) if failure is None and status == "ok" else (None, [])
    warnings += notes  # the loop's growth and verdict.bound
    for text in warnings:
        log.warning("%s: %s", scenario.name, text)
    warnings = said + warnings
    result.meta.update(
        {
            "status": status,
            "error": error,
            "t_end_s": t_end / S,
            "duration_s": scenario.duration / S,
            "wall_time_s": wall,
            "events": _event_count(sim.env),
            "warnings": warnings,
        }
    )
    apply_finding(result.meta, finding, scenario)
    return result, sim, failure


def _unrecorded(scenario: Scenario, recorder: Any) -> list[str]:
    """Warnings for ``record:`` names that nothing recorded during the run (a typo, most often)."""
    if not scenario.record:
        return []
    seen = {name.split("[", 1)[0] for name in recorder.names()} | set(recorder.names())
    missing = [name for name in scenario.record if name not in seen]
    if not missing:
        return []
    known = ", ".join(sorted({n.split("[", 1)[0] for n in recorder.names()})) or "none"
    return [f"record: nothing recorded '{name}' (recorded signals: {known})" for name in missing]


class _WarningCapture(logging.Handler):
    """Collects the texts of the warnings netsim and the models log while a run's metrics are computed."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.texts: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.texts.append(record.getMessage())


def _metrics(result: RunResult, sim: Any, scenario: Scenario, baseline: RunResult | None) -> dict[str, float]:
    """The run's metrics; warnings a metric logs (e.g. et_control's 'h is shorter than a packet gap') are also
    kept in ``result.meta["warnings"]``."""
    from netsim.metrics.runtime import compute_metrics, generic_metrics

    t_end_ns = int(round(result.meta["t_end_s"] * S))
    capture = _WarningCapture()
    loggers = [logging.getLogger("netsim")]  # netsim.models logs under it too
    levels = [lg.level for lg in loggers]
    for lg in loggers:  # meta.json keeps the warnings even when the console shows only errors (netsim -q)
        lg.addHandler(capture)
        if lg.getEffectiveLevel() > logging.WARNING:
            lg.setLevel(logging.WARNING)
    view = _metrics_view(result)  # a table a metric reads is built on the view: the run folder's CSVs are still
    try:                           # written straight from the records (RunResult._table_rows)
        values = generic_metrics(view, sim, t_end_ns)
        values.update(compute_metrics(view, list(scenario.metrics), baseline))
    finally:
        for lg, level in zip(loggers, levels):
            lg.removeHandler(capture)
            lg.setLevel(level)
    if capture.texts:
        result.meta["warnings"] = list(result.meta.get("warnings") or []) + capture.texts
    from netsim.results.verdict import apply_finding, judge_metrics
    apply_finding(result.meta, judge_metrics(view, scenario) if result.ok else None, scenario)  # the pendulum fell
    return values


def run(
    source: Any,
    *,
    out: str | Path | None = None,
    seed: int | None = None,
    overrides: Mapping[str, Any] | None = None,
    plot: bool = False,
    write: bool = True,
    progress: Callable[[int, int], None] | None = None,
    allow_plugins: bool | None = None,
    tables: bool = True,
) -> RunResult:
    """Run one scenario and (by default) write its run folder.

    Parameters
    ----------
    source
        Scenario file path, raw mapping, or validated :class:`~netsim.scenario.schema.Scenario` (the CLI loads
        the file with ``--seed`` and ``--set`` applied and ``for_run=True`` and passes the Scenario: one
        validation and one build per run; a Scenario loaded without ``for_run`` had its dry run while loading,
        and is built once more here). A file or mapping is loaded for the run: built once. In a
        mapping, ``plant`` may be a python-control ``StateSpace`` or ``TransferFunction`` (or
        ``{system: <it>, x0: ...}``): its matrices are copied once into the ``plant: {type: ss|tf}`` form
        (:func:`netsim.plant.described.plant_spec_from_system`); a ``NonlinearIOSystem`` runs its ``updfcn``
        and ``outfcn`` in a :class:`~netsim.plant.nonlinear.NonlinearPlant` (plant model ``nonlinear_io``).
    out
        Run folder, anywhere (default: ``reports/<output.dir>`` when the scenario gives ``output.dir``, else
        ``reports/<name>/<run-id>``).
    seed
        Overrides the scenario seed (applied to the raw data with ``overrides``).
    overrides
        ``{"dotted.path": value}`` applied to the raw data before the one validation; given with a loaded
        ``Scenario``, its raw data is validated again with them.
    plot
        Also write PNG figures (as does ``output.plot: true`` in the scenario).
    write
        False: write nothing (the result is still complete in memory).
    progress
        Optional ``progress(t_ns, t_end_ns)`` called about every 1 % of the run's simulated time (not during a
        baseline run); results are identical with and without it.
    allow_plugins
        Whether the Python files the scenario's ``plugins:`` list names may run (None: the user's settings,
        :mod:`netsim.trust`); a scenario naming files that are not allowed is refused (``ScenarioError``).
    tables
        False: the run folder holds ``metrics.csv`` and ``meta.json`` only (no scenario.yaml, signals, jobs,
        messages, summaries or figures; a sweep's ``runs: metrics``). The result in memory is complete.

    Returns
    -------
    RunResult
        ``meta["status"]`` is ``"ok"``, ``"diverged at t = ... s"`` or ``"unstable at t = ... s"``.

    Raises
    ------
    ScenarioError
        The scenario does not validate or does not build (every problem listed, as loading lists them); nothing
        is written.
    ConfigError
        The run folder cannot be written (``out`` is a file ...); checked before anything runs.
    NetsimError
        Another user-caused failure (after the partial run folder was written; its path is the exception's
        ``run_folder`` attribute). An ``OSError`` while writing the folder also carries ``run_folder``.
    """
    from netsim.scenario.loader import load_scenario, scenario_hash

    wall0 = time.perf_counter()
    if isinstance(source, (str, Path)):
        from netsim.sweep.check import is_sweep_file

        if is_sweep_file(source):
            from netsim.errors import ConfigError

            raise ConfigError(f"{source}: this is a sweep file; run it with netsim.sweep.run_sweep "
                              f"(`netsim sweep {source}`)")
    ov = dict(overrides or {})
    if seed is not None:
        ov["seed"] = int(seed)
    if isinstance(source, Mapping):  # a python-control system as the plant: its plant: mapping (issue 16)
        from netsim.plant.described import resolve_plant_object

        source = resolve_plant_object(dict(source))
    scenario = load_scenario(source, overrides=ov or None, allow_plugins=allow_plugins, for_run=True)
    base_sc = scenario.baseline_scenario()
    base_key = _baseline_key(base_sc) if base_sc is not None else ""
    cached = _baseline_hit(base_sc, base_key) if base_sc is not None else None
    sim, base_built = _built(scenario, base_sc if cached is None else None, base_key)  # before the run folder
    needs = trace_problems(scenario)
    if needs:
        from netsim.errors import ConfigError

        raise ConfigError(f"{scenario.name}: " + "; ".join(needs))
    digest = scenario_hash(scenario)
    folder: Path | None = None
    if write:
        folder = check_out_dir(out if out is not None else (
            scenario_out_dir(scenario.output.dir) if scenario.output.dir else default_out_dir(scenario.name, digest)))
        folder.mkdir(parents=True, exist_ok=True)  # before the run: incomplete (no meta.json) until written
        (folder / "meta.json").unlink(missing_ok=True)  # a folder run again reads incomplete until it is rewritten

    baseline = cached
    if base_sc is not None and baseline is None:
        baseline = _baseline_run(base_sc, base_key, *base_built)

    result, sim, failure = simulate(scenario, progress, sim)
    result.scenario = scenario.resolved_dict()
    try:
        if failure is not None and not isinstance(failure, DivergenceError):
            # a run that failed has tables up to the failure, but no metrics: numbers computed over a run cut
            # short by an error would read like results (RunResult.to_csv then writes no metrics.csv)
            result._set_metrics({})
        else:
            result._set_metrics(_metrics(result, sim, scenario, baseline))
    except Exception as exc:  # noqa: BLE001
        if failure is None:
            failure = exc
            result.meta["status"] = "error"
            result.meta["error"] = f"{type(exc).__name__}: {exc}"
        result._set_metrics({})
    if failure is None:
        from netsim.run_warnings import load_warnings

        mode = result.traces.get("jobs", "full")  # 'never ran' is known from the rows or the summary, not when off
        rows = result._table_rows("jobs")  # the records' columns: no DataFrame built for the warnings
        ran = (result.jobs if rows is None else rows) if mode == "full" else result.job_summary
        extra = load_warnings(result.metric_values(), ran, scenario.nodes if mode != "off" else {},
                              scenario.networks or {})
        for text in extra:
            log.warning("%s: %s", scenario.name, text)
        result.meta["warnings"] = list(result.meta.get("warnings") or []) + extra
    result.meta.update(
        {
            "scenario": scenario.name,
            "source": scenario.source,
            "seed": scenario.seed,
            "scenario_hash": digest,
            "versions": package_versions(),
            "baseline": None if baseline is None else {"status": baseline.status},
        }
    )
    result.meta["wall_time_s"] = time.perf_counter() - wall0
    if folder is not None:
        try:
            from netsim.programs.design_summary import write_design  # D's hook: design.json, before meta.json

            write_design(folder, sim, tables)
            result.to_csv(folder, tables=tables)
        except OSError as exc:
            _mark_folder(exc, folder)
            raise
        if tables and (plot or scenario.output.plot):
            try:
                result.plot(folder)
            except Exception:  # noqa: BLE001 - figures are a convenience; the tables are written
                log.exception("plotting failed for %s", folder)
    if failure is not None and not isinstance(failure, DivergenceError):
        if folder is not None:
            _mark_folder(failure, folder)
            if isinstance(failure, KeyboardInterrupt):
                log.warning("%s: %s; the run folder %s holds the run up to then", scenario.name, result.status,
                            folder)
        raise failure
    if not result.ok:
        log.warning("%s: %s", scenario.name, result.status)
    return result


#: Baseline results kept per process: key -> {seed or None (any seed): RunResult}.
_BASELINES: "OrderedDict[str, dict[int | None, RunResult]]" = OrderedDict()
_BASELINE_CACHE_SIZE = 8
#: The warnings of each cached baseline's build (an unstable nominal loop), logged again by a run that reuses it.
_BASELINE_WARNINGS: dict[str, list[Problem]] = {}


def clear_baseline_cache() -> None:
    """Forget the baseline results kept in this process."""
    _BASELINES.clear()
    _BASELINE_WARNINGS.clear()


def _built(scenario: Scenario, base_sc: Scenario | None, base_key: str
           ) -> tuple[Simulation, tuple[Simulation | None, list[Problem] | None]]:
    """The run's one build of ``scenario`` and of its baseline ``base_sc`` (None: not built here, it is cached or
    there is none): ``(simulation, (baseline simulation, baseline's build warnings))`` (None, None for the baseline
    when it is not built or not checked here).

    A scenario loaded for the run (``load_scenario(..., for_run=True)``, which leaves out the dry run) is checked
    here as the dry run checks it (:func:`_checked`: the kernels' references, an unstable nominal loop), and its
    build's problems are reported as loading reports them (:class:`~netsim.build.dry_run.RunCheck`): an error
    raises the same :class:`~netsim.scenario.problems.ScenarioError` (file, line, YAML path), before anything is
    written; the warnings are logged in loading's order. A scenario loaded otherwise was
    checked by its dry run already: it is only built.

    Raises
    ------
    ScenarioError
        The scenario or its baseline does not build.
    """
    check = scenario._run_check
    if check is None:
        from netsim.build.builder import build

        return build(scenario), (None, None)
    sim, found = _checked(scenario)
    refused = check.refused(found)
    if refused is not None:
        raise refused
    assert sim is not None  # a build that failed is refused above, or its own error was raised
    base_sim: Simulation | None = None
    base_found = list(_BASELINE_WARNINGS.get(base_key, [])) if base_key else []
    if base_sc is not None:
        base_sim, base_found = _checked(base_sc)
        refused = check.refused_baseline(found, base_found)
        if refused is not None:
            raise refused
    check.log_warnings(found, base_found)
    scenario._run_check = None  # checked: running this Scenario again only builds it
    return sim, (base_sim, base_found)


def _checked(scenario: Scenario) -> tuple[Simulation | None, list[Problem]]:
    """Build ``scenario`` and check the build as loading's dry run checks it: ``(simulation, problems)``.

    When the build or its check fails, the dry run (:func:`netsim.build.dry_run.build_problems`) is made after all,
    and its error is the problem returned: what loading refuses is refused with the same path and message. A
    failure the dry run does not see (in a user's plugin, which it leaves out) stays the run's own, as before: the
    build's error is raised, and a kernel's reference error is left for the run to meet when it starts.
    """
    from netsim.build.builder import build
    from netsim.build.dry_run import build_problems, built_problems
    from netsim.errors import ConfigError

    try:
        sim = build(scenario)
    except ConfigError:
        dry = build_problems(scenario)
        if any(p.is_error for p in dry):
            return None, dry
        raise
    found = built_problems(sim)
    if any(p.is_error for p in found):  # the dry run's verdict: its error, or its warnings (the run meets the error)
        return sim, build_problems(scenario)
    return sim, found


def _baseline_key(scenario: Scenario) -> str:
    """Hash of the resolved scenario without ``output``/``seed``, inert program parameters reset."""
    from netsim.registry import lookup

    data = scenario.resolved_dict()
    data.pop("output", None)
    data.pop("seed", None)
    for node in (data.get("nodes") or {}).values():
        for kind in ("tasks", "handlers"):
            for entry in node.get(kind) or []:
                try:
                    canon = getattr(lookup("program", entry["program"]), "canonical_params", None)
                except Exception:  # noqa: BLE001 - no canonical form: the parameters stay as they are
                    canon = None
                if canon is not None and isinstance(entry.get("params"), dict):
                    entry["params"] = canon(dict(entry["params"]))
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _metrics_view(result: RunResult) -> RunResult:
    """``result`` for the metrics: the same signals, metadata and records, with its unbuilt tables as their own
    :class:`~netsim.results.Lazy` builders, so a table a metric reads is built on the view, not on ``result``."""
    return RunResult(signals=_lazy_view(result, "signals"), jobs=_lazy_view(result, "jobs"),
                     messages=_lazy_view(result, "messages"), metrics=_same(result, "metrics"), meta=result.meta,
                     scenario=result.scenario, schedule=_lazy_view(result, "schedule"), out_dir=result.out_dir,
                     traces=result.traces, job_summary=result.job_summary, message_summary=result.message_summary,
                     _job_rows=result._job_rows, _message_rows=result._message_rows, _signal_source=result._signal_source,
                     _streams=result._streams, _metric_values=result._metric_values)


def _shared(result: RunResult) -> RunResult:
    """A view of a cached result that a metric may modify without touching the cache (copy-on-write)."""
    return RunResult(signals=_lazy_view(result, "signals"), jobs=_lazy_view(result, "jobs"),
                     messages=_lazy_view(result, "messages"), metrics=_lazy_view(result, "metrics"),
                     meta=dict(result.meta), scenario=result.scenario,
                     schedule=_lazy_view(result, "schedule"), traces=dict(result.traces),
                     job_summary=result.job_summary, message_summary=result.message_summary,
                     _job_rows=result._job_rows, _message_rows=result._message_rows, _signal_source=result._signal_source,
                     _metric_values=result._metric_values)


def _lazy_view(result: RunResult, name: str) -> Any:
    """A table of ``result`` for a view: its :class:`~netsim.results.Lazy` builder while unbuilt (nothing built
    for a baseline that no metric reads that table of; each view that reads it builds its own), else a shallow
    copy."""
    value = object.__getattribute__(result, name)
    return value if isinstance(value, Lazy) else value.copy(deep=False)


def _same(result: RunResult, name: str) -> Any:
    """A field of ``result`` as it is: the object itself, or its :class:`~netsim.results.Lazy` builder while unbuilt
    (reading it from the view builds a table equal to the one ``result`` would build)."""
    return object.__getattribute__(result, name)


def _baseline(base_sc: Any) -> RunResult:
    """The baseline run of a scenario (with its generic metrics), from the cache when possible."""
    key = _baseline_key(base_sc)
    hit = _baseline_hit(base_sc, key)
    return hit if hit is not None else _baseline_run(base_sc, key)


def _baseline_hit(base_sc: Any, key: str) -> RunResult | None:
    """The cached baseline run of ``base_sc`` (whose :func:`_baseline_key` is ``key``), or None."""
    entries = _BASELINES.get(key)
    if entries is not None:
        hit = entries.get(None) or entries.get(int(base_sc.seed))
        if hit is not None:
            _BASELINES.move_to_end(key)
            return _shared(hit)
    return None


def _baseline_run(base_sc: Any, key: str, sim: Simulation | None = None, warnings: list[Problem] | None = None
                  ) -> RunResult:
    """Run the baseline ``base_sc`` (on ``sim``, its build, when given) and cache it under ``key``, with its build's
    ``warnings``."""
    baseline, base_sim, base_fail = simulate(base_sc, sim=sim)
    if base_fail is not None and not isinstance(base_fail, DivergenceError):
        raise base_fail
    from netsim.metrics.runtime import generic_metrics

    t_base = int(round(baseline.meta["t_end_s"] * S))
    baseline._set_metrics(generic_metrics(baseline, base_sim, t_base))
    _ = baseline.signals  # built once for the cache (metrics read the baseline's signals at every point)
    slot = None if not base_sim.used_seed() else int(base_sc.seed)
    _BASELINES.setdefault(key, {})[slot] = baseline
    _BASELINES.move_to_end(key)
    if warnings is not None:
        _BASELINE_WARNINGS[key] = list(warnings)
    while len(_BASELINES) > _BASELINE_CACHE_SIZE:
        old, _ = _BASELINES.popitem(last=False)
        _BASELINE_WARNINGS.pop(old, None)
    return _shared(baseline)


def run_point(raw: Mapping[str, Any], out: str | Path, seed: int, tables: bool = True) -> dict[str, float]:
    """One sweep point in a worker process: run ``raw`` with ``seed``, write the run folder to ``out`` (with
    ``tables`` False only ``metrics.csv`` and ``meta.json``: a sweep's ``runs: metrics``).

    Returns the metrics (an errored run raises; a diverged run returns its metrics, its ``meta.json`` says so).
    """
    result = run(dict(raw), out=out, seed=seed, write=True, tables=tables)
    return result.metric_values()
