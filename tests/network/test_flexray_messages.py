"""FlexRay's refusals of a dynamic segment that cannot hold its frame IDs say what to change (fuzz figures).

The scenario of :mod:`tests.network.test_flexray`'s ``_scenario``: 2 static slots (frame IDs 1 and 2), so a
dynamic frame ID ``k`` needs at least ``k - 2`` minislots.
"""

from __future__ import annotations

from netsim.scenario.loader import check_scenario
from tests.fuzz.mutations import message_has_fix
from tests.network.test_flexray import _scenario


def _errors(raw: dict) -> list[tuple[str, str]]:
    return [(p.path, p.message) for p in check_scenario(raw) if p.severity == "error"]


def test_no_minislot_for_a_dynamic_id_asks_for_enough_minislots():
    # 2 static slots (IDs 1, 2) and no minislot: dynamic ID 3 needs 3 - 2 = 1 minislot
    errs = _errors(_scenario(minislot="5 us", minislots=0, dynamic_ids={"b": 3}))
    assert [p for p, _ in errs] == ["networks.bus.dynamic_ids"]
    message = errs[0][1]
    assert "set minislots to at least 1" in message and "no minislot" in message
    assert message_has_fix(message)


def test_too_few_minislots_for_a_dynamic_id_names_the_least_count():
    # 2 static slots; ID 9 is the 7th dynamic ID (9 - 2), so 4 minislots are too few and 7 are needed
    errs = _errors(_scenario(minislot="5 us", minislots=4, dynamic_ids={"b": 9}))
    assert [p for p, _ in errs] == ["networks.bus.dynamic_ids"]
    assert "set minislots to at least 7" in errs[0][1] and "run from 3 to 6" in errs[0][1]


def test_a_dynamic_id_at_or_below_the_static_slots_says_the_range_to_use():
    for fid in (0, -12, 2):
        errs = _errors(_scenario(minislot="5 us", minislots=10, dynamic_ids={"b": fid}))
        assert [p for p, _ in errs] == ["networks.bus.dynamic_ids"]
        assert "run from 3 to 12" in errs[0][1] and message_has_fix(errs[0][1]), errs[0][1]


def test_too_many_minislots_for_the_cycle_names_how_many_fit():
    # a 900 us cycle after 10 static slots of 50 us (500 us) holds (900 - 500) / 5 = 80 minislots of 5 us
    errs = _errors(_scenario(cycle="900 us", static_schedule=["a", "b"] + [None] * 8, minislot="5 us",
                             minislots=100))
    assert [p for p, _ in errs] == ["networks.bus.cycle"] and "at most 80 minislots" in errs[0][1]
