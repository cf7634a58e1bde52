"""What each ``netsim`` sub-command does: validate, run, batch, sweep, report, list.

Each ``_cmd_<name>(args) -> exit code`` imports the heavy modules it needs inside, so ``netsim --help`` stays fast.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path
from typing import Any, Callable, Sequence, TextIO

from netsim.status import EXIT_INVALID, EXIT_OK, EXIT_PROBLEMS

__all__ = ["LIST_KINDS"]

log = logging.getLogger("netsim.cli")

LIST_KINDS: dict[str, str] = {
    "plants": "plant",
    "controllers": "controller",
    "estimators": "estimator",
    "networks": "network",
    "policies": "policy",
    "servers": "server",
    "programs": "program",
    "signals": "signal",
    "metrics": "metric",
    "path_losses": "path_loss",
    "reports": "report",
}



def _err(message: str) -> None:
    print(f"netsim: error: {message}", file=sys.stderr)


def _print_problems(problems: Sequence[Any], stream: TextIO) -> None:
    for p in problems:
        print(str(p), file=stream)


def _overrides(items: Sequence[str]) -> dict[str, Any]:
    from netsim.scenario import parse_override

    out: dict[str, Any] = {}
    for item in items:
        key, value = parse_override(item)
        out[key] = value
    return out


# --------------------------------------------------------------------------------------------- commands
def _scenario_file(argument: str) -> str:
    """A FILE argument: the file as given, or the shipped scenario a bare name stands for (``dc_servo_can``)."""
    from netsim.shipped import resolve

    return resolve(argument)


def _is_sweep(file: str) -> bool:
    from netsim.sweep.check import is_sweep_file

    return is_sweep_file(file)


def _cmd_validate(args: argparse.Namespace) -> int:
    from netsim.scenario import check_scenario

    overrides = _overrides(args.overrides)
    n_errors = 0
    from netsim.errors import ConfigError

    for given in args.files:
        try:
            file = _scenario_file(given)
        except ConfigError as exc:  # a bare name that is neither a file nor a shipped scenario: one problem
            print(str(exc))
            n_errors += 1
            continue
        if _is_sweep(file):
            from netsim.sweep.check import check_sweep

            problems = check_sweep(file)
        else:
            problems = check_scenario(file, overrides or None)
        errors = [p for p in problems if p.is_error]
        n_errors += len(errors)
        _print_problems(problems, sys.stdout)
        if not errors:
            warn = len(problems)
            note = f" ({warn} warning{'s' if warn != 1 else ''})" if warn else ""
            print(f"{given}: valid{note}")
    if n_errors:  # the count is printed, not returned: 2 is a usage error and 130 is Ctrl-C (issue 27)
        total = " in total" if len(args.files) > 1 else ""
        print(f"{n_errors} problem{'s' if n_errors != 1 else ''}{total}", file=sys.stderr)
        return EXIT_PROBLEMS
    return EXIT_OK


def _cmd_run(args: argparse.Namespace) -> int:
    from netsim.scenario import ScenarioError, load_scenario

    args.file = _scenario_file(args.file)
    if _is_sweep(args.file):
        from netsim.errors import ConfigError

        raise ConfigError(f"{args.file}: this is a sweep file; use `netsim sweep {args.file}`")
    overrides = _overrides(args.overrides)
    if args.out is not None:
        from netsim.results import check_out_dir

        check_out_dir(args.out)  # a bad --out is refused before anything runs
    if args.seed is not None:
        overrides["seed"] = args.seed  # applied to the raw tree with the --set values: one validation
    try:  # the build is checked by run's one build (issue 28): its problems come from run(), as loading's do here
        scenario = load_scenario(args.file, overrides or None, for_run=True)
        from netsim.runner import run

        show = not (args.no_progress or args.quiet) and sys.stderr.isatty()
        window = _plot_window(getattr(args, "plot_window", None))
        with _RunProgress(scenario.name, enabled=show) as progress:
            if window is None:
                result = run(scenario, out=args.out, plot=args.plot, progress=progress.callback)
            else:  # --plot-window implies --plot: the figures are drawn here with that window
                result = run(scenario, out=args.out, plot=False, progress=progress.callback)
    except ScenarioError as exc:
        if getattr(exc, "run_folder", None) is not None:  # raised by the simulation, after the folder was written
            raise
        _print_problems(exc.problems, sys.stderr)
        n = len(exc.errors)
        _err(f"{args.file}: {n} problem{'s' if n != 1 else ''}; nothing was run")
        return EXIT_INVALID
    meta = getattr(result, "meta", {}) or {}
    status = str(meta.get("status", "ok"))
    out_dir = getattr(result, "out_dir", None) or meta.get("out_dir")
    if window is not None and out_dir:
        from netsim.plotting import save_figures

        save_figures(result, out_dir, window=window)
    n_warn = len(meta.get("warnings") or [])
    told = f"{status} ({n_warn} warning{'s' if n_warn != 1 else ''} above)" if n_warn else status
    if not args.quiet or status != "ok":  # quiet: nothing on stdout unless the run failed
        print(f"{scenario.name}: {told}{_run_facts(meta)}")
    if not args.quiet:
        values = getattr(result, "metric_values", None)  # a plain dict: no pandas Series built to print them
        _print_metrics(values() if callable(values) else getattr(result, "metrics", None))
        if out_dir:
            print(f"run folder: {out_dir}")
    from netsim.status import count_statuses

    if status != "ok":
        error = meta.get("error")
        if error:
            _err(str(error))
    return count_statuses([status]).exit_code()


def _cmd_analyze(args: argparse.Namespace) -> int:
    from netsim.scenario import ScenarioError, load_scenario

    args.file = _scenario_file(args.file)
    if _is_sweep(args.file):
        from netsim.errors import ConfigError

        raise ConfigError(f"{args.file}: this is a sweep file; analyze its base scenario instead")
    overrides = _overrides(args.overrides)
    if args.out is not None:
        from netsim.results import check_out_dir

        check_out_dir(args.out)
    if args.seed is not None:
        overrides["seed"] = args.seed
    try:  # one build, in run() (issue 28), as `netsim run` does
        scenario = load_scenario(args.file, overrides or None, for_run=True)
        from netsim.runner import run

        result = run(scenario, out=args.out)
    except ScenarioError as exc:
        if getattr(exc, "run_folder", None) is not None:  # raised by the simulation, after the folder was written
            raise
        _print_problems(exc.problems, sys.stderr)
        n = len(exc.errors)
        _err(f"{args.file}: {n} problem{'s' if n != 1 else ''}; nothing was run")
        return EXIT_INVALID
    from netsim.cli.analyze import analyze_run
    from netsim.safe_write import write_atomic

    meta = getattr(result, "meta", {}) or {}
    status = str(meta.get("status", "ok"))
    table = analyze_run(scenario, result)
    print(f"{scenario.name}: run {status}; analysis beside simulation "
          "(task and message times in ms, loop costs as ISE):")
    cells = [[str(v) if isinstance(v, str) else f"{v:.4g}" for v in row] for row in table.itertuples(index=False)]
    widths = [max([len(c)] + [len(r[i]) for r in cells]) for i, c in enumerate(table.columns)]
    for row in [list(table.columns), *cells]:
        print("  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip())
    out_dir = getattr(result, "out_dir", None) or meta.get("out_dir")
    if out_dir:
        from pathlib import Path

        write_atomic(Path(out_dir) / "analysis.csv", table.to_csv(index=False))
        print(f"run folder: {out_dir} (analysis.csv)")
    bad = int((table["verdict"] == "EXCEEDS").sum())
    if bad:
        _err(f"{bad} simulated value{'s' if bad != 1 else ''} above the analytic bound: a bug in the simulator "
             "or in the analysis")
        return 1
    return 0


def _plot_window(text: str | None) -> tuple[float, float] | None:
    """``--plot-window``: ``T1`` or ``T0:T1`` with time units (``50 ms``, ``1 s:1.2 s``) -> seconds."""
    if text is None:
        return None
    from netsim.errors import ConfigError
    from netsim.timebase import S, parse_time

    parts = [p.strip() for p in str(text).split(":")]
    try:
        if len(parts) == 1:
            t0, t1 = 0, parse_time(parts[0])
        elif len(parts) == 2:
            t0, t1 = parse_time(parts[0]), parse_time(parts[1])
        else:
            raise ValueError(text)
    except (ValueError, TypeError) as exc:
        raise ConfigError(f"--plot-window {text!r}: write a length or START:END with units, e.g. "
                          "--plot-window '50 ms' or --plot-window '1 s:1.2 s'") from exc
    if t1 <= t0:
        raise ConfigError(f"--plot-window {text!r}: the end must come after the start")
    return t0 / S, t1 / S


def _run_facts(meta: dict[str, Any]) -> str:
    """`` (2 s simulated in 1.3 s)`` from a run's meta, or nothing."""
    simulated, wall = meta.get("t_end_s"), meta.get("wall_time_s")
    if simulated is None:
        return ""
    return f" ({float(simulated):.6g} s simulated" + (f" in {float(wall):.3g} s)" if wall is not None else ")")


