"""Reproduction report of the HDD case study (``netsim report hdd``).

Runs ``scenarios/hdd_case1.yaml`` .. ``hdd_case6.yaml`` (each with its Case 1 baseline), the alternative
readings of issue 13 (interlacing wiring, Case 2 between measurements, Case 3's horizon ``h``), the runs a
reason quotes (seeds, DOB bandwidths) and the GPI sweep ``scenarios/hdd_gpi_sweep.yaml``; puts the
paper's numbers (section 5 of Cuenca et al.) beside ours and writes into ``reports/hdd/``:

* ``table.csv`` (one row per case, two for Case 2's readings ``arrival`` and ``every_period``; ours / paper /
  difference, overshoot, reason), ``readings.csv`` (every alternative-reading run), ``quoted.csv`` (every
  number the prose quotes, with the run it comes from), ``gpi.csv`` (the sweep surface), ``README.md`` and
  figures like the paper's Figs. 6-13.

The README's words and layout are data (``models/hdd_report.md``); each number of its prose is a :data:`TEXT`
placeholder filled from ``quoted.csv``, the only other digits are labels (``tests/models/test_hdd_report.py``).
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from netsim.casestudy import Quotes, Templates, fmt, md_table
from netsim.casestudy import sweep as run_study_sweep
from netsim.lazy_import import lazy_module
from netsim.registry import register
from netsim.shipped import folder as shipped_scenarios

if TYPE_CHECKING:
    import pandas as pd
else:
    pd = lazy_module("pandas")  # imported at first use: `netsim list` and `netsim docs` import this module too

__all__ = ["PAPER", "TEXT", "LABEL_PATTERNS", "Quoted", "hdd_report", "render", "overshoot_pct", "VARIANTS"]

log = logging.getLogger(__name__)

ROOT = Path(__file__).resolve().parents[1]
T = 20e-6

#: Section 5 of the paper (NaN: not printed). Ua of Cases 5-6 computed from Nca/464 (not printed).
#: ``PAPER`` (a DataFrame of these rows) is built at its first use, so importing this module imports no pandas.
_PAPER_ROWS = (
    [
        (1, 464, 464, 1.00, 1.00, 66, 3.75, np.nan, np.nan),
        (2, 250, 78, 0.54, 0.16, 35, 3.75, 0.54, 0.14),
        (3, 120, 50, 0.26, 0.10, 17, 3.75, np.nan, np.nan),
        (4, 203, 77, 0.44, 0.15, 29, 3.75, np.nan, 0.09),
        (5, 338, 231, 0.73, 231 / 464, 48, 3.75, np.nan, 0.02),
        (6, 360, 315, 0.78, 315 / 464, 53, 3.75, np.nan, 0.01),
    ],
    ["case", "Nsc", "Nca", "Uc", "Ua", "Cc_pct", "ISE", "ISEP", "NE"],
)


def __getattr__(name: str) -> Any:
    """``PAPER``: the paper's section 5 table as a DataFrame, built when first read (PEP 562)."""
    if name == "PAPER":
        return pd.DataFrame(_PAPER_ROWS[0], columns=_PAPER_ROWS[1])
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
#: Section 5.2: Case 2's computation is "a 31 percentage point decrease" from the TTS case's.
PAPER_CASE2_CC_DROP = 31
#: Fig. 5 / section 5: the thresholds the paper found optimal (delta_s = sigma_s, delta_c = sigma_c).
PAPER_OPT = {"sigma_s": 100e-7, "sigma_c": 1.32e-2}

_COLS = {"Nsc": "et.Nsc", "Nca": "et.Nca", "Uc": "et.Uc", "Ua": "et.Ua", "Cc_pct": "et.Cc", "ISE": "et.ISE",
         "ISEP": "et.ISEP", "NE": "et.NE", "GPI": "et.GPI"}

#: The headline table's reading label of a run (the shipped runs of the other cases have none).
HEADLINE_READINGS = {"case2": "arrival (default)", "case2_every": "every_period"}

