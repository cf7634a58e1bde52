"""The ``netsim`` command: run, batch, sweep, report, validate and list.

Every command catches the errors a user can cause (:class:`~netsim.errors.NetsimError`, including
:class:`~netsim.scenario.ScenarioError`) and prints them without a traceback. Exit codes:

- ``0`` success;
- ``1`` a run, or any run of a batch or sweep, is not ``ok`` (diverged or error; one rule, :mod:`netsim.status`);
- ``2`` the scenario or the command line is invalid (nothing ran);
- ``validate``: the number of problems found (0 when every file is valid), capped at 255;
- ``130`` interrupted (Ctrl-C).

Heavy modules (numpy, pandas, control, the simulation engine) are imported inside the commands, so
``netsim --help`` is fast. BLAS is pinned to one thread (tiny matrices; parallelism comes from processes).
"""

from __future__ import annotations

import os

import netsim  # noqa: F401  (first: one BLAS thread and the same OpenBLAS kernels everywhere, netsim.blas)

import argparse  # noqa: E402
import logging  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any, Callable, Sequence, TextIO  # noqa: E402

__all__ = ["main", "build_parser", "LIST_KINDS"]

log = logging.getLogger("netsim.cli")

#: Registry kinds shown by ``netsim list`` (in this order), with their plural spellings.
LIST_KINDS: dict[str, str] = {
    "plants": "plant",
    "controllers": "controller",
    "estimators": "estimator",
    "networks": "network",
    "policies": "policy",
    "programs": "program",
    "signals": "signal",
    "metrics": "metric",
    "reports": "report",
}

from netsim.status import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_INVALID, EXIT_OK  # noqa: E402

_MAIN_EPILOG = """\
examples:
  netsim run scenarios/dc_servo_can.yaml                 run one scenario, write reports/<name>/<run-id>/
  netsim run scenarios/dc_servo_can.yaml --plot --seed 3 --set networks.can.bitrate="1 Mbit/s"
  netsim validate scenarios/*.yaml                       check files; exit code = number of problems
  netsim batch scenarios/ --workers 4                    run every scenario in a folder, write summary.csv
  netsim sweep scenarios/hdd_gpi_sweep.yaml              threshold sweep (parallel), summary.csv + surface
  netsim report reports/hdd_gpi                          tables and figures from a finished sweep
  netsim list programs                                   registered task programs, one per line

exit codes: 0 ok, 1 a run failed, 2 invalid scenario or usage; validate: number of problems.
"""

_RUN_EPILOG = """\
examples:
  netsim run scenarios/dc_servo_ideal.yaml
  netsim run scenarios/dc_servo_can.yaml --out /tmp/can --seed 7 --plot
  netsim run scenarios/dc_servo_can.yaml --set networks.can.bitrate="1 Mbit/s" --set 'plant.x0=[1, 0]'
  netsim run scenarios/three_servos_dm.yaml --set nodes.cpu.tasks[2].period="5 ms"

--set values are YAML: "1 Mbit/s" stays text, 0.5 is a number, [1, 0] a list, null removes a value.
The scenario is validated first; nothing runs when it has problems (exit code 2).
"""

_VALIDATE_EPILOG = """\
examples:
  netsim validate scenarios/dc_servo_can.yaml
  netsim validate scenarios/*.yaml --set duration="10 s"

Prints every problem as file:line: path: message (warnings marked "warning:") and exits with the
number of errors found (0 when every file is valid, at most 255).
"""

_BATCH_EPILOG = """\
examples:
  netsim batch scenarios/dc_servo_ideal.yaml scenarios/dc_servo_can.yaml
  netsim batch scenarios/ --out reports/batch --workers 2

A folder means every *.yaml/*.yml scenario in it (sweep files are skipped). A failing scenario does not
stop the batch: its row in summary.csv carries the error and the exit code is 1.
"""

_SWEEP_EPILOG = """\
examples:
  netsim sweep scenarios/hdd_gpi_sweep.yaml
  netsim sweep scenarios/hdd_gpi_sweep.yaml --workers 8 --out reports/gpi
  netsim sweep scenarios/hdd_gpi_sweep.yaml --scheduler tcp://10.0.0.5:8786
  netsim sweep scenarios/hdd_gpi_sweep.yaml --dask-local

Finished points are kept and skipped when the sweep is run again (use --overwrite to redo them).
"""

