"""``netsim completion bash|zsh`` prints a completion script (issue 27 section 5)."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from netsim.cli import main

#: Every sub-command of ``netsim`` (written out here, so that a command dropped from the script is noticed).
COMMANDS = ("run", "analyze", "batch", "sweep", "report", "validate", "design", "list", "docs", "schema",
            "scenarios", "completion")


def test_bash_script_names_every_subcommand_and_completes_files_for_run(capsys):
    assert main(["completion", "bash"]) == 0
    script = capsys.readouterr().out
    line = next(x for x in script.splitlines() if x.startswith("_shtab_netsim_subparsers="))
    assert set(line.split("=", 1)[1].strip("()").split()) == set(COMMANDS)
    assert "_shtab_netsim_run_pos_0_COMPGEN=_shtab_compgen_files" in script
    assert "complete -o bashdefault -F _shtab_netsim netsim" in script


@pytest.mark.skipif(shutil.which("bash") is None, reason="needs bash")
def test_bash_completes_a_subcommand_prefix_and_the_completion_shells(tmp_path, capsys):
    assert main(["completion", "bash"]) == 0
    (tmp_path / "netsim.bash").write_text(capsys.readouterr().out)
    probe = (f"source {tmp_path / 'netsim.bash'}\n"
             'COMP_WORDS=(netsim sce); COMP_CWORD=1; _shtab_netsim netsim sce netsim; echo "${COMPREPLY[*]}"\n'
             'COMP_WORDS=(netsim completion ""); COMP_CWORD=2; _shtab_netsim netsim "" completion; '
             'echo "${COMPREPLY[*]}"\n')
    out = subprocess.run(["bash", "-c", probe], capture_output=True, text=True, timeout=30).stdout.splitlines()
    assert out == ["scenarios", "bash zsh"]


def test_zsh_script_is_a_compdef_for_netsim(capsys):
    assert main(["completion", "zsh"]) == 0
    script = capsys.readouterr().out
    assert script.startswith("#compdef netsim")
    assert all(f"{command}:" in script for command in COMMANDS)


def test_an_unknown_shell_is_a_usage_error(capsys):
    assert main(["completion", "fish"]) == 2
    assert "invalid choice: 'fish'" in capsys.readouterr().err