CTRL = "nodes.controller.tasks[0]."
DP = CTRL + "params.design_params."
#: Overrides of the alternative readings.
OWN_INSTANT = {DP + "mrci_wiring": "own_instant"}
EVERY_PERIOD = {CTRL + "release": "periodic", CTRL + "period": "20 us", CTRL + "offset": "5 us",
                CTRL + "params.step_on": "every_period"}
STD_FRAMES_1G = {"networks.net.bitrate": "1 Gbit/s", "networks.net.max_frame_bits": 12144}
JUMBO_1G = {"networks.net.bitrate": "1 Gbit/s", "networks.net.max_frame_bits": 72144}


@dataclass(frozen=True)
class Variant:
    """One run of the report: a shipped case with overrides (and a seed)."""

    case: int
    overrides: dict
    seed: int | None = None
    label: str = ""


def _variants() -> dict[str, Variant]:
    v: dict[str, Variant] = {}
    for n in range(1, 7):
        v[f"case{n}"] = Variant(n, {}, None, "shipped")
        v[f"case{n}_own"] = Variant(n, dict(OWN_INSTANT), None, "mrci_wiring: own_instant")
    v["case2_every"] = Variant(2, dict(EVERY_PERIOD), None, "step_on: every_period")
    v["case3_h100"] = Variant(3, {DP + "h": 100, **STD_FRAMES_1G}, None, "h 100, 1 Gbit/s, standard frames")
    v["case3_jumbo1g"] = Variant(3, dict(JUMBO_1G), None, "h 464, 1 Gbit/s, jumbo frames")
    v["case3_allsent"] = Variant(3, {CTRL + "params.controller_et": False}, None, "eq (22) off")
    for s in range(2, 6):
        v[f"case5_s{s}"] = Variant(5, {}, s, f"seed {s}")
        v[f"case6_s{s}"] = Variant(6, {}, s, f"seed {s}")
    for s in (1, 2):
        v[f"case6_bw300_s{s}"] = Variant(6, {DP + "dob_bandwidth": 300.0}, s, f"DOB 300 Hz, seed {s}")
        v[f"case6_bw2000_s{s}"] = Variant(6, {DP + "dob_bandwidth": 2000.0}, s, f"DOB 2 kHz, seed {s}")
        v[f"case6_nodob_s{s}"] = Variant(6, {DP + "dob": False}, s, f"no DOB, seed {s}")
    return v


VARIANTS = _variants()


# ------------------------------------------------------------------------------------------ prose
#: The report's templates (``models/hdd_report.md``): the README's layout (``readme``, ``readme_gpi``) and the
#: prose (:data:`TEXT`), whose numbers are all ``{placeholder}``s filled from the quoted values; the only digits
#: allowed in the prose are labels matching :data:`LABEL_PATTERNS`.
TEMPLATES = Templates(Path(__file__).with_suffix(".md"))
TEXT: dict[str, str] = {k: v for k, v in TEMPLATES.items() if not k.startswith(("readme", "gpi_why", "gpi_edge",
                                                                                     "gpi_inside"))}

#: Digits a template may hold (labels, not results).
LABEL_PATTERNS = (
    r"eqs? \(\d+\)", r"\(\d+\)", r"Cases? \d", r"Figs?\. \d+", r"[Ss]ection \d+(\.\d+)*", r"\b[A-Za-z]\d\b",
    r"`scenarios/[a-z0-9_]+\.yaml`", r"z\^-\(i-1\)", r"y\^2", r"t = 0", r"m j \+ i - 1", r"u_gap_max - 1", r"1 - CS", r"Cs_i", r"->",
)


#: The quoted numbers of the prose (``key, value, text, source``; a value without a format prints ``.3g``).
Quoted = Quotes


def render(key: str, texts: dict[str, str]) -> str:
    """Template ``key`` of :data:`TEMPLATES` filled with ``texts`` (a missing value is an error naming it)."""
    return TEMPLATES.fill(key, texts)