class _RunProgress:
    """A rich progress bar on stderr for one run: simulated time, wall time and ETA (or nothing).

    ``callback`` is the ``progress(t_ns, t_end_ns)`` function for :func:`netsim.runner.run` (None when
    disabled, so the run takes its unsliced path).
    """

    def __init__(self, label: str, *, enabled: bool) -> None:
        self.bar: Any = None
        self.callback: Callable[[int, int], None] | None = None
        if not enabled:
            return
        from rich.console import Console
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

        self.bar = Progress(
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            TextColumn("{task.fields[sim]} simulated"),
            TextColumn("wall"),
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            console=Console(stderr=True),
            transient=True,
        )
        self.task = self.bar.add_task(label, total=None, sim="building")
        self.callback = self._update

    def _update(self, t_ns: int, t_end_ns: int) -> None:
        from netsim.timebase import format_time

        self.bar.update(self.task, completed=t_ns, total=max(t_end_ns, 1),
                        sim=f"{format_time(t_ns)} / {format_time(t_end_ns)}")

    def __enter__(self) -> "_RunProgress":
        if self.bar is not None:
            self.bar.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        if self.bar is not None:
            self.bar.stop()


def _print_metrics(metrics: Any) -> None:
    """The control metrics first, then worst response and deadline misses per task, loss and worst delay per
    network (:func:`netsim.results.summary.key_metrics`); the rest stays in ``metrics.csv``."""
    if metrics is None:
        return
    try:
        items = dict(metrics.items())
    except AttributeError:
        return
    if not items:
        return
    from netsim.results.summary import key_metrics

    control, timing = key_metrics(items)
    rows = control + timing
    width = max((len(k) for k, _ in rows), default=0)
    for key, text in rows:
        print(f"  {key:<{width}}  {text}")
    if len(items) > len(control):
        print(f"  ({len(items)} metrics in all: metrics.csv)")


