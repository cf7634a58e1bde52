"""kernel.sync: the named sync objects of a node, and the parameter types that name them."""

from __future__ import annotations

import pytest

from netsim.env import SimEnv
from netsim.errors import ConfigError
from netsim.kernel import Event, Kernel, Mailbox, Monitor, Semaphore
from netsim.kernel.node_sync import MailboxName, MonitorName, SyncRef, sync_refs
from netsim.units import StrictModel


def test_lookup_by_kind_with_the_known_names_in_the_error() -> None:
    k = Kernel(SimEnv(seed=1), "n1")
    mb = k.sync.add(Mailbox("inbox", capacity=2))
    k.sync.add(Semaphore("slots", count=1))
    k.sync.add(Event("go"))
    k.sync.add(Monitor("state"))
    assert k.sync.mailbox("inbox") is mb and k.sync.semaphore("slots").count == 1
    assert k.sync.event("go").name == "go" and k.sync.monitor("state").protocol == "inherit"
    with pytest.raises(ConfigError) as err:
        k.sync.mailbox("inbx")
    assert err.value.message == ("node 'n1' has no mailbox 'inbx' (its mailboxes: inbox); did you mean 'inbox'?; "
                                 "declare it under nodes.n1.sync.mailboxes")
    with pytest.raises(ConfigError, match="it declares no events"):
        Kernel(SimEnv(seed=1), "n2").sync.event("go")
    with pytest.raises(ConfigError, match="declared twice"):
        k.sync.add(Mailbox("inbox"))
    with pytest.raises(ConfigError, match="is not a Mailbox"):
        k.sync.add("inbox")  # type: ignore[arg-type]


def test_sync_refs_finds_names_in_optional_list_and_nested_fields() -> None:
    class Inner(StrictModel):
        guard: MonitorName

    class Params(StrictModel):
        a: MailboxName
        b: MailboxName | None = None
        c: list[MailboxName] = []
        inner: Inner | None = None
        other: str = "x"

    p = Params(a="m1", c=["m2", "m3"], inner=Inner(guard="g"))
    assert list(sync_refs(p)) == [("mailboxes", "m1", ["a"]), ("mailboxes", "m2", ["c", 0]),
                                  ("mailboxes", "m3", ["c", 1]), ("monitors", "g", ["inner", "guard"])]
    with pytest.raises(ValueError, match="SyncRef kind"):
        SyncRef("queues")