# ------------------------------------------------------------------------------------------ runs
def overshoot_pct(res) -> float:
    """``100 (max y - r_end) / r_end`` over the run (recorded ``y`` and ``r``)."""
    s = res.signals
    y = s["y"].to_numpy(float)
    r_end = float(s["r"].dropna().iloc[-1])
    return float(100.0 * (np.nanmax(y) - r_end) / r_end)


def _run_variants(names) -> dict[str, Any]:
    from netsim.runner import run

    out = {}
    for name in names:
        v = VARIANTS[name]
        res = run(shipped_scenarios() / f"hdd_case{v.case}.yaml", write=False, overrides=v.overrides or None,
                  seed=v.seed)
        if res.meta.get("status") != "ok":
            log.warning("%s: %s", name, res.meta.get("error"))
        out[name] = res
    return out


def _metric(res, key: str) -> float:
    m = res.metrics
    return float(m[key]) if key in m else float("nan")


def _row(res) -> dict[str, float]:
    out = {col: _metric(res, key) for col, key in _COLS.items()}
    out["OS_pct"] = overshoot_pct(res)
    for key in ("et.N_max", "et.played_past_packet", "et.u_gap_max"):
        out[key.split(".", 1)[1]] = _metric(res, key)
    out["ctrl_jobs"] = float((res.jobs["task"] == "control").sum()) if len(res.jobs) else float("nan")
    msgs = res.messages
    u = msgs[msgs["tag"] == "u"]
    out["u_delay_max_us"] = float(u["delay_s"].max() * 1e6) if len(u) else float("nan")
    return out


def _scenario_value(case: int, path: str) -> Any:
    """A value of the shipped scenario file (dotted path with ``[i]`` indices)."""
    import yaml

    node: Any = yaml.safe_load((shipped_scenarios() / f"hdd_case{case}.yaml").read_text())
    for part in re.findall(r"[^.\[\]]+|\[\d+\]", path):
        node = node[int(part[1:-1])] if part.startswith("[") else node[part]
    return node


def _run_gpi(workers: int | None, sweep: str = "hdd_gpi_sweep", folder: str = "gpi",
             runs: Path = Path("reports") / "hdd" / "runs") -> tuple[pd.DataFrame, dict]:
    """Run (or resume, in ``<runs>/<folder>``: the report's own ``runs/``) a GPI sweep; return its summary and
    run facts."""
    res = run_study_sweep(shipped_scenarios() / f"{sweep}.yaml", Path(runs) / folder,
                          workers=workers, complete=False)  # a point without a result: NaN on the surface
    summ = res.summary
    keep = [c for c in ("sigma_s", "sigma_c", "et.GPI", "et.Uc", "et.Ua", "et.NE", "et.Nsc", "et.Nca", "et.N_max",
                        "et.played_past_packet", "et.u_gap_max", "status") if c in summ.columns]
    return summ[keep], {"wall_s": res.wall_time_s, "workers": workers, "executed": res.n_executed,
                        "resumed": res.n_resumed}


# ------------------------------------------------------------------------------------------ numbers
def off_text(row: dict[str, float], paper: Any, cols: tuple[str, ...] = ("Nsc", "Nca", "ISEP", "NE")) -> str:
    """How far ``row`` is from the paper's values, per column: e.g. ``"Nsc +46 %, NE -8.1 %"``.

    Relative differences ``100 (ours - paper) / paper``; one decimal below 10 %, none above.
    """
    parts = []
    for c in cols:
        d = 100.0 * (float(row[c]) - float(paper[c])) / float(paper[c])
        parts.append(f"{c} {d:+.0f} %" if abs(d) >= 10 else f"{c} {d:+.1f} %")
    return ", ".join(parts)


def _dirword(new: float, old: float) -> str:
    return "rises" if new > old else ("falls" if new < old else "is unchanged")


