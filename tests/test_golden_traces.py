"""Every shipped scenario reproduces its golden trace (tests/golden/digests/<scenario>.json) byte for byte.

The digests were written by ``tests/golden/golden_traces.py`` from the runs themselves: they pin what the code
produced when the digest was taken, so that a restructuring that moves any output fails here. A change that is
meant to move an output regenerates the digest of the scenarios it moves, and its commit says why.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "golden"))
import golden_traces  # noqa: E402


def _differences(want: Any, got: Any, path: str = "") -> list[str]:
    """Human-readable leaf differences between two digests."""
    if isinstance(want, dict) and isinstance(got, dict):
        out: list[str] = []
        for key in sorted(set(want) | set(got)):
            out += _differences(want.get(key, "<missing>"), got.get(key, "<missing>"), f"{path}.{key}" if path else key)
        return out
    return [] if want == got else [f"{path}: golden {want!r}, now {got!r}"]


def test_every_shipped_scenario_has_a_golden_trace() -> None:
    names = set(golden_traces.shipped_scenarios())
    pinned = {p.stem for p in golden_traces.DIGESTS.glob("*.json")}
    assert names, "no shipped scenarios found"
    assert names == pinned, f"scenarios without a digest: {sorted(names - pinned)}; stale digests: {sorted(pinned - names)}"


@pytest.mark.parametrize("name", golden_traces.shipped_scenarios())
def test_shipped_scenario_reproduces_its_golden_trace(name: str) -> None:
    want = json.loads(golden_traces.digest_path(name).read_text(encoding="utf-8"))
    got = golden_traces.run_and_digest(name)
    diff = _differences(want, got)
    assert not diff, (
        f"{name}: output moved from its golden trace ({len(diff)} differences; if intended, run "
        f"`python tests/golden/golden_traces.py {name}` and say why in the commit):\n  " + "\n  ".join(diff[:40])
    )
