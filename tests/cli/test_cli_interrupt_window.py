"""A SIGTERM (turned into KeyboardInterrupt) that lands outside the command's own try still exits 130.

Uncaught, the KeyboardInterrupt makes Python end the process by SIGINT, so a sweep killed at such an instant
exited -2 instead of 130 (seen once in tests/sweep/test_faults_on_real_processes.py).
"""

import os

import netsim.cli as cli
from netsim.status import EXIT_INTERRUPTED
from netsim.trust import ENV_VAR


def test_an_interrupt_just_after_the_handler_is_set_exits_130(monkeypatch, capsys):
    def handler_then_signal():  # the signal arrives right after the handler is in place, before the try
        raise KeyboardInterrupt("signal 15")

    monkeypatch.setattr(cli, "_terminate_as_interrupt", handler_then_signal)
    assert cli.main(["list", "policies"]) == EXIT_INTERRUPTED
    assert "interrupted" in capsys.readouterr().err


def test_an_interrupt_in_the_commands_cleanup_exits_130(monkeypatch, capsys):
    # the finally restores the trust variable after the handler: an interrupt raised there still exits 130
    real_pop = os.environ.pop

    def pop(key, *default):
        if key == ENV_VAR:
            raise KeyboardInterrupt("signal 15")
        return real_pop(key, *default)

    monkeypatch.delenv(ENV_VAR, raising=False)
    monkeypatch.setattr(os.environ, "pop", pop)
    assert cli.main(["list", "policies"]) == EXIT_INTERRUPTED


def test_a_sigterm_that_c_code_wraps_in_another_exception_still_exits_as_interrupted(monkeypatch, capsys):
    # a SIGTERM that lands while pydantic-core builds a schema (during a lazy import inside the command) comes out
    # as a SchemaError wrapping the KeyboardInterrupt; the CLI used to report it as a crash (exit 1 with a
    # traceback, seen in tests/sweep/test_faults_on_real_processes.py); with the signal on record it is exit 130
    import os
    import signal

    import netsim.cli as cli
    from netsim.cli import parser

    def wrapped(args):
        try:
            os.kill(os.getpid(), signal.SIGTERM)  # the command's handler turns it into a KeyboardInterrupt here
            for _ in range(1000):  # Python runs the handler at its next bytecode check
                pass
        except KeyboardInterrupt as exc:
            raise RuntimeError("Error building validator: KeyboardInterrupt: signal 15") from exc  # as C code does
        raise AssertionError("the SIGTERM was not turned into a KeyboardInterrupt")

    monkeypatch.setattr(parser, "_cmd_validate", wrapped)
    monkeypatch.setattr(cli, "_interrupts", [])
    assert cli.main(["validate", "dc_servo_can"]) == 130
    assert "interrupted" in capsys.readouterr().err
