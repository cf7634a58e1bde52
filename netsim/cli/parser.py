"""The argument parser of the ``netsim`` command: sub-commands, options, and the examples in each ``--help``."""

from __future__ import annotations

import argparse

from netsim.cli.commands import (
    LIST_KINDS,
    _cmd_analyze,
    _cmd_batch,
    _cmd_docs,
    _cmd_list,
    _cmd_report,
    _cmd_run,
    _cmd_schema,
    _cmd_sweep,
    _cmd_validate,
)

__all__ = ["build_parser"]

_MAIN_EPILOG = """\
examples:
  netsim scenarios                                       the shipped scenarios, one line each
  netsim run dc_servo_can                                run a shipped scenario by name
  netsim run scenarios/dc_servo_can.yaml                 run one scenario, write reports/<name>/<run-id>/
  netsim run scenarios/dc_servo_can.yaml --plot --seed 3 --set networks.can.bitrate="1 Mbit/s"
  netsim validate scenarios/*.yaml                       check files; exit 1 and the count on problems
  netsim design scenarios/dc_servo_lqr_kalman.yaml       gains, eigenvalues, delay margin; nothing runs
  netsim batch scenarios/ --workers 4                    run every scenario in a folder, write summary.csv
  netsim sweep scenarios/hdd_gpi_sweep.yaml              threshold sweep (parallel), summary.csv + surface
  netsim report reports/hdd_gpi                          tables and figures from a finished sweep
  netsim list programs                                   registered task programs, one per line
  netsim docs > scenario-reference.md                    every scenario key and plugin parameter
  netsim schema > netsim.schema.json                     JSON Schema for editor completion
  netsim completion bash > ~/.local/share/bash-completion/completions/netsim

FILE is a scenario file, or the name of a shipped scenario (netsim scenarios lists them); a file of that name
in the working folder comes first.

exit codes: 0 ok, 1 a run failed, 2 invalid scenario or usage; validate: 1 on problems (count printed).
"""

_RUN_EPILOG = """\
examples:
  netsim run dc_servo_can                                 a shipped scenario, by name
  netsim run scenarios/dc_servo_ideal.yaml
  netsim run scenarios/dc_servo_can.yaml --out /tmp/can --seed 7 --plot
  netsim run scenarios/three_servos_dm.yaml --plot-window "0.2 s:0.3 s"
  netsim run scenarios/dc_servo_can.yaml --set networks.can.bitrate="1 Mbit/s" --set 'plant.x0=[1, 0]'
  netsim run scenarios/three_servos_dm.yaml --set nodes.cpu.tasks[2].period="5 ms"

--set values are YAML: "1 Mbit/s" stays text, 0.5 is a number, [1, 0] a list, null removes a value.
The scenario is validated first; nothing runs when it has problems (exit code 2).
"""

_ANALYZE_EPILOG = """\
examples:
  netsim analyze scenarios/three_servos_dm.yaml       RTA bound vs worst response per task, ISE per loop
  netsim analyze scenarios/dc_servo_can.yaml --out /tmp/can
  netsim analyze scenarios/dc_servo_can.yaml --set nodes.interference.tasks[0].params.share=0.5

Runs the scenario (writing its run folder), then prints per task the response-time bound beside the worst
simulated response, per CAN message the CAN analysis bound beside the worst simulated latency, and per PID
loop on an LTI plant the expected ISE (netsim.analysis.lqg, fed the run's measured timing) beside the run's.
The same table is written as analysis.csv in the run folder. Exit code 1 when a simulated value exceeds its
bound (a bug in the simulator or in the analysis).
"""

_VALIDATE_EPILOG = """\
examples:
  netsim validate scenarios/dc_servo_can.yaml
  netsim validate scenarios/*.yaml --set duration="10 s"

Prints every problem as file:line: path: message (warnings marked "warning:"), then the number of
errors on standard error; exits 1 when there are any, 0 when every file is valid.
"""

_DESIGN_EPILOG = """\
examples:
  netsim design scenarios/dc_servo_lqr_kalman.yaml
  netsim design scenarios/dc_servo_lqr_kalman.yaml --set nodes.controller.tasks[0].params.law.R=1e-4
  netsim design scenarios/pendulum_lqr.yaml --json > design.json

Builds every state_feedback task's model, estimator and law as a run does and prints, per task, the discrete
model, K and Ki, the estimator gain, the eigenvalues of the state-feedback loop, of the observer and of the
nominal loop (no network), and the delay margin (netsim.analysis.lqg) where the plant has a continuous LTI
model. --json prints what a run writes to design.json. Nothing is simulated.
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
  netsim report hdd                          a registered case-study report (see: netsim list reports),
                                             written to ./reports/hdd/ (its runs under ./reports/hdd/runs/)
  netsim report reports/hdd_gpi --no-plots
"""

