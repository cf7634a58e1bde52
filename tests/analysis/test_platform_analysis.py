"""`netsim analyze` on nodes with speed scaling, several cores, bandwidth servers and a schedule table
(netsim.analysis.platform): each bound beside a number worked out by hand in the comment."""

from __future__ import annotations

import copy
from fractions import Fraction
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

import netsim
from netsim.analysis.platform import gfb_test
from netsim.analysis.rta import RTATask, edf_schedulable
from netsim.cli.analyze import analyze_run
from netsim.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[2]
MS = 1_000_000


def _table(source: Any) -> pd.DataFrame:
    scenario = load_scenario(source)
    return analyze_run(scenario, netsim.run(scenario)).set_index(["kind", "name"])


# ------------------------------------------------------------------ speed scaling
def test_dvs_speed_bounds_stretch_by_the_slowest_speed() -> None:
    table = _table(ROOT / "scenarios" / "dvs_speed.yaml")
    # full: 2 ms at speed 1 -> 2 ms. half: 2 ms / 0.5 = 4 ms. governed: speed 1, its governor sets 1 and 0.5,
    # so the slowest speed is 0.5: 2 / 0.5 = 4 ms (the jobs after 50 ms take exactly that). Before: 2, 2, 2 ms and
    # two EXCEEDS rows.
    assert table.loc[("task", "full.load"), "analysis"] == pytest.approx(2.0)
    assert table.loc[("task", "half.load"), "analysis"] == pytest.approx(4.0)
    assert table.loc[("task", "governed.load"), "analysis"] == pytest.approx(4.0)
    assert table.loc[("task", "half.load"), "simulated"] == pytest.approx(4.0)
    assert "s = 0.5" in table.loc[("task", "governed.load"), "note"]
    assert not (table["verdict"] == "EXCEEDS").any()


def test_speed_stretches_the_interference_of_more_urgent_tasks() -> None:
    raw = {"name": "slow_rta", "duration": "60 ms", "nodes": {"cpu": {
        "policy": "fp", "speed": 0.5, "tasks": [
            {"name": "hi", "program": "idle", "period": "5 ms", "execution": "1 ms", "priority": 1},
            {"name": "lo", "program": "idle", "period": "20 ms", "execution": "3 ms", "priority": 2}]}}}
    table = _table(raw)
    # at speed 0.5: C_hi = 2 ms, C_lo = 6 ms. R_hi = 2. R_lo: w = 6 + ceil(w/5) * 2: w0 = 6 -> 6 + 2*2 = 10 ->
    # 10 + 2*2 = 10: R_lo = 10 ms. (At speed 1 the code before gave 1 and 4 ms, below the run's 2 and 10 ms.)
    assert table.loc[("task", "cpu.hi"), "analysis"] == pytest.approx(2.0)
    assert table.loc[("task", "cpu.lo"), "analysis"] == pytest.approx(10.0)
    assert table.loc[("task", "cpu.lo"), "simulated"] == pytest.approx(10.0)  # synchronous start: the critical instant


# ------------------------------------------------------------------ several cores
def test_dhall_set_is_not_shown_schedulable_under_global_edf_and_partitions_pass() -> None:
    table = _table(ROOT / "scenarios" / "multicore_dhall.yaml")
    row = table.loc[("node", "global_edf")]
    # GFB on m = 2 with migration_cost 0.1 ms per release of another task within D (ceil(D/T) + 1 each):
    # tau1, tau2: D = 10, others T = 10, 11 -> 2 + 2 = 4 moves: C = 2.4 ms, density 0.24;
    # tau3: D = 11, others T = 10, 10 -> 3 + 3 = 6 moves: C = 10.6 ms, density 10.6/11 = 0.9636;
    # sum 1.4436 > 2 - 0.9636 = 1.0364: not shown schedulable (never "schedulable": the run misses once)
    assert row["analysis"] == "not shown schedulable"
    assert "1.44 > m - (m-1) max = 1.04" in row["note"]
    assert row["simulated"] == 1
    # partitioned: core 0 has tau1 + tau2 (U = 0.4), core 1 tau3 (U = 10/11 = 0.909): EDF with U <= 1 and D = T
    assert table.loc[("node", "partitioned_edf.core0"), "analysis"] == "schedulable"
    assert table.loc[("node", "partitioned_edf.core1"), "analysis"] == "schedulable"
    assert "U = 0.909" in table.loc[("node", "partitioned_edf.core1"), "note"]
    assert ("node", "partitioned_edf") not in table.index  # the one-core test of the whole node is gone