def _expand_batch(paths: Sequence[str]) -> list[Path]:
    """Files as given; folders become their *.yaml/*.yml scenarios (sweep files skipped), sorted."""
    from netsim.errors import ConfigError

    out: list[Path] = []
    for item in paths:
        p = Path(item)
        if p.is_dir():
            found = sorted([*p.glob("*.yaml"), *p.glob("*.yml")])
            found = [f for f in found if not _is_sweep(str(f))]
            if not found:
                raise ConfigError(f"no scenario files (*.yaml, *.yml) in folder {item}")
            out += found
        elif p.exists():
            out.append(p)
        else:  # a shipped scenario's name (a bare name that is none: a one-line error naming the closest)
            found_file = Path(_scenario_file(item))
            if not found_file.exists():
                raise ConfigError(f"file not found: {item}")
            out.append(found_file)
    return out


def _cmd_batch(args: argparse.Namespace) -> int:
    files = _expand_batch(args.paths)
    from netsim.sweep.batch import run_batch

    from netsim.status import count_statuses

    summary, _ = run_batch(files, out=args.out, workers=args.workers,
                           progress=not (args.no_progress or args.quiet))
    counts = count_statuses(summary["status"] if summary is not None and not summary.empty else [])
    print(counts.describe("scenario"))  # the same status rule as `netsim run` (netsim.status)
    out = getattr(summary, "attrs", {}).get("path") if summary is not None else None
    if out:
        print(f"summary: {out}")
    return counts.exit_code()


def _cmd_sweep(args: argparse.Namespace) -> int:
    from netsim.errors import ConfigError

    if args.scheduler and args.dask_local:
        raise ConfigError("give either --scheduler ADDR or --dask-local, not both")
    if args.dask_dashboard and not args.dask_local:
        raise ConfigError("--dask-dashboard needs --dask-local (a scheduler you start has its own: "
                          "`dask scheduler --dashboard-address ADDR`)")
    if args.scheduler or args.dask_local:  # before anything runs
        from netsim.sweep.executor import require_dask

        require_dask("--scheduler" if args.scheduler else "--dask-local")
    args.file = _scenario_file(args.file)
    if not Path(args.file).exists():
        raise ConfigError(f"file not found: {args.file}")
    from netsim.figure_style import plot_format
    from netsim.sweep import run_sweep

    with plot_format(getattr(args, "plot_format", None)):
        result = run_sweep(
            args.file,
            out=args.out,
            workers=args.workers,
            scheduler=args.scheduler,
            local_dask=args.dask_local,
            dashboard=args.dask_dashboard,
            overwrite=args.overwrite,
            progress=not (args.no_progress or args.quiet),
        )
    print(result.describe())
    from netsim.status import count_statuses

    counts = count_statuses(result.summary["status"] if result.summary is not None else [])
    if result.interrupted:
        _err("interrupted: finished runs are kept; run the same command again to resume")
    elif counts.not_ok:
        _err(f"{counts.describe('sweep run')} (see summary.csv)")
    return counts.exit_code(result.interrupted)


