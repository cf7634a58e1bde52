"""Taking the messages a program selects out of a node's inbox, leaving the others for other programs."""

from __future__ import annotations

from collections import deque
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from netsim.network.message import Message

__all__ = ["take_matching"]


def take_matching(inbox: deque[Message], sender: str | None = None, tag: str | None = None) -> list[Message]:
    """Remove and return, in arrival order, the messages of ``inbox`` from ``sender`` with ``tag``.

    ``None`` matches any sender (any tag). The other messages stay in the inbox in their order, for the other
    programs of the node that read the same network.
    """
    taken: list[Message] = []
    if not inbox:
        return taken
    keep: list[Message] = []
    while inbox:
        msg = inbox.popleft()
        if (sender is not None and msg.sender != sender) or (tag is not None and msg.tag != tag):
            keep.append(msg)
        else:
            taken.append(msg)
    inbox.extend(keep)
    return taken
