"""Malformed or hostile YAML is refused quickly with one short line (issue 14 A and B, "YAML structure")."""

from __future__ import annotations

import os
import time

import pytest
import yaml

from netsim.scenario import check_scenario

HEAD = "name: y\nduration: 1 s\n"
_LIBYAML = bool(getattr(yaml, "__with_libyaml__", False))  # PyYAML built with libyaml


def _laughs() -> str:
    # the classic "billion laughs": 9 levels of 9 aliases each expand to 9^9 = 387 420 489 strings
    lines = [HEAD.strip(), 'x-a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    prev = "a"
    for c in "bcdefghi":
        lines.append(f"x-{c}: &{c} [" + ",".join(["*" + prev] * 9) + "]")
        prev = c
    return "\n".join(lines) + f"\ndescription: *{prev}\n"


CASES = {
    # name: (file content, words the one-line message must contain)
    "billion_laughs": (_laughs(), "aliases are expanded"),
    "one_mb_string_aliased_1000_times": (HEAD + 'x-s: &s "' + "x" * 1_000_000 + '"\nx-l: [' + ",".join(["*s"] * 1000)
                                         + "]\n", "aliases are expanded"),
    "nesting_1000_deep": (HEAD + "description: " + "[" * 1000 + "]" * 1000 + "\n", "levels deep"),
    "mapping_nesting_1000_deep": (HEAD + "x-d: " + "{a: " * 1000 + "1" + "}" * 1000 + "\n", "levels deep"),
    "block_nesting_1000_deep": (HEAD + "x-d:\n" + "".join(" " * (i + 1) + f"k{i}:\n" for i in range(1000)) + " " * 1001
                                + "v\n", "levels deep"),
    "float_tag_on_text": (HEAD + "seed: !!float abc\n", "tagged !!float"),
    "int_tag_on_0x": (HEAD + "seed: !!int 0x\n", "tagged !!int"),
    "recursive_merge_key": (HEAD + "x-a: &a\n  b: 1\n  <<: *a\n", "inside its own anchor"),
    "python_tag": (HEAD + 'description: !!python/object/apply:os.system ["echo hi"]\n', "is not allowed"),
    "custom_tag": (HEAD + "description: !secret abc\n", "is not allowed"),
    "tab_indentation": (HEAD + "nodes:\n\tn: {}\n", "indent with spaces"),
}


def _check_fast(path, limit: float = 1.0) -> list:
    t0 = time.perf_counter()
    problems = check_scenario(path)
    elapsed = time.perf_counter() - t0
    assert elapsed < limit, f"took {elapsed:.2f} s"
    return problems


@pytest.mark.parametrize("case", sorted(CASES))
def test_hostile_yaml_is_refused_quickly_in_one_short_line(tmp_path, case):
    text, words = CASES[case]
    path = tmp_path / "s.yaml"
    path.write_text(text)
    # libyaml's parser scans the 1 MB string in about 40 ms (ruamel's pure-Python scanner needed 0.8 s); without
    # libyaml, PyYAML's pure-Python parser is about as slow as ruamel's was
    problems = _check_fast(path, 2.0 if case.startswith("one_mb") and not _LIBYAML else 1.0)
    assert len(problems) == 1 and problems[0].is_error
    message = problems[0].describe()
    assert words in message
    assert len(message) < 300 and "\n" not in message, message  # never echoes the file


def test_no_python_object_is_built(tmp_path):
    marker = tmp_path / "built"
    path = tmp_path / "s.yaml"
    path.write_text(HEAD + f'description: !!python/object/apply:os.system ["touch {marker}"]\n')
    (problem,) = _check_fast(path)
    assert "is not allowed" in problem.message
    assert not marker.exists()


@pytest.mark.parametrize("content,words", [
    (b"name: d\xff\xfe\nduration: 1 s\n", "not UTF-8"),
    (b"name: d\x00\nduration: 1 s\n", "NUL byte"),
    (b"name: d\nduration: 1 s\ndescription: '" + b"x" * (3 * 1024 * 1024) + b"'\n", "larger than"),
])
def test_bad_bytes_are_refused_with_what_to_change(tmp_path, content, words):
    path = tmp_path / "s.yaml"
    path.write_bytes(content)
    (problem,) = _check_fast(path)
    assert words in problem.message and len(problem.describe()) < 300


@pytest.mark.parametrize("kind", ["fifo", "directory", "dev_zero"])
def test_a_file_that_is_not_a_regular_file_is_refused_without_reading(tmp_path, kind):
    if kind == "fifo":
        path = tmp_path / "pipe.yaml"
        os.mkfifo(path)  # reading it would block forever
    elif kind == "directory":
        path = tmp_path / "dir.yaml"
        path.mkdir()
    else:
        path = "/dev/zero"  # reading it never ends
    (problem,) = _check_fast(path)
    assert "not a scenario file; pass the path of a .yaml file" in problem.message


def test_cli_validate_of_a_fifo_exits_non_zero(tmp_path, capsys):
    from netsim.cli import main

    path = tmp_path / "pipe.yaml"
    os.mkfifo(path)
    assert main(["validate", str(path)]) != 0
    assert "FIFO" in capsys.readouterr().out


def test_a_sweep_whose_base_is_an_alias_bomb_is_refused_quickly(tmp_path):
    from netsim.errors import ConfigError
    from netsim.sweep.spec import load_sweep

    (tmp_path / "base.yaml").write_text(_laughs())
    (tmp_path / "sweep.yaml").write_text("sweep: s\nbase: base.yaml\nfactors:\n  sd: {paths: [seed], values: [1, 2]}\n")
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match="aliases are expanded") as info:
        load_sweep(tmp_path / "sweep.yaml")
    assert time.perf_counter() - t0 < 1.0 and len(str(info.value)) < 400


def test_reading_a_run_folder_with_an_alias_bomb_is_refused_quickly(tmp_path, scenario):
    from netsim.errors import ConfigError
    from netsim.results import RunResult
    from netsim.runner import run

    run(scenario(), out=tmp_path / "run")
    (tmp_path / "run" / "scenario.yaml").write_text(_laughs())  # a run folder someone mailed
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match="aliases are expanded"):
        RunResult.read(tmp_path / "run")
    assert time.perf_counter() - t0 < 1.0