def _plain_c_ise() -> float:
    """ISE over 464 samples of the ideal loop with the plain C(z) (MRCI with m = 1: no interlacing)."""
    from netsim.models.hdd import hdd_model
    from netsim.control import ControlSide, MrciController, TimeTriggered, decompose, simulate_loop

    m = hdd_model()
    side = ControlSide(MrciController(decompose(m.controller_num, m.controller_den, m=1, n_slow=1)), lambda k: 1.0)
    tr = simulate_loop(m.Ap, m.Bp, m.Cp, side, TimeTriggered(), 464, reference=lambda k: 1.0)
    return float(np.sqrt(np.sum((1.0 - tr.y) ** 2)))


def _quote(rows: dict[str, dict], gpi: pd.DataFrame | None, gpi_meta: dict, gpi4: pd.DataFrame | None = None,
           gpi4_meta: dict | None = None) -> Quoted:
    q = Quoted()
    P = __getattr__("PAPER").set_index("case")
    for n in range(1, 7):
        for col in ("Nsc", "Nca"):
            q.add(f"p{n}_{col}", P.loc[n, col], "d", "paper section 5")
        for col in ("Uc", "Ua", "ISE", "ISEP", "NE"):
            if not np.isnan(P.loc[n, col]):
                q.add(f"p{n}_{col}", P.loc[n, col], ".3g", "paper section 5")

    def m(key, name, col, fmt=".3g"):
        q.add(key, rows[name][col], fmt, f"{name}:{col}")

    for n in range(1, 7):
        for col, fmt in (("Nsc", "d"), ("Nca", "d"), ("Uc", ".3g"), ("Ua", ".3g"), ("ISE", ".3g"), ("ISEP", ".3g"),
                         ("NE", ".2g"), ("OS_pct", ".3g"), ("GPI", ".3g")):
            m(f"c{n}_{col if col != 'OS_pct' else 'OS'}", f"case{n}", col, fmt)
    m("c1own_ISE", "case1_own", "ISE")
    m("c1own_OS", "case1_own", "OS_pct")
    q.add("plainC_ISE", _plain_c_ise(), ".3g", "numpy loop, C(z) of eq (33)")
    # Case 2
    for col, fmt in (("Nsc", "d"), ("Nca", "d"), ("ISEP", ".3g"), ("NE", ".2g"), ("ctrl_jobs", "d")):
        m(f"c2ev_{col if col != 'ctrl_jobs' else 'jobs'}", "case2_every", col, fmt)
    ev, ar = rows["case2_every"], rows["case2"]

    def dist(r):
        return sum(abs(r[c] - P.loc[2, c]) / P.loc[2, c] for c in ("Nsc", "Nca", "ISEP", "NE"))

    q.add("c2_closer", "closer to" if dist(ev) < dist(ar) else "farther from", source="case2_every vs case2")
    q.add("c2_off", off_text(ar, P.loc[2]), source="case2 vs paper section 5.2 (Nsc, Nca, ISEP, NE)")
    q.add("c2ev_off", off_text(ev, P.loc[2]), source="case2_every vs paper section 5.2 (Nsc, Nca, ISEP, NE)")
    q.add("p2_Cc", P.loc[2, "Cc_pct"], "d", "paper section 5.2")
    q.add("p2_Ccdrop", PAPER_CASE2_CC_DROP, "d", "paper section 5.2")
    m("c1_Cc", "case1", "Cc_pct", ".3g")
    from netsim.metrics.et import controller_computation

    q.add("c2ev_Cc", ev["Cc_pct"], ".3g", "case2_every:et.Cc (eq 28)")
    q.add("c2ev_Ccjobs", controller_computation(ev["ctrl_jobs"] / 464, 2, 1), ".3g",
          "case2_every: jobs / N_TTS in eq (28)")
    q.add("ev_offset", 5, "d", "EVERY_PERIOD overrides")
    # Case 3
    q.add("c3_h", _scenario_value(3, "nodes.controller.tasks[0].params.design_params.h"), "d", "hdd_case3.yaml")
    m("c3_gap", "case3", "u_gap_max", "d")
    m("c3_past", "case3", "played_past_packet", "d")
    m("c3_Nmax", "case3", "N_max", "d")
    q.add("c3h_h", VARIANTS["case3_h100"].overrides[DP + "h"], "d", "case3_h100 overrides")
    m("c3h_gap", "case3_h100", "u_gap_max", "d")
    m("c3h_past", "case3_h100", "played_past_packet", "d")
    m("c3h_NE", "case3_h100", "NE", ".2g")
    m("c3j_NE", "case3_jumbo1g", "NE", ".2g")
    m("c3j_delay", "case3_jumbo1g", "u_delay_max_us", ".3g")
    q.add("c3_bits", 32 * (int(q.rows["c3_h"][0]) + 1), "d", "32 bits x (h + 1)")
    q.add("jumbo_bits", _scenario_value(3, "networks.net.max_frame_bits"), "d", "hdd_case3.yaml")
    q.add("std_bits", STD_FRAMES_1G["networks.net.max_frame_bits"], "d", "netsim/network/ethernet.py default")
    q.add("c3_rate", float(str(_scenario_value(3, "networks.net.bitrate")).split()[0]), "g", "hdd_case3.yaml")
    q.add("slow_rate", float(str(JUMBO_1G["networks.net.bitrate"]).split()[0]), "g", "case3_jumbo1g overrides")
    q.add("T_us", T * 1e6, "g", "T")
    # Cases 4-5
    q.add("noise_std", _scenario_value(4, "io.ys.noise_std"), "g", "hdd_case4.yaml")
    q.add("w_var", _scenario_value(4, "plant.params.w_var"), "g", "hdd_case4.yaml")
    q.add("c4_dir", _dirword(rows["case4"]["Uc"], rows["case3"]["Uc"]), source="case4 vs case3")
    for col in ("Uc", "Ua", "NE"):
        q.add(f"c5_dir{col}", {"rises": "up", "falls": "down"}.get(_dirword(rows["case5"][col], rows["case4"][col]),
                                                                   "unchanged"), source="case5 vs case4")
    q.add("c5_vs", "above" if rows["case5"]["Uc"] > P.loc[5, "Uc"] else "below", source="case5 vs paper")
    ss = float(_scenario_value(5, "nodes.sensor.handlers[0].params.sigma_s"))
    ds = float(_scenario_value(5, "nodes.sensor.handlers[0].params.delta_s"))
    thr = float(np.sqrt(ds + ss * 1.0))
    q.add("c5_thr", thr, ".2g", "sqrt(delta_s + sigma_s) of hdd_case5.yaml")
    q.add("c5_thr_vs", "below" if thr < float(q.rows["noise_std"][0]) else "above", source="threshold vs noise")
    # Case 6
    q.add("dob_bw", 1000.0, "g", "netsim.models.hdd.HddControlParams.dob_bandwidth default")
    q.add("dob_dc", 1e-2, "g", "netsim.models.hdd.HddControlParams.dob_dc_error default")
    seeds = range(1, 6)
    ne6 = [rows["case6" if s == 1 else f"case6_s{s}"]["NE"] for s in seeds]
    ne5 = [rows["case5" if s == 1 else f"case5_s{s}"]["NE"] for s in seeds]
    q.add("seed_lo", 1, "d", "seeds run")
    q.add("seed_hi", 5, "d", "seeds run")
    for key, vals, src in (("c6_NE", ne6, "case6, case6_s2..5"), ("c5_NE", ne5, "case5, case5_s2..5")):
        q.add(f"{key}_lo", min(vals), ".2g", src + ":NE min")
        q.add(f"{key}_hi", max(vals), ".2g", src + ":NE max")
    q.add("bw_a", 300, "d", "case6_bw300 overrides")
    q.add("bw_b", 2000, "d", "case6_bw2000 overrides")
    q.add("s_lo", 1, "d", "seeds run")
    q.add("s_hi", 2, "d", "seeds run")
    for tag, pre in (("bw300", "bwa"), ("bw2000", "bwb"), ("nodob", "nodob")):
        vals = [rows[f"case6_{tag}_s{s}"]["NE"] for s in (1, 2)]
        q.add(f"{pre}_NE_lo", min(vals), ".2g", f"case6_{tag}_s1..2:NE min")
        q.add(f"{pre}_NE_hi", max(vals), ".2g", f"case6_{tag}_s1..2:NE max")
        if tag != "nodob":
            ua = [rows[f"case6_{tag}_s{s}"]["Ua"] for s in (1, 2)]
            q.add(f"{pre}_Ua", float(np.mean(ua)), ".2g", f"case6_{tag}_s1..2:Ua mean")
    if gpi is not None:
        _quote_gpi(q, gpi, gpi_meta)
    if gpi4 is not None:
        _quote_gpi(q, gpi4, gpi4_meta or {}, "gpi4")
    return q


