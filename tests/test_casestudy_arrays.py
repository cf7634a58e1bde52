"""RunCache keeps arrays beside its JSON rows as ``.npz``, read back without unpickling (issue 28)."""

from __future__ import annotations

import numpy as np
import pytest

from netsim.casestudy import RunCache


@pytest.mark.parametrize("on_disk", [True, False])
def test_arrays_round_trip_under_a_key(tmp_path, on_disk):
    cache = RunCache(tmp_path if on_disk else None, "abc")
    assert cache.get_arrays("k") is None
    e = np.arange(12, dtype=np.float32).reshape(2, 3, 2) / 7
    cache.put_arrays("k", {"e0": e, "n": np.array([1, 2])})
    got = RunCache(tmp_path, "abc").get_arrays("k") if on_disk else cache.get_arrays("k")
    assert got is not None and sorted(got) == ["e0", "n"]
    np.testing.assert_array_equal(got["e0"], e)
    assert got["e0"].dtype == np.float32
    if on_disk:
        assert [p.name for p in (tmp_path / "abc").iterdir()] == ["k.npz"]
        assert RunCache(tmp_path, "other").get_arrays("k") is None  # another code fingerprint: another folder


def test_arrays_of_objects_are_not_read_back(tmp_path):
    cache = RunCache(tmp_path, "abc")
    (tmp_path / "abc").mkdir()
    np.savez(tmp_path / "abc" / "k.npz", o=np.array([{"a": 1}], dtype=object))  # would need unpickling
    assert cache.get_arrays("k") is None
