"""``netsim validate``: every problem as file:line: path: message; exit 1 and the count on problems."""

from __future__ import annotations

from cli_files import line_of, write

from netsim.cli import main


def test_valid_file_exits_zero(tmp_path, capsys, good):
    path = write(tmp_path, "good.yaml", good)
    assert main(["validate", str(path)]) == 0
    assert capsys.readouterr().out == f"{path}: valid\n"


def test_each_problem_is_printed_with_file_line_and_path(tmp_path, capsys, good):
    text = good.replace("period: 10 ms", "period: 10 usec").replace("priority: 1", "priority: one")
    text = text.replace("nodes: [a, b]", "nodes: [a, b, ghost]")
    path = write(tmp_path, "bad.yaml", text)
    assert main(["validate", str(path)]) == 1
    captured = capsys.readouterr()
    assert captured.err == "3 problems\n"
    assert captured.out.splitlines() == [
        f"{path}:{line_of(path, '10 usec')}: nodes.a.tasks[0].period: unknown unit 'usec'; did you mean 'us'?",
        f"{path}:{line_of(path, 'priority: one')}: nodes.a.tasks[0].priority: expected an integer, got 'one'",
        f"{path}:{line_of(path, 'ghost')}: networks.net.nodes[2]: unknown node 'ghost' (known nodes: a, b)",
    ]


def test_problems_of_several_files_add_up(tmp_path, capsys, good):
    ok = write(tmp_path, "good.yaml", good)
    bad = write(tmp_path, "bad.yaml", good.replace("duration: 1 s", "duration: -1 s"))
    missing = tmp_path / "missing.yaml"
    assert main(["validate", str(ok), str(bad), str(missing)]) == 1
    captured = capsys.readouterr()
    assert "2 problems in total" in captured.err
    out = captured.out.splitlines()
    assert f"{ok}: valid" in out
    assert f"{bad}:2: duration: time must not be negative, got '-1 s'" in out
    assert f"{missing}: file not found: {missing}" in out


def test_warnings_are_printed_but_not_counted(tmp_path, capsys, good):
    path = write(tmp_path, "warn.yaml", good.replace("execution: 1 ms", "execution: 1 ms\n        deadline: 20 ms"))
    assert main(["validate", str(path)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith(f"{path}:{line_of(path, 'deadline: 20 ms')}: warning: nodes.a.tasks[0].deadline: ")
    assert out[1] == f"{path}: valid (1 warning)"


def test_many_problems_exit_one_and_print_the_count(tmp_path, capsys):
    # 300 problems: the old exit code (the count, capped at 255) read as neither a usage error nor Ctrl-C only by luck
    tasks = "".join(
        f"      - {{name: t{i}, program: zzc_prog, period: -{i + 1} ms, priority: 1}}\n" for i in range(300)
    )
    text = f"name: many\nduration: 1 s\nnodes:\n  a:\n    tasks:\n{tasks}"
    path = write(tmp_path, "many.yaml", text)
    assert main(["validate", str(path)]) == 1
    captured = capsys.readouterr()
    assert len(captured.out.splitlines()) == 300
    assert captured.err == "300 problems\n"


def test_two_or_130_problems_do_not_read_as_usage_error_or_ctrl_c(tmp_path, capsys, good):
    for n in (2, 130):
        tasks = "".join(
            f"      - {{name: t{i}, program: zzc_prog, period: -{i + 1} ms, priority: 1}}\n" for i in range(n)
        )
        path = write(tmp_path, f"n{n}.yaml", f"name: many\nduration: 1 s\nnodes:\n  a:\n    tasks:\n{tasks}")
        assert main(["validate", str(path)]) == 1
        assert capsys.readouterr().err == f"{n} problems\n"


def test_set_applies_before_checking(tmp_path, capsys, good):
    path = write(tmp_path, "good.yaml", good)
    assert main(["validate", str(path), "--set", "nodes.a.tasks[0].period=5 msec"]) == 1
    assert "nodes.a.tasks[0].period: unknown unit 'msec'; did you mean 'ms'?" in capsys.readouterr().out


def test_empty_file_and_syntax_error(tmp_path, capsys):
    empty = write(tmp_path, "empty.yaml", "")
    broken = write(tmp_path, "broken.yaml", "name: x\nduration: [1 s\n")
    assert main(["validate", str(empty), str(broken)]) == 1
    out = capsys.readouterr().out.splitlines()
    assert out[0] == f"{empty}:1: the file is empty; a scenario needs at least 'name' and 'duration'"
    assert out[1].startswith(f"{broken}:3: YAML syntax error: ")