def _quote_gpi(q: Quoted, gpi: pd.DataFrame, meta: dict, pre: str = "gpi") -> None:
    """Quoted values of one GPI sweep (keys ``<pre>_...``)."""

    ok = gpi.dropna(subset=["et.GPI"])
    xs, ys = np.sort(ok["sigma_s"].unique()), np.sort(ok["sigma_c"].unique())
    best = ok.iloc[ok["et.GPI"].argmin()]  # the row of the smallest GPI (its index is unique)
    i, j = int(np.searchsorted(xs, best["sigma_s"])), int(np.searchsorted(ys, best["sigma_c"]))
    q.add(f"{pre}_n", len(gpi), "d", f"{pre}.csv rows")
    q.add(f"{pre}_wall", meta.get("wall_s", float("nan")), ".0f", "wall time of the sweep in this report run")
    q.add(f"{pre}_exec", meta.get("executed", 0), "d", "points run in this report run")
    q.add(f"{pre}_res", meta.get("resumed", 0), "d", "points resumed")
    q.add(f"{pre}_NE_lo", ok["et.NE"].min(), ".2g", f"{pre}.csv min et.NE")
    q.add(f"{pre}_NE_hi", ok["et.NE"].max(), ".2g", f"{pre}.csv max et.NE")
    q.add(f"{pre}_workers", meta.get("workers") or 0, "d", "workers")
    q.add(f"{pre}_min", best["et.GPI"], ".3g", f"{pre}.csv min et.GPI")
    q.add(f"{pre}_ss", best["sigma_s"], ".2g", f"{pre}.csv argmin sigma_s")
    q.add(f"{pre}_sc", best["sigma_c"], ".3g", f"{pre}.csv argmin sigma_c")
    q.add(f"{pre}_i", i, "d", "index of sigma_s level")
    q.add(f"{pre}_j", j, "d", "index of sigma_c level")
    q.add("p_ss", PAPER_OPT["sigma_s"], ".2g", "paper section 5")
    q.add("p_sc", PAPER_OPT["sigma_c"], ".3g", "paper section 5")
    near = ok.loc[(np.abs(np.log10(ok["sigma_s"] / PAPER_OPT["sigma_s"])) < 1e-6)
                  & (np.abs(np.log10(ok["sigma_c"] / PAPER_OPT["sigma_c"])) < 1e-3)]
    q.add(f"{pre}_at_paper", float(near["et.GPI"].iloc[0]) if len(near) else float("nan"), ".3g",
          f"{pre}.csv at the paper's thresholds")
    w = (0.45, 0.45, 0.1)
    terms = {"W1 Uc": w[0] * best["et.Uc"], "W2 Ua": w[1] * best["et.Ua"], "W3 NE": w[2] * best["et.NE"]}
    q.add(f"{pre}_t1", terms["W1 Uc"], ".3g", "0.45 x et.Uc at the minimum")
    q.add(f"{pre}_t2", terms["W2 Ua"], ".3g", "0.45 x et.Ua at the minimum")
    q.add(f"{pre}_t3", terms["W3 NE"], ".3g", "0.1 x et.NE at the minimum")
    q.add(f"{pre}_dom", max(terms, key=terms.__getitem__), source="largest term")
    q.add("w3", w[2], "g", "hdd_gpi_sweep.yaml weights")
    ne_share = float(w[2] * ok["et.NE"].max() / max(best["et.GPI"], 1e-300))
    if "et.played_past_packet" in ok.columns:
        q.add(f"{pre}_past_n", int((ok["et.played_past_packet"] > 0).sum()), "d",
              f"{pre}.csv points with et.played_past_packet > 0")
    q.add(f"{pre}_why", render("gpi_why_transmissions" if ne_share < 1.0 else "gpi_why_balance", {}),
          source="W3 max NE vs GPI minimum")
    edge = [axis for axis, k, n in (("sigma_s", i, len(xs)), ("sigma_c", j, len(ys))) if k in (0, n - 1)]
    q.add(f"{pre}_edge", render("gpi_edge", {"axes": " and ".join(edge)}) if edge else render("gpi_inside", {}),
          source="grid edges")