def test_gfb_by_hand() -> None:
    # Dhall's set without migration cost: densities 0.2, 0.2, 10/11; sum = 0.4 + 10/11 = 144/110;
    # limit 2 - 10/11 = 12/11 = 120/110 < 144/110
    dhall = [RTATask("a", 2 * MS, 10 * MS), RTATask("b", 2 * MS, 10 * MS), RTATask("c", 10 * MS, 11 * MS)]
    assert gfb_test(dhall, 2) == (False, Fraction(144, 110), Fraction(12, 11))
    # four tasks of density 0.25 on 2 cores: sum 1 <= 2 - 0.25 = 1.75
    light = [RTATask(f"t{i}", 1 * MS, 4 * MS) for i in range(4)]
    assert gfb_test(light, 2) == (True, Fraction(1), Fraction(7, 4))


def test_partitioned_fp_is_one_rta_per_core_with_handlers_on_core_0() -> None:
    raw = {"name": "two_cores_fp", "duration": "40 ms", "nodes": {"cpu": {
        "policy": "fp", "cores": 2, "multicore": "partitioned", "tasks": [
            {"name": "a", "program": "idle", "period": "4 ms", "execution": "2 ms", "priority": 1, "core": 0},
            {"name": "b", "program": "idle", "period": "8 ms", "execution": "3 ms", "priority": 2, "core": 0},
            {"name": "c", "program": "idle", "period": "8 ms", "execution": "3 ms", "priority": 3, "core": 1}],
        "handlers": [{"name": "isr", "program": "idle", "execution": "0.5 ms",
                      "trigger": {"timer": {"period": "8 ms"}}}]}}}
    table = _table(raw)
    # core 0 (with the handler, 0.5 ms per 8 ms, above every task): R_a: w = 2 + ceil(w/8)*0.5: 2 -> 2.5 -> 2.5;
    # R_b: w = 3 + ceil(w/4)*2 + ceil(w/8)*0.5: 3 -> 5.5 -> 7.5 -> 7.5 ms. core 1: c alone, R_c = 3 ms.
    # (The old code's one-core RTA put c below a, b and the handler: level load 1/16 + 2/4 + 3/8 + 3/8 > 1,
    # "unbounded".)
    assert table.loc[("task", "cpu.a"), "analysis"] == pytest.approx(2.5)
    assert table.loc[("task", "cpu.b"), "analysis"] == pytest.approx(7.5)
    assert table.loc[("task", "cpu.b"), "simulated"] == pytest.approx(7.5)  # all released at 0: the critical instant
    assert table.loc[("task", "cpu.c"), "analysis"] == pytest.approx(3.0)
    assert "core 1" in table.loc[("task", "cpu.c"), "note"]
    assert not (table["verdict"] == "EXCEEDS").any()