def _cmd_report(args: argparse.Namespace) -> int:
    from netsim.report import report

    if not args.quiet:  # case-study reports log their progress under netsim.progress.<name>
        logging.getLogger("netsim.progress").setLevel(logging.INFO)
    from netsim.figure_style import plot_format

    with plot_format(getattr(args, "plot_format", None)):
        tables = report(args.target, out=args.out, plots=not args.no_plots)
    for name, frame in (tables or {}).items():
        rows = getattr(frame, "shape", (0,))[0]
        print(f"{name}: {rows} row{'s' if rows != 1 else ''}")
    return EXIT_OK


def _kind_of(text: str) -> str | None:
    key = text.strip().lower()
    if key in LIST_KINDS:
        return LIST_KINDS[key]
    if key in LIST_KINDS.values():
        return key
    return None


def _cmd_list(args: argparse.Namespace) -> int:
    from netsim import registry
    from netsim.errors import ConfigError
    from netsim.scenario.paths import did_you_mean
    from netsim.scenario.validate import plugin_load_problems

    if args.kind is not None:
        kind = _kind_of(args.kind)
        if kind is None:
            raise ConfigError(f"unknown kind '{args.kind}'{did_you_mean(args.kind.lower(), LIST_KINDS, what='kinds')}")
        kinds = [kind]
    else:
        kinds = list(LIST_KINDS.values())
    for problem in plugin_load_problems(load_all=True):
        print(f"warning: {problem.message}", file=sys.stderr)
    if args.name is not None:
        _print_plugin(kinds[0], args.name)
        return EXIT_OK
    for kind in kinds:
        items = registry.entries(kind)
        if args.kind is None:
            plural = next(k for k, v in LIST_KINDS.items() if v == kind)
            print(f"{plural}:")
            if not items:
                print("  (none)")
        indent = "  " if args.kind is None else ""
        width = max((len(e.name) for e in items), default=0)
        for e in items:
            print(f"{indent}{e.name:<{width}}  {e.summary}".rstrip())
    return EXIT_OK


def _print_plugin(kind: str, name: str) -> None:
    """``netsim list KIND NAME``: the plugin's summary, where it is defined, and its parameters as a table."""
    from netsim import registry

    obj = registry.lookup(kind, name)  # ConfigError (exit 2) with the closest name when unknown
    same = [e for e in registry.entries(kind) if e.obj is obj]
    entry = next((e for e in same if e.name == name), same[0] if same else None)
    shown = entry.name if entry is not None else name
    summary = entry.summary if entry is not None else ""
    print(f"{shown} ({kind}){': ' + summary if summary else ''}")
    aliases = [e.name for e in same if e.name != shown]
    if aliases:
        print(f"also named: {', '.join(aliases)}")
    print(f"defined in: {getattr(obj, '__module__', '?')}:{getattr(obj, '__qualname__', type(obj).__name__)}")
    model = registry.params_model(obj)
    if model is None:
        print("parameters: none declared (it has no Params model)")
        return
    rows = registry.param_rows(model)
    if not rows:
        print("parameters: none")
        return
    print("parameters:")
    header = ("name", "type", "default", "unit", "description")
    table = [header, *((r.name, r.type, r.default, r.unit, r.description) for r in rows)]
    widths = [min(max(len(row[i]) for row in table), cap) for i, cap in enumerate((28, 36, 24, 8))]
    for row in table:
        cells = [f"{cell:<{w}}" if len(cell) <= w else cell for cell, w in zip(row[:4], widths)]
        print(("  " + "  ".join(cells) + "  " + row[4]).rstrip())
    if any(r.unit == registry.TIME_UNIT for r in rows):
        print("times are written with their unit: 20 us, 1.5 ms, 2 s")


def _cmd_docs(args: argparse.Namespace) -> int:
    """``netsim docs``: the scenario reference (Markdown) from the schema and every registered plugin."""
    from netsim.cli.docs import scenario_reference
    from netsim.scenario.validate import plugin_load_problems

    for problem in plugin_load_problems(load_all=True):
        print(f"warning: {problem.message}", file=sys.stderr)
    sys.stdout.write(scenario_reference())
    return EXIT_OK


def _cmd_schema(args: argparse.Namespace) -> int:
    """``netsim schema``: the JSON Schema of scenario and sweep files, for a YAML language server."""
    import json

    from netsim.cli.docs import json_schema

    sys.stdout.write(json.dumps(json_schema(), indent=2, sort_keys=True) + "\n")
    return EXIT_OK