# ------------------------------------------------------------------------------------------ output
def _table(rows: dict[str, dict], texts: dict[str, str]) -> pd.DataFrame:
    out = []
    P = __getattr__("PAPER").set_index("case")
    runs = [(n, f"case{n}") for n in range(1, 7)]
    runs.insert(2, (2, "case2_every"))
    for n, run in runs:
        r = rows[run]
        row: dict[str, Any] = {"case": n, "reading": HEADLINE_READINGS.get(run, "")}
        for col in _COLS:
            row[f"{col}_ours"] = r[col]
            if col in P.columns:
                row[f"{col}_paper"] = float(P.loc[n, col])
                row[f"{col}_diff"] = r[col] - float(P.loc[n, col])
        row["OS_pct_ours"] = r["OS_pct"]
        for k in ("N_max", "played_past_packet", "u_gap_max"):
            row[k] = r[k]
        row["reason"] = render("reason2ev" if run == "case2_every" else f"reason{n}", texts)
        out.append(row)
    return pd.DataFrame(out)


def _readings(rows: dict[str, dict]) -> pd.DataFrame:
    keep = ["Nsc", "Nca", "Uc", "Ua", "ISE", "ISEP", "NE", "GPI", "OS_pct", "N_max", "played_past_packet",
            "u_gap_max", "ctrl_jobs", "u_delay_max_us"]
    return pd.DataFrame([{"run": k, "case": VARIANTS[k].case, "variant": VARIANTS[k].label,
                          **{c: rows[k][c] for c in keep}} for k in rows])