_REPORT_EPILOG = """\
examples:
  netsim report reports/hdd_gpi              tables/figures of a sweep or run folder
  netsim report hdd --out reports/hdd        a registered case-study report (see: netsim list reports)
  netsim report reports/hdd_gpi --no-plots
"""

_LIST_EPILOG = """\
examples:
  netsim list                 everything, grouped by kind
  netsim list plants          registered plant models
  netsim list programs        task/handler programs a scenario can run
  netsim list network can     one plugin: what it is, where it is defined, its parameters with
                              types, defaults and units (from its Params model)

kinds: """ + ", ".join(LIST_KINDS)


class _Formatter(argparse.RawDescriptionHelpFormatter):
    def __init__(self, prog: str) -> None:
        super().__init__(prog, max_help_position=32, width=100)


def _version() -> str:
    from netsim import __version__

    return f"netsim {__version__}"


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``netsim`` command (no heavy imports)."""
    parser = argparse.ArgumentParser(
        prog="netsim",
        description="Co-simulate networked control systems: real-time kernels, networks and plants.",
        epilog=_MAIN_EPILOG,
        formatter_class=_Formatter,
    )
    parser.add_argument("--version", action="version", version=_version())
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more log output (-vv: debug)")
    parser.add_argument("-q", "--quiet", action="store_true", help="only errors")
    # the same options after the command (`netsim run x.yaml -q`); SUPPRESS keeps the values given before it
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("-v", "--verbose", action="count", default=argparse.SUPPRESS,
                        help="more log output (-vv: debug)")
    common.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS, help="only errors")
    # issue 14: code from a scenario's plugins: files runs only when the user says so
    trust = argparse.ArgumentParser(add_help=False)
    trust.add_argument("--allow-plugins", action="store_true",
                       help="run the Python files the scenario's plugins: list names (only if you trust them)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    p = sub.add_parser("run", parents=[common, trust], help="run one scenario and write its run folder",
                       epilog=_RUN_EPILOG,
                       formatter_class=_Formatter, description="Validate and run one scenario.")
    p.add_argument("file", metavar="FILE", help="scenario YAML file")
    p.add_argument("--out", metavar="DIR", help="run folder (default: reports/<scenario>/<run-id>/)")
    p.add_argument("--seed", type=int, metavar="N", help="override the scenario seed")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="PATH=VALUE",
                   help="override a value, e.g. networks.can.bitrate='1 Mbit/s' (repeatable)")
    p.add_argument("--plot", action="store_true", help="also write PNG figures")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress bar (there is none either when stderr is not a terminal)")
    p.set_defaults(func=_cmd_run)

    p = sub.add_parser("batch", parents=[common, trust], help="run many scenarios in parallel, write summary.csv",
                       epilog=_BATCH_EPILOG,
                       formatter_class=_Formatter, description="Run many scenarios (parallel processes).")
    p.add_argument("paths", nargs="+", metavar="FILE|DIR", help="scenario files or folders of them")
    p.add_argument("--out", metavar="DIR", help="output folder (default: reports/batch-<time>/)")
    p.add_argument("--workers", type=_positive_int, metavar="N", help="parallel processes (default: all cores)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_batch)

    p = sub.add_parser("sweep", parents=[common, trust], help="run a parameter sweep (locally or on a dask cluster)",
                       epilog=_SWEEP_EPILOG,
                       formatter_class=_Formatter, description="Run a sweep file: factors over scenario fields.")
    p.add_argument("file", metavar="FILE", help="sweep YAML file")
    p.add_argument("--out", metavar="DIR", help="output folder (default: reports/<sweep>/)")
    p.add_argument("--workers", type=_positive_int, metavar="N", help="parallel processes (default: all cores)")
    p.add_argument("--scheduler", metavar="ADDR", help="dask scheduler address, e.g. tcp://host:8786")
    p.add_argument("--dask-local", action="store_true", help="use a local dask cluster instead of processes")
    p.add_argument("--dask-dashboard", metavar="ADDR",
                   help="with --dask-local: serve its dashboard at ADDR, e.g. 127.0.0.1:8787 (default: off)")
    p.add_argument("--overwrite", action="store_true", help="rerun points that already have results")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_sweep)

    p = sub.add_parser("report", parents=[common], help="tables and figures from a run/sweep folder or a case study",
                       epilog=_REPORT_EPILOG, formatter_class=_Formatter,
                       description="Build report tables (CSV) and figures.")
    p.add_argument("target", metavar="DIR|NAME", help="a run or sweep folder, or a registered report name")
    p.add_argument("--out", metavar="DIR", help="where to write (default: next to the input)")
    p.add_argument("--no-plots", action="store_true", help="tables only")
    p.set_defaults(func=_cmd_report)

    p = sub.add_parser("validate", parents=[common, trust], help="check scenario files; exit code = number of problems",
                       epilog=_VALIDATE_EPILOG, formatter_class=_Formatter,
                       description="Check scenario files completely without running them.")
    p.add_argument("files", nargs="+", metavar="FILE", help="scenario YAML files")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="PATH=VALUE",
                   help="apply an override before checking (repeatable)")
    p.set_defaults(func=_cmd_validate)

    p = sub.add_parser("list", parents=[common], help="list registered plants, programs, networks, ...",
                       epilog=_LIST_EPILOG,
                       formatter_class=_Formatter, description="List registered building blocks, or show one "
                       "plugin's parameters.")
    p.add_argument("kind", nargs="?", metavar="KIND", help="one kind (plural or singular), e.g. plants")
    p.add_argument("name", nargs="?", metavar="NAME", help="one plugin of KIND: print its parameters")
    p.set_defaults(func=_cmd_list)
    return parser


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


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
def _is_sweep(file: str) -> bool:
    from netsim.sweep.check import is_sweep_file

    return is_sweep_file(file)


def _cmd_validate(args: argparse.Namespace) -> int:
    from netsim.scenario import check_scenario

    overrides = _overrides(args.overrides)
    n_errors = 0
    for file in args.files:
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
            print(f"{file}: valid{note}")
    if len(args.files) > 1 and n_errors:
        print(f"{n_errors} problem{'s' if n_errors != 1 else ''} in total", file=sys.stderr)
    return min(n_errors, 255)


def _cmd_run(args: argparse.Namespace) -> int:
    from netsim.scenario import ScenarioError, load_scenario

    if _is_sweep(args.file):
        from netsim.errors import ConfigError

        raise ConfigError(f"{args.file}: this is a sweep file; use `netsim sweep {args.file}`")
    overrides = _overrides(args.overrides)
    if args.out is not None:
        from netsim.results import check_out_dir

        check_out_dir(args.out)  # a bad --out is refused before anything runs
    if args.seed is not None:
        overrides["seed"] = args.seed  # applied to the raw tree with the --set values: one validation
    try:
        scenario = load_scenario(args.file, overrides or None)
    except ScenarioError as exc:
        _print_problems(exc.problems, sys.stderr)
        n = len(exc.errors)
        _err(f"{args.file}: {n} problem{'s' if n != 1 else ''}; nothing was run")
        return EXIT_INVALID
    from netsim.runner import run

    show = not (args.no_progress or args.quiet) and sys.stderr.isatty()
    with _RunProgress(scenario.name, enabled=show) as progress:
        result = run(scenario, out=args.out, plot=args.plot, progress=progress.callback)
    meta = getattr(result, "meta", {}) or {}
    status = str(meta.get("status", "ok"))
    out_dir = getattr(result, "out_dir", None) or meta.get("out_dir")
    where = f"; wrote {out_dir}" if out_dir else ""
    n_warn = len(meta.get("warnings") or [])
    told = f"{status} ({n_warn} warning{'s' if n_warn != 1 else ''} above)" if n_warn else status
    if not args.quiet or status != "ok":  # quiet: nothing on stdout unless the run failed
        print(f"{scenario.name}: {told}{where}")
    if not args.quiet:
        _print_metrics(getattr(result, "metrics", None))
    from netsim.status import count_statuses

    if status != "ok":
        error = meta.get("error")
        if error:
            _err(str(error))
    return count_statuses([status]).exit_code()


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


def _print_metrics(metrics: Any, limit: int = 30) -> None:
    if metrics is None:
        return
    try:
        items = list(metrics.items())
    except AttributeError:
        return
    if not items:
        return
    width = max(len(str(k)) for k, _ in items[:limit])
    for key, value in items[:limit]:
        text = f"{value:.6g}" if isinstance(value, float) else str(value)
        print(f"  {str(key):<{width}}  {text}")
    if len(items) > limit:
        print(f"  ... {len(items) - limit} more in metrics.csv")


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
        else:
            raise ConfigError(f"file not found: {item}")
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
    if not Path(args.file).exists():
        raise ConfigError(f"file not found: {args.file}")
    from netsim.sweep import run_sweep

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
    for problem in plugin_load_problems():
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


# --------------------------------------------------------------------------------------------- main
def _setup_logging(verbose: int, quiet: bool) -> None:
    level = logging.ERROR if quiet else (logging.WARNING, logging.INFO, logging.DEBUG)[min(verbose, 2)]
    root = logging.getLogger()
    if not any(getattr(h, "_netsim_cli", False) for h in root.handlers):
        handler = logging.StreamHandler(sys.stderr)
        handler.setFormatter(logging.Formatter("%(levelname)s: %(message)s"))
        handler._netsim_cli = True  # type: ignore[attr-defined]
        root.addHandler(handler)
    root.setLevel(level)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``netsim`` command line; returns the exit code (see the module docstring).

    Parameters
    ----------
    argv
        Arguments without the program name (default: ``sys.argv[1:]``).
    """
    parser = build_parser()
    try:
        args = parser.parse_args(list(argv) if argv is not None else None)
    except SystemExit as exc:  # --help, --version, usage errors
        return int(exc.code) if isinstance(exc.code, int) else (EXIT_OK if exc.code is None else EXIT_INVALID)
    if getattr(args, "func", None) is None:
        parser.print_help()
        return EXIT_INVALID
    _setup_logging(args.verbose, args.quiet)
    func: Callable[[argparse.Namespace], int] = args.func
    from netsim.errors import ConfigError, NetsimError

    previous = _terminate_as_interrupt()
    from netsim.trust import ENV_VAR

    trust_before = os.environ.get(ENV_VAR)
    if getattr(args, "allow_plugins", False):
        os.environ[ENV_VAR] = "1"  # this command and the batch/sweep worker processes it starts
    try:
        return func(args)
    except KeyboardInterrupt as exc:
        _err("interrupted")
        _partial_folder(exc)
        return EXIT_INTERRUPTED
    except ConfigError as exc:
        problems = getattr(exc, "problems", None)
        if problems:
            _print_problems(problems, sys.stderr)
            _err(str(exc).splitlines()[0].rstrip(":"))  # the summary line, e.g. "...: 2 problems; nothing was run"
        else:
            _err(str(exc))
        return EXIT_INVALID
    except NetsimError as exc:
        _err(str(exc))
        _partial_folder(exc)
        return EXIT_FAILED
    except OSError as exc:  # a file or folder that cannot be written (disk full, permissions, a file in the way)
        where = exc.filename or getattr(exc, "run_folder", None) or "output"
        _err(f"cannot write {where}: {exc.strerror or exc}")
        _partial_folder(exc)
        return EXIT_FAILED
    except Exception as exc:  # a bug: the traceback is wanted, and where the partial results are
        _partial_folder(exc)
        raise
    finally:
        if trust_before is None:
            os.environ.pop(ENV_VAR, None)
        else:
            os.environ[ENV_VAR] = trust_before
        if previous is not None:
            import signal

            signal.signal(signal.SIGTERM, previous)


def _terminate_as_interrupt() -> Any:
    """Make SIGTERM stop a command like Ctrl-C (what was simulated is kept); returns the previous handler.

    Only in the main thread (signal handlers cannot be set elsewhere); returns None where it was not set.
    """
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return None

    def _raise(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt(f"signal {signum}")

    try:
        return signal.signal(signal.SIGTERM, _raise)
    except (ValueError, OSError):
        return None


def _partial_folder(exc: BaseException) -> None:
    """Tell where a failed run left its partial run folder (``exc.run_folder``, set by the runner)."""
    folder = getattr(exc, "run_folder", None)
    if folder is not None:
        print(f"netsim: the partial results are in {folder}", file=sys.stderr)


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
