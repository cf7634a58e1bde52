"""The ``netsim`` command: run, batch, sweep, report, validate and list.

Every command catches the errors a user can cause (:class:`~netsim.errors.NetsimError`, including
:class:`~netsim.scenario.ScenarioError`) and prints them without a traceback. Exit codes:

- ``0`` success;
- ``1`` a run, or any run of a batch or sweep, is not ``ok`` (diverged, unstable or error; one rule, :mod:`netsim.status`);
- ``2`` the scenario or the command line is invalid (nothing ran);
- ``validate``: ``1`` when any file has problems (their count is printed: as an exit code it would read as a
  usage error or Ctrl-C), ``0`` when every file is valid;
- ``130`` interrupted (Ctrl-C);
- ``0`` when the reader of the output stops early (``netsim list | head``): the rest of the output is dropped
  quietly (no traceback), like output nobody reads; 0 rather than 141 so that ``set -o pipefail`` scripts do not
  fail on a ``| head``.

Heavy modules (numpy, pandas, control, the simulation engine) are imported inside the commands, so
``netsim --help`` is fast. BLAS is pinned to one thread (tiny matrices; parallelism comes from processes).

The command is split in three: :mod:`netsim.cli.parser` (arguments and examples), :mod:`netsim.cli.commands`
(what each sub-command does) and this module (:func:`main`: logging, exit codes, signals, errors).
"""

from __future__ import annotations

import os

import netsim  # noqa: F401  (first: one BLAS thread and the same OpenBLAS kernels everywhere, netsim.blas)

import argparse  # noqa: E402
import atexit  # noqa: E402
import gc  # noqa: E402
import logging  # noqa: E402
import sys  # noqa: E402
from typing import Any, Callable, Sequence  # noqa: E402

from netsim.cli.commands import LIST_KINDS, _err, _print_problems  # noqa: E402
from netsim.cli.parser import build_parser  # noqa: E402
from netsim.status import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_INVALID, EXIT_OK  # noqa: E402

__all__ = ["main", "build_parser", "LIST_KINDS"]

log = logging.getLogger("netsim.cli")


# --------------------------------------------------------------------------------------------- main
def _setup_logging(verbose: int, quiet: bool) -> None:
    level = logging.ERROR if quiet else (logging.WARNING, logging.INFO, logging.DEBUG)[min(verbose, 2)]
    root = logging.getLogger()
    ours = [h for h in root.handlers if getattr(h, "_netsim_cli", False)]
    for h in ours:  # a second main() in one process (tests, notebooks): write to today's stderr, not the first one's
        if isinstance(h, logging.StreamHandler) and h.stream is not sys.stderr:
            h.stream = sys.stderr  # not setStream(): it flushes the old stream, which may be closed
    if not ours:
        handler = logging.StreamHandler(sys.stderr)
        handler.setFormatter(logging.Formatter("%(levelname)s: %(message)s"))
        handler._netsim_cli = True  # type: ignore[attr-defined]
        root.addHandler(handler)
        ours = [handler]
    for h in ours:  # the console's own level: a run may lower a logger's level to keep warnings in meta.json
        h.setLevel(level)
    root.setLevel(level)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``netsim`` command line; returns the exit code (see the module docstring).

    Parameters
    ----------
    argv
        Arguments without the program name (default: ``sys.argv[1:]``).
    """
    _freeze_heap_at_exit()
    threshold = gc.get_threshold()
    gc.set_threshold(max(threshold[0], _YOUNG_GC_THRESHOLD), *threshold[1:])
    try:
        return _main(argv)
    except KeyboardInterrupt:
        # a Ctrl-C, or a SIGTERM in the instants between setting the command's handler and entering its try (or
        # while its finally restores it): still exit 130. Uncaught, Python would end the process by SIGINT (-2).
        _err("interrupted")
        return EXIT_INTERRUPTED
    finally:
        gc.set_threshold(*threshold)


#: Allocations between two collections of the youngest generation while a command runs (Python's default: 700).
#: Building the scenario schema and the simulation allocates hundreds of thousands of objects that all stay alive;
#: at 700, ~150 collections re-examined them for ~30-60 ms of a 0.5 s `netsim validate` or `run` (issue 29).
_YOUNG_GC_THRESHOLD = 20_000

_frozen_at_exit = False


def _freeze_heap_at_exit() -> None:
    """At interpreter exit, move every object to the collector's permanent generation (:func:`gc.freeze`), once per
    process.

    The interpreter's shutdown runs full garbage collections over everything a command imported and built (the
    schema, numpy, the run's records); they free nothing that matters to a process about to end, and cost ~0.1 s of
    CPU in a `netsim validate` (issue 29). Registered with :mod:`atexit`, the freeze runs after the handlers
    registered later (weakref finalizers, a plugin's clean-up) and does not change what they do; Python does not
    promise ``__del__`` calls for objects still alive at exit anyway. A caller of :func:`main` inside a longer
    process (tests, a notebook) only gets a faster exit of that process.
    """
    global _frozen_at_exit
    if not _frozen_at_exit:
        atexit.register(gc.freeze)
        _frozen_at_exit = True


def _main(argv: Sequence[str] | None) -> int:
    """:func:`main` without the last-resort catch of an interrupt that lands outside the command's own try."""
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
        code = func(args)
        sys.stdout.flush()  # a closed pipe shows here, inside the try, rather than at interpreter exit
        return code
    except BrokenPipeError:
        _drop_stdout()
        return EXIT_OK
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
    except MemoryError as exc:  # outside the event loop (which ends as a SimulationError): one line, the fix
        from netsim.scenario.memory import out_of_memory

        _err(str(out_of_memory()))
        _partial_folder(exc)
        return EXIT_FAILED
    except Exception as exc:  # a bug: the traceback is wanted, and where the partial results are
        if _interrupts:  # unless a SIGTERM landed in C code that wrapped its KeyboardInterrupt (see _interrupts)
            _err("interrupted")
            _partial_folder(exc)
            return EXIT_INTERRUPTED
        _partial_folder(exc)
        raise
    finally:
        if previous is not None:  # first, so that a late SIGTERM no longer raises inside this cleanup
            import signal

            signal.signal(signal.SIGTERM, previous)
        if trust_before is None:
            os.environ.pop(ENV_VAR, None)
        else:
            os.environ[ENV_VAR] = trust_before


def _drop_stdout() -> None:
    """Point stdout at the null device after its reader went away, so that the flush at exit neither fails nor
    prints 'Exception ignored ... BrokenPipeError'."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):  # an in-process stdout without a file descriptor
        pass


#: Signals turned into KeyboardInterrupt during this process's commands. An interrupt raised inside C code can come
#: out as another exception (pydantic-core building a schema during a lazy import wraps it in a SchemaError): with
#: a signal on record, such an exception is an interruption, not a bug.
_interrupts: list[int] = []


def _terminate_as_interrupt() -> Any:
    """Make SIGTERM stop a command like Ctrl-C (what was simulated is kept); returns the previous handler.

    Only in the main thread (signal handlers cannot be set elsewhere); returns None where it was not set.
    """
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return None

    def _raise(signum: int, frame: Any) -> None:
        _interrupts.append(signum)
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