def _reading(r: Any) -> str:
    """The reading label of a headline-table row (empty for the shipped runs; NaN after a CSV round trip)."""
    v = r.get("reading", "")
    return v if isinstance(v, str) else ""


def _fmt(v: Any) -> str:
    """A table cell: a float with 3 significant digits (empty when NaN), anything else as it prints."""
    return fmt(v, missing="") if isinstance(v, (float, np.floating)) else str(v)


def _md_table(df: pd.DataFrame, cols: list[str]) -> list[str]:
    return md_table(df, cols, cell=_fmt)


def _readme(table: pd.DataFrame, readings: pd.DataFrame, texts: dict[str, str], figs: list[str],
            has_gpi: bool) -> str:
    from netsim.figure_style import current_format

    cols = ["Nsc", "Nca", "Uc", "Ua", "Cc_pct", "ISE", "ISEP", "NE"]
    head = ["| case | reading | " + " | ".join(f"{c} paper / ours" for c in cols) + " | overshoot % |",
            "|---" * (len(cols) + 3) + "|"]
    for _, r in table.iterrows():
        cells = [f"{_fmt(r.get(c + '_paper', np.nan))} / {_fmt(r[c + '_ours'])}" for c in cols]
        head.append(f"| {int(r['case'])} | {_reading(r)} | " + " | ".join(cells) + f" | {_fmt(r['OS_pct_ours'])} |")
    reasons = [f"- **Case {int(r['case'])}" + (f", {_reading(r)}" if _reading(r) else "") + f"**: {r['reason']}"
               for _, r in table.iterrows()]
    wir = readings[readings["run"].str.fullmatch(r"case\d(_own)?")].copy()
    wir["wiring"] = np.where(wir["run"].str.endswith("_own"), "own_instant", "delayed (default)")
    c2 = readings[readings["run"].isin(["case2", "case2_every"])].copy()
    c2["reading"] = c2["run"].map(HEADLINE_READINGS)
    c3 = readings[readings["run"].isin(["case3", "case3_h100", "case3_jumbo1g", "case3_allsent"])].copy()
    c3["variant"] = np.where(c3["run"] == "case3", "shipped (h 464, 10 Gbit/s, jumbo)", c3["variant"])
    blocks = {
        "headline_table": head, "reasons": reasons,
        "wiring_table": _md_table(wir.sort_values(["case", "wiring"]), ["case", "wiring", "ISE", "OS_pct", "Nsc",
                                                                        "Nca", "NE"]),
        "case2_table": _md_table(c2, ["reading", "Nsc", "Nca", "Uc", "Ua", "ISEP", "NE", "ctrl_jobs"]),
        "case3_table": _md_table(c3, ["variant", "N_max", "u_gap_max", "played_past_packet", "u_delay_max_us", "Nsc",
                                      "Nca", "NE"]),
        "figures": ["", *(f"![{f}]({f})" for f in figs)] if figs else []}
    all_texts = {**texts, **{k: "\n".join(v) for k, v in blocks.items()}, "fig_format": current_format()}
    all_texts.update({k: render(k, all_texts) for k in ("wiring", "case2", "case3", "gpi", "gpi4") if has_gpi
                      or not k.startswith("gpi")})
    all_texts["gpi_section"] = "\n" + render("readme_gpi", all_texts) if has_gpi else ""
    return render("readme", all_texts) + "\n"


