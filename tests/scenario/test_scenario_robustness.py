"""Whatever a user writes, validation reports problems instead of raising."""

from __future__ import annotations

import textwrap

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from netsim.scenario import check_scenario, load_scenario
from netsim.scenario.paths import format_path

_SCALARS = st.one_of(
    st.none(), st.booleans(), st.integers(-5, 10**12), st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from(["", "10 ms", "-1 s", "1 usec", "ghost", "bus", "on_message:bus", "zzt_idle", "x" * 80]),
)
_VALUES = st.recursive(
    _SCALARS,
    lambda inner: st.one_of(st.lists(inner, max_size=3), st.dictionaries(st.sampled_from(["a", "type", "name", "nodes", "dist"]), inner, max_size=3)),
    max_leaves=6,
)


def _all_paths(node, prefix=()):
    yield prefix
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _all_paths(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _all_paths(v, (*prefix, i))


@settings(max_examples=80, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_random_values_anywhere_give_problems_not_exceptions(base, data):
    paths = [p for p in _all_paths(base()) if p]
    edits = data.draw(st.lists(st.tuples(st.sampled_from(paths), _VALUES), min_size=1, max_size=3))
    raw = base()
    for parts, value in edits:
        node = raw
        try:
            for part in parts[:-1]:
                node = node[part]
            node[parts[-1]] = value
        except (KeyError, IndexError, TypeError):
            continue  # an earlier edit replaced a parent
    problems = check_scenario(raw)
    for p in problems:
        assert isinstance(p.message, str) and p.message
    if not any(p.is_error for p in problems):
        load_scenario(raw)  # and a clean result really loads


def test_yaml_anchors_merge_keys_and_extension_keys(tmp_path):
    path = tmp_path / "anchors.yaml"
    path.write_text(
        textwrap.dedent(
            """\
            name: anchors
            duration: 1 s
            x-task: &task {program: zzt_idle, priority: 1, execution: 1 ms}
            nodes:
              a:
                tasks:
                  - {<<: *task, name: t1, period: 10 ms}
                  - <<: *task
                    name: t2
                    period: 1 usec
            """
        )
    )
    problems = check_scenario(path)
    assert [str(p) for p in problems] == [f"{path}:10: nodes.a.tasks[1].period: unknown unit 'usec'; did you mean 'us'?"]
    fixed = path.read_text().replace("1 usec", "20 ms")
    path.write_text(fixed)
    tasks = load_scenario(path).nodes["a"].tasks
    assert [(t.name, t.priority, t.execution) for t in tasks] == [("t1", 1, 1_000_000), ("t2", 1, 1_000_000)]
    assert format_path(["nodes", "a", "tasks", 1]) == "nodes.a.tasks[1]"
