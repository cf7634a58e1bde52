"""The unicycle report's Monte-Carlo cache is the harness's run cache, not a pickle (issue 28).

The facts go to JSON and each run's error ``e`` (what the figures need) to ``.npz``; a second report reuses them
without running, and no code of the reports loads a pickle from disk.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from netsim.models.unicycle import report as U
from netsim.models.unicycle import studies as S

ROOT = Path(__file__).resolve().parents[3]


def _fake_monte_carlo(calls):
    def run(facts, runs, workers, t):
        calls.append(runs)
        rng = np.random.default_rng(3)
        facts["qr"] = {name: {"cover_x": 0.9 + 0.01 * i, "runs": runs, "rmse_y_straight": float(rng.random())}
                       for i, name in enumerate(S.QR_SETTINGS)}
        facts["zcover"] = 0.1 + 0.2  # not exactly representable: the JSON round trip must keep every bit
        facts["printed_side"] = {"printed_cover_theta": float(rng.random()), "derived_nees": float("nan")}
        return {name: [{"e": rng.standard_normal((len(t), 3)).astype(np.float32), "m": {}} for _ in range(runs)]
                for name in S.QR_SETTINGS}
    return run


def test_monte_carlo_is_kept_as_json_and_npz_and_reused(tmp_path, monkeypatch):
    calls: list[int] = []
    monkeypatch.setattr(U, "_monte_carlo", _fake_monte_carlo(calls))
    t = np.arange(5) * 0.01
    first: dict = {}
    made = U.cached_monte_carlo(first, 3, 1, t, tmp_path)
    again: dict = {}
    kept = U.cached_monte_carlo(again, 3, 1, t, tmp_path)
    assert calls == [3]  # the second call ran nothing
    facts = ("qr", "zcover", "printed_side")
    assert set(again) == set(facts)  # no fact dropped by the cache
    # every fact kept bit for bit (NaN included: json writes it as NaN on both sides)
    assert json.dumps(again, sort_keys=True) == json.dumps({k: first[k] for k in facts}, sort_keys=True)
    for name in S.QR_SETTINGS:
        assert [r["e"].dtype for r in kept[name]] == [np.float32] * 3
        np.testing.assert_array_equal(np.stack([r["e"] for r in kept[name]]), np.stack([r["e"] for r in made[name]]))
    files = sorted(p.suffix for p in tmp_path.rglob("*") if p.is_file())
    assert files == [".json", ".npz"]
    assert U.cached_monte_carlo({}, 4, 1, t, tmp_path) and calls == [3, 4]  # another run count: another key


def test_no_report_code_loads_a_pickle():
    files = [*sorted((ROOT / "models").rglob("*.py")), ROOT / "netsim" / "casestudy.py"]
    banned = re.compile(r"pickle\.loads?\(|read_pickle\(|allow_pickle\s*=\s*True|import pickle|from pickle")
    found = [f"{f.relative_to(ROOT)}:{n}" for f in files
             for n, line in enumerate(f.read_text().splitlines(), 1) if banned.search(line)]
    assert found == []