def collect(names=None, *, gpi: bool = True, workers: int | None = 2,
            runs: Path = Path("reports") / "hdd" / "runs"):
    """Run the variants (default: all) and the GPI sweeps; return ``(results, rows, sweeps)``.

    ``sweeps`` maps ``"gpi"`` (Case 3 base) and ``"gpi4"`` (Case 4 base) to ``(summary, run facts)``; the sweeps'
    run folders are kept (and resumed) under ``runs``.
    """
    results = _run_variants(list(VARIANTS) if names is None else names)
    rows = {k: _row(r) for k, r in results.items()}
    sweeps = {}
    if gpi:
        sweeps["gpi"] = _run_gpi(workers, runs=runs)
        sweeps["gpi4"] = _run_gpi(workers, "hdd_gpi_sweep_case4", "gpi_case4", runs=runs)
    return results, rows, sweeps


@register("report", "hdd", "HDD Cases 1-6 vs the paper: reports/hdd/README.md, table.csv and figures")
def hdd_report(out_dir: Path | None = None, plots: bool = True) -> dict[str, pd.DataFrame]:
    """Run Cases 1-6, the alternative readings and the GPI sweep; write the report (see the module docstring)."""
    from netsim.models.hdd_figures import case_figures, save_gpi_figure

    out = Path(out_dir) if out_dir is not None else Path("reports") / "hdd"
    out.mkdir(parents=True, exist_ok=True)
    results, rows, sweeps = collect(runs=out / "runs")  # with --out, the sweeps' runs go there too
    gdf, gmeta = sweeps.get("gpi", (None, {}))
    g4, g4meta = sweeps.get("gpi4", (None, {}))
    q = _quote(rows, gdf, gmeta, g4, g4meta)
    texts = q.texts()
    table = _table(rows, texts)
    readings = _readings(rows)
    table.to_csv(out / "table.csv", index=False)
    readings.to_csv(out / "readings.csv", index=False)
    q.frame().to_csv(out / "quoted.csv", index=False)
    for name, df in (("gpi", gdf), ("gpi4", g4)):
        if df is not None:
            df.to_csv(out / f"{name}.csv", index=False)
            if plots:
                save_gpi_figure(df, out, f"{name}.png", PAPER_OPT)
    figs = case_figures(results, out) if plots else []
    (out / "README.md").write_text(_readme(table, readings, texts, figs, gdf is not None))
    return {"table": table, "paper": __getattr__("PAPER"), "readings": readings, "quoted": q.frame()}