def test_global_fixed_priorities_by_the_bertogna_cirinei_test() -> None:
    raw = {"name": "global_fp", "duration": "40 ms", "nodes": {"cpu": {
        "policy": "fp", "cores": 2, "tasks": [
            {"name": "a", "program": "idle", "period": "4 ms", "execution": "2 ms", "priority": 1},
            {"name": "b", "program": "idle", "period": "8 ms", "execution": "3 ms", "priority": 2},
            {"name": "c", "program": "idle", "period": "8 ms", "execution": "4 ms", "priority": 3}]}}}
    table = _table(raw)
    # m = 2; R is a bound when C + floor(sum_i min(W_i(R), R - C + 1 ns) / 2) <= R, tried at C, C + 1 ms, ...
    # a: no more urgent task, R_a = 2 ms. b: W_a(3 ms) = 2 ms, min(2 ms, 1 ns) = 1 ns, floor(1/2) = 0: R_b = 3 ms.
    # c (C = 4): R = 4: 4 ms + floor((1 + 1 ns)/2) = 4 ms + 1 ns > 4 ms. R = 5: W_a = 2 + min(2, 1) = 3 ms,
    # W_b = 3 ms, both capped at 1 ms + 1 ns: 4 + 1 ms + 1 ns > 5. R = 6: caps 2 ms + 1 ns: 6 ms + 1 ns > 6.
    # R = 7: W_a = 2 + min(2, 3) = 4 ms -> 3 ms + 1 ns, W_b = 3 ms: floor((6 ms + 1 ns)/2) = 3 ms: 7 <= 7: R_c = 7 ms.
    # (The old code applied the one-core RTA: R_c unbounded, level load 2/4 + 3/8 + 4/8 > 1.) The run: a takes
    # core 1 at 4 ms (idle), c runs 2-6 ms on core 0: 6 ms <= 7.
    assert table.loc[("task", "cpu.a"), "analysis"] == pytest.approx(2.0)
    assert table.loc[("task", "cpu.b"), "analysis"] == pytest.approx(3.0)
    assert table.loc[("task", "cpu.c"), "analysis"] == pytest.approx(7.0)
    assert table.loc[("task", "cpu.c"), "simulated"] == pytest.approx(6.0)
    assert "Bertogna & Cirinei" in table.loc[("task", "cpu.c"), "note"]


def test_dhalls_set_under_global_fp_gets_no_bound_for_the_long_task() -> None:
    raw = load_scenario(ROOT / "scenarios" / "multicore_dhall.yaml").model_dump(mode="json", exclude_none=True)
    node = {**raw["nodes"]["global_edf"], "policy": "fp"}
    node["tasks"] = [{**t, "priority": p} for t, p in zip(node["tasks"], (1, 2, 3))]
    raw["nodes"] = {"global_fp": node}
    table = _table(raw)
    # migration_cost 0.1 ms per release of a more urgent task within D, ceil(D/T) + 1 each:
    # tau1: none, R = C = 2 ms. tau2: 1 * (ceil(10/10) + 1) = 2 moves: C = 2.2 ms; W_1(2.2) = 2 ms capped at 1 ns,
    # floor(1/2) = 0: R = 2.2 ms. tau3: 2 * (ceil(11/10) + 1) = 6 moves: C = 10.6 ms; at R = 10.6 both caps are
    # 1 ns: 10.6 ms + 1 ns > R; the next point (1 ms grain) 11.6 ms > D = 11: no bound (the run misses at 11 ms).
    assert table.loc[("task", "global_fp.tau1"), "analysis"] == pytest.approx(2.0)
    assert table.loc[("task", "global_fp.tau2"), "analysis"] == pytest.approx(2.2)
    assert table.loc[("task", "global_fp.tau3"), "analysis"] == "n/a"
    assert not (table["verdict"] == "EXCEEDS").any()


# ------------------------------------------------------------------ servers
def test_three_servos_cbs_reserves_the_servers_bandwidth() -> None:
    table = _table(ROOT / "scenarios" / "three_servos_cbs.yaml")
    node = table.loc[("node", "cpu")]
    # pid1, pid2: 2/6 + 2/5 = 0.7333, plus the CBS's 1/4: U = 0.9833 <= 1 with D = T: schedulable, and they miss
    # nothing (the old row tested all three at U = 1.23: "not schedulable")
    assert node["analysis"] == "schedulable"
    assert "U = 0.983" in node["note"]
    assert node["simulated"] == 0
    # pid3 needs 2/4 = 0.5 of the CPU in a server of 1/4: its queue grows, no bound
    assert table.loc[("task", "cpu.pid3"), "analysis"] == "unbounded"