_SCENARIOS_EPILOG = """\
examples:
  netsim scenarios                           name and one-line summary of each shipped scenario and sweep
  netsim run dc_servo_can                    run one by name
  cp "$(netsim scenarios --path)/dc_servo_can.yaml" my_servo.yaml     start your own from a copy
"""

_COMPLETION_EPILOG = """\
examples:
  netsim completion bash > ~/.local/share/bash-completion/completions/netsim
  netsim completion zsh > ~/.zfunc/_netsim        (with fpath+=(~/.zfunc) before compinit in ~/.zshrc)
  eval "$(netsim completion bash)"                this shell only
"""

_LIST_EPILOG = """\
examples:
  netsim list                 everything, grouped by kind
  netsim list plants          registered plant models
  netsim list programs        task/handler programs a scenario can run
  netsim list network can     one plugin: what it is, where it is defined, its parameters with
                              types, defaults and units (from its Params model)

kinds: """ + ", ".join(LIST_KINDS)


_DOCS_EPILOG = """\
examples:
  netsim docs                              the reference on the terminal
  netsim docs > scenario-reference.md      the same as docs/scenario-reference.md in the repository
"""

_SCHEMA_EPILOG = """\
examples:
  netsim schema > netsim.schema.json

Editors with a YAML language server (VS Code's YAML extension, ...) complete keys and flag errors with it:
put '# yaml-language-server: $schema=netsim.schema.json' on a scenario's first line, or map the schema to
your scenario files in the editor's settings (yaml.schemas).
"""


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
    _file(p.add_argument("file", metavar="FILE", help="scenario YAML file, or a shipped scenario's name"))
    p.add_argument("--out", metavar="DIR", help="run folder (default: reports/<scenario>/<run-id>/)")
    p.add_argument("--seed", type=int, metavar="N", help="override the scenario seed")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="PATH=VALUE",
                   help="override a value, e.g. networks.can.bitrate='1 Mbit/s' (repeatable)")
    p.add_argument("--plot", action="store_true", help="also write PNG figures")
    p.add_argument("--plot-window", metavar="T|T0:T1",
                   help="time window of the Gantt chart and network timeline, e.g. '50 ms' or '1 s:1.2 s' "
                        "(implies --plot; default: the window where every job spans 2 px, the whole run when it fits)")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress bar (there is none either when stderr is not a terminal)")
    p.set_defaults(func=_cmd_run)

    p = sub.add_parser("analyze", parents=[common, trust], help="run a scenario and set analysis beside simulation",
                       epilog=_ANALYZE_EPILOG, formatter_class=_Formatter,
                       description="Run one scenario and compare its response times, CAN latencies and loop "
                                   "costs with what analysis predicts.")
    _file(p.add_argument("file", metavar="FILE", help="scenario YAML file, or a shipped scenario's name"))
    p.add_argument("--out", metavar="DIR", help="run folder (default: reports/<scenario>/<run-id>/)")
    p.add_argument("--seed", type=int, metavar="N", help="override the scenario seed")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="PATH=VALUE",
                   help="override a value (repeatable)")
    p.set_defaults(func=_cmd_analyze)

    p = sub.add_parser("batch", parents=[common, trust], help="run many scenarios in parallel, write summary.csv",
                       epilog=_BATCH_EPILOG,
                       formatter_class=_Formatter, description="Run many scenarios (parallel processes).")
    _file(p.add_argument("paths", nargs="+", metavar="FILE|DIR",
                         help="scenario files or folders of them (or shipped scenarios' names)"))
    p.add_argument("--out", metavar="DIR", help="output folder (default: reports/batch-<time>/)")
    p.add_argument("--workers", type=_positive_int, metavar="N", help="parallel processes (default: all cores)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_batch)

    p = sub.add_parser("sweep", parents=[common, trust], help="run a parameter sweep (locally or on a dask cluster)",
                       epilog=_SWEEP_EPILOG,
                       formatter_class=_Formatter, description="Run a sweep file: factors over scenario fields.")
    _file(p.add_argument("file", metavar="FILE", help="sweep YAML file, or a shipped sweep's name"))
    p.add_argument("--out", metavar="DIR", help="output folder (default: reports/<sweep>/)")
    p.add_argument("--workers", type=_positive_int, metavar="N", help="parallel processes (default: all cores)")
    p.add_argument("--scheduler", metavar="ADDR", help="dask scheduler address, e.g. tcp://host:8786")
    p.add_argument("--dask-local", action="store_true", help="use a local dask cluster instead of processes")
    p.add_argument("--dask-dashboard", metavar="ADDR",
                   help="with --dask-local: serve its dashboard at ADDR, e.g. 127.0.0.1:8787 (default: off)")
    p.add_argument("--overwrite", action="store_true", help="rerun points that already have results")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--plot-format", choices=("png", "pdf", "svg"), default="png",
                   help="file format of the surface figure (default: png)")
    p.set_defaults(func=_cmd_sweep)

    p = sub.add_parser("report", parents=[common], help="tables and figures from a run/sweep folder or a case study",
                       epilog=_REPORT_EPILOG, formatter_class=_Formatter,
                       description="Build report tables (CSV) and figures.")
    p.add_argument("target", metavar="DIR|NAME", help="a run or sweep folder, or a registered report name")
    p.add_argument("--out", metavar="DIR",
                   help="where to write (default: DIR/report/ for a folder, ./reports/NAME/ for a case study)")
    p.add_argument("--no-plots", action="store_true", help="tables only")
    p.add_argument("--plot-format", choices=("png", "pdf", "svg"), default="png",
                   help="file format of the figures (default: png)")
    p.set_defaults(func=_cmd_report)

    p = sub.add_parser("validate", parents=[common, trust], help="check scenario files; exit 1 on problems",
                       epilog=_VALIDATE_EPILOG, formatter_class=_Formatter,
                       description="Check scenario files completely without running them.")
    _file(p.add_argument("files", nargs="+", metavar="FILE", help="scenario YAML files, or shipped scenarios' names"))
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="PATH=VALUE",
                   help="apply an override before checking (repeatable)")
    p.set_defaults(func=_cmd_validate)

    p = sub.add_parser("design", parents=[common, trust], help="print the state_feedback designs without running",
                       epilog=_DESIGN_EPILOG, formatter_class=_Formatter,
                       description="Print each state_feedback task's gains, eigenvalues and delay margin.")
    _file(p.add_argument("file", metavar="FILE", help="scenario YAML file, or a shipped scenario's name"))
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="PATH=VALUE",
                   help="apply an override first (repeatable)")
    p.add_argument("--json", action="store_true", help="print design.json's text instead of the table")
    p.set_defaults(func=_cmd_design)

    p = sub.add_parser("list", parents=[common], help="list registered plants, programs, networks, ...",
                       epilog=_LIST_EPILOG,
                       formatter_class=_Formatter, description="List registered building blocks, or show one "
                       "plugin's parameters.")
    p.add_argument("kind", nargs="?", metavar="KIND", help="one kind (plural or singular), e.g. plants")
    p.add_argument("name", nargs="?", metavar="NAME", help="one plugin of KIND: print its parameters")
    p.set_defaults(func=_cmd_list)

    p = sub.add_parser("docs", parents=[common], help="print the scenario reference (every key and plugin parameter)",
                       epilog=_DOCS_EPILOG, formatter_class=_Formatter,
                       description="Print a Markdown reference of scenario and sweep files: every key, and every "
                       "registered plugin's parameters with types, defaults and units.")
    p.set_defaults(func=_cmd_docs)

    p = sub.add_parser("schema", parents=[common], help="print the JSON Schema of scenario and sweep files",
                       epilog=_SCHEMA_EPILOG, formatter_class=_Formatter,
                       description="Print a JSON Schema (draft 2020-12) that accepts a scenario or a sweep file.")
    p.set_defaults(func=_cmd_schema)

    p = sub.add_parser("scenarios", parents=[common], help="list the shipped scenarios and sweeps, one line each",
                       epilog=_SCENARIOS_EPILOG, formatter_class=_Formatter,
                       description="List the scenarios and sweeps that come with netsim (run them by name).")
    p.add_argument("--path", action="store_true", help="print the folder that holds them instead")
    p.set_defaults(func=_cmd_scenarios)

    p = sub.add_parser("completion", parents=[common], help="print a shell completion script (bash or zsh)",
                       epilog=_COMPLETION_EPILOG, formatter_class=_Formatter,
                       description="Print a completion script for the netsim command (sub-commands, options, "
                                   "choices and file names).")
    p.add_argument("shell", choices=_SHELLS, help="the shell: " + " or ".join(_SHELLS))
    p.set_defaults(func=_cmd_completion)
    return parser


#: Shells ``netsim completion`` writes a script for.
_SHELLS = ("bash", "zsh")

#: shtab's file-name completion, spelled out so that building the parser does not import shtab (shtab.FILE).
_FILE_COMPLETION = {"bash": "_shtab_compgen_files", "zsh": "_files", "tcsh": "f"}


def _file(action: argparse.Action) -> argparse.Action:
    """Mark a FILE argument for shell completion by file name (read by ``netsim completion``)."""
    action.complete = _FILE_COMPLETION  # type: ignore[attr-defined]
    return action


def _cmd_design(args: argparse.Namespace) -> int:
    from netsim.cli.design import cmd_design  # imported when the command runs (netsim --help stays fast)
    from netsim.shipped import resolve

    args.file = resolve(args.file)  # a shipped scenario's name, as for run
    return cmd_design(args)


def _cmd_scenarios(args: argparse.Namespace) -> int:
    from netsim.cli.shell import cmd_scenarios

    return cmd_scenarios(args)


def _cmd_completion(args: argparse.Namespace) -> int:
    from netsim.cli.shell import cmd_completion

    return cmd_completion(args, build_parser())


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value
