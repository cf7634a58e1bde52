"""take_matching: the messages a program selects leave the inbox in arrival order; the others stay, in order."""

from __future__ import annotations

from collections import deque
from types import SimpleNamespace

from netsim.programs.inbox import take_matching


def _msg(sender: str, tag: str) -> SimpleNamespace:
    return SimpleNamespace(sender=sender, tag=tag)


def test_take_matching_removes_selected_messages_and_keeps_the_rest_in_order() -> None:
    a, b, c, d = _msg("s1", "y"), _msg("s2", "y"), _msg("s1", "u"), _msg("s1", "y")
    inbox = deque([a, b, c, d])
    assert take_matching(inbox, "s1", "y") == [a, d]
    assert list(inbox) == [b, c]


def test_take_matching_with_no_filter_takes_everything() -> None:
    a, b = _msg("s1", "y"), _msg("s2", "u")
    inbox = deque([a, b])
    assert take_matching(inbox) == [a, b]
    assert not inbox
