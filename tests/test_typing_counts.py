"""The Any counter of .ci/typing_counts.py (issue 28's measure) counts what it says on a small tree."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _load():
    spec = importlib.util.spec_from_file_location("typing_counts", ROOT / ".ci" / "typing_counts.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_annotations_with_any_and_bare_any_names_are_counted(tmp_path):
    (tmp_path / "netsim").mkdir()
    (tmp_path / "models").mkdir()
    (tmp_path / "netsim" / "a.py").write_text(
        "from typing import Any\n"
        "import typing\n"
        "def f(scenario: Any, job: 'Any', x: dict[str, Any], y: int) -> typing.Any: ...\n"
        "class C:\n"
        "    scenario: 'Scenario | None' = None\n"
        "    job: list[Any]\n",
        encoding="utf-8",
    )
    (tmp_path / "models" / "b.py").write_text("def g(job: Any, *args: 'Any', **kw: int) -> None: ...\n",
                                                encoding="utf-8")
    total, with_any, named, per_file = _load().count(tmp_path)
    # by hand: a.py has 5 (f: scenario, job, x, y, return) + 2 (C's fields) annotations, b.py 4 (job, args, kw,
    # return); with Any: scenario, job, x, return, C.job in a.py, job and args in b.py
    assert (total, with_any) == (11, 7)
    # bare Any: f's scenario and job, g's job (C.scenario is not Any, C.job is list[Any], not bare)
    assert (named["scenario"], named["job"]) == (1, 2)
    assert per_file[("models/b.py", "job")] == 1