SERVED: dict[str, Any] = {"name": "served", "duration": "120 ms", "nodes": {"cpu": {
    "policy": "edf",
    "servers": [{"name": "srv", "type": "cbs", "budget": "2 ms", "period": "5 ms"}],
    "tasks": [
        {"name": "ctl", "program": "idle", "period": "10 ms", "execution": "4 ms"},
        {"name": "aux", "program": "idle", "period": "10 ms", "execution": "2 ms", "server": "srv"}]}}}


def test_a_task_alone_in_a_cbs_is_bounded_by_the_server_period() -> None:
    table = _table(copy.deepcopy(SERVED))
    # ctl 4/10 + the CBS 2/5 = 0.8 <= 1: the server's deadlines are met. aux: C = 2 ms <= Qs = 2 ms and
    # Ts = 5 ms <= T = 10 ms: a fresh budget at each arrival, deadline r + 5 ms: R <= 5 ms (Abeni & Buttazzo)
    assert table.loc[("node", "cpu"), "analysis"] == "schedulable"
    assert table.loc[("task", "cpu.aux"), "analysis"] == pytest.approx(5.0)
    # at t = 0 the server's deadline (5 ms) precedes ctl's (10 ms): aux runs 0-2 ms
    assert table.loc[("task", "cpu.aux"), "simulated"] == pytest.approx(2.0)
    assert table.loc[("task", "cpu.aux"), "verdict"] == "ok"


def test_a_task_alone_in_a_tbs_is_bounded_by_wcet_over_us() -> None:
    raw = copy.deepcopy(SERVED)
    raw["nodes"]["cpu"]["servers"] = [{"name": "srv", "type": "tbs", "utilization": 0.25}]
    raw["nodes"]["cpu"]["tasks"][1]["wcet"] = "2 ms"
    table = _table(raw)
    # TBS: d = max(r, d_prev) + 2 / 0.25 = r + 8 ms (8 <= T = 10, so d_prev <= r): R <= 8 ms (Spuri & Buttazzo);
    # ctl 0.4 + Us 0.25 = 0.65 <= 1
    assert table.loc[("task", "cpu.aux"), "analysis"] == pytest.approx(8.0)
    # at t = 0 aux's TBS deadline (8 ms) precedes ctl's (10 ms): aux runs 0-2 ms
    assert table.loc[("task", "cpu.aux"), "simulated"] == pytest.approx(2.0)


def test_edf_demand_with_reserved_bandwidth_by_hand() -> None:
    # a task C = 3, T = 10, D = 4 beside 0.3 of bandwidth: dbf(4) + 0.3 * 4 = 3 + 1.2 = 4.2 > 4: fails;
    # with 0.2: 3 + 0.8 = 3.8 <= 4; next deadlines 14: 6 + 2.8 = 8.8 <= 14 (U = 0.5 < 1: Baruah's horizon
    # (10 - 4) * 0.3 / 0.5 = 3.6 < D = 4, so t = 4 is the only deadline checked)
    task = [RTATask("t", 3 * MS, 10 * MS, deadline=4 * MS)]
    assert not edf_schedulable(task, bandwidth=Fraction(3, 10))
    assert edf_schedulable(task, bandwidth=Fraction(1, 5))
    assert edf_schedulable(task)  # no bandwidth: the plain demand test (3 <= 4)


# ------------------------------------------------------------------ schedule table
def test_timetable_slot_bounds_a_task_that_fits_its_slot() -> None:
    table = _table(ROOT / "scenarios" / "dc_servo_timetable.yaml")
    # pid: C = 1 ms in a 2 ms slot, activated at the slot's start: R <= 2 ms (the run: 1 ms every cycle).
    # Before: a 4 ms 'sporadic' bound from the shortest gap of the run.
    assert table.loc[("task", "ecu.pid"), "analysis"] == pytest.approx(2.0)
    assert table.loc[("task", "ecu.pid"), "simulated"] == pytest.approx(1.0)
    # diag: up to 3 ms (uniform 1..3 ms) in a 2 ms slot: it can overrun, so no bound (the run: 2.967 ms)
    assert table.loc[("task", "ecu.diag"), "analysis"] == "n/a"
    assert table.loc[("task", "ecu.diag"), "simulated"] > 2.0
