"""The 2WD cart reproduction report (registered as kind ``report``, name ``unicycle``): ``netsim report unicycle``.

Writes ``reports/unicycle/README.md`` (one section per experiment: what the report claims, what we measured,
why it differs), ``table.csv`` (``experiment, setting, quantity, ours, source, reason``) and figures. Every
number in the README is computed here from runs: the numpy loop for the Monte-Carlo studies with hundreds of
runs per setting (:mod:`netsim.models.unicycle.studies`), netsim scenarios and sweeps (``replicates``) for everything
with sensors, estimator and drive on their own nodes (sweep folders under ``reports/unicycle/runs/``; a second
call resumes them).
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from netsim.casestudy import RunCache, code_fingerprint, fmt, splice, sweep
from netsim.models.unicycle import studies as S
from netsim.models.unicycle.design import PHASES
from netsim.lazy_import import lazy_module
from netsim.registry import register
from netsim.shipped import folder as shipped_scenarios

if TYPE_CHECKING:
    import pandas as pd
else:
    pd = lazy_module("pandas")  # imported at first use: `netsim list` and `netsim docs` import this module too

__all__ = ["unicycle_report", "counted_runs"]

_ROOT = Path(__file__).resolve().parents[2]
_SCEN = shipped_scenarios()


class _Table:
    def __init__(self) -> None:
        self.rows: list[dict[str, Any]] = []

    def add(self, experiment: str, setting: str, quantity: str, ours: Any, source: str = "", reason: str = "") -> Any:
        from netsim.models.unicycle.quoting import Quotes

        self.rows.append({"experiment": experiment, "setting": setting, "quantity": quantity,
                          "ours": Quotes.render(ours) if isinstance(ours, str) else fmt(float(ours), 4, missing="n/a"),
                          "source": source,
                          "reason": reason})
        return ours

    def frame(self) -> pd.DataFrame:
        return pd.DataFrame(self.rows, columns=["experiment", "setting", "quantity", "ours", "source", "reason"])


def counted_runs(summary: pd.DataFrame, name: str) -> pd.DataFrame:
    """Every run of sweep ``name``'s summary, each one counted: a run that diverged or ended unstable is kept and
    marked ``_failed`` (:func:`netsim.models.unicycle.readme_net.lost_runs` counts it as a lost loop; its metrics, when
    it has them, enter the means like any other run's).

    Raises
    ------
    NetsimError
        When a run gave no result (status ``error``, ``interrupted`` or ``pending``): the report would otherwise
        count fewer runs than the sweep has without saying so.
    """
    from netsim.status import DIVERGED, UNSTABLE, kind_of
    from netsim.sweep.summary import require_results

    require_results(summary, name)
    kinds = summary["status"].map(kind_of)
    out = summary.copy()
    out["_failed"] = kinds.isin([DIVERGED, UNSTABLE]).to_numpy()
    return out


def _sweep(name: str, out: Path, workers: int | None) -> pd.DataFrame:
    return counted_runs(sweep(_SCEN / f"{name}.yaml", out / "runs" / name, workers=workers).summary, name)


def unicycle_report(out_dir: Path | None = None, plots: bool = True, *, runs: int = 200, replicates_note: str = "",
                    workers: int | None = None, sweeps: bool = True, progress: Any = None) -> dict[str, pd.DataFrame]:
    """Run the studies and write ``reports/unicycle`` (or ``out_dir``); returns ``{"table": ...}``.

    Parameters
    ----------
    out_dir
        Output folder (default ``reports/unicycle``).
    plots
        Write the figures.
    runs
        Monte-Carlo runs per (Q, R) setting of the numpy loop (default 200).
    workers
        Processes for the Monte-Carlo runs and the sweeps (default: up to 4, one per CPU).
    sweeps
        Also run (or resume) the netsim sweeps ``unicycle_net_sweep``, ``unicycle_lqr_delay`` and
        ``unicycle_burst_sweep``.
    """
    import netsim

    t0 = time.perf_counter()
    out = Path(out_dir) if out_dir is not None else Path("reports") / "unicycle"
    out.mkdir(parents=True, exist_ok=True)
    T = _Table()
    from netsim.models.unicycle.readme import write_readme

    facts: dict[str, Any] = {"runs": runs}
    # ---------------------------------------------------------------- model and design facts
    facts["lqr"] = S.lqr_facts()
    facts["obs"] = {"straight": S.observability(PHASES[0], 0.0), "front": S.observability(PHASES[2], math.pi / 2)}
    facts["lqr_nf"] = S.lqr_noise_free("lqr")
    facts["lqr_ff_nf"] = S.lqr_noise_free("lqr_ff")
    facts["printed_lqr"] = S.printed_lqr_study()
    facts["delay_margin"] = {v: S.delay_margin(v) for v in (0.03, 0.02, 0.015)}
    # ---------------------------------------------------------------- netsim runs of the two scenarios
    base = netsim.run(_SCEN / "unicycle_ekf.yaml")
    lqr = netsim.run(_SCEN / "unicycle_lqr.yaml")
    facts["base"], facts["lqr_run"] = base.metrics, lqr.metrics
    facts["zigbee"] = netsim.run(_SCEN / "unicycle_zigbee.yaml").metrics
    # ---------------------------------------------------------------- Monte-Carlo (numpy loop)
    t = np.arange(int(round(10 / 0.01)) + 1) * 0.01
    qr_runs = cached_monte_carlo(facts, runs, workers, t, out / "runs")
    # ---------------------------------------------------------------- netsim sweeps
    for key, name in (("net", "unicycle_net_sweep"), ("delay", "unicycle_lqr_delay"), ("burst", "unicycle_burst_sweep"),
                      ("radio_mc", "unicycle_radio_mc"), ("radio_delay", "unicycle_radio_delay"),
                      ("qr_can", "unicycle_qr_can"), ("qr_radio", "unicycle_qr_radio"),
                      ("delay_aware_can", "unicycle_lqr_delay_aware"),
                      ("delay_aware_radio", "unicycle_radio_delay_aware")):
        facts[key] = _sweep(name, out, workers) if sweeps else None
    for key in ("qr_can", "qr_radio"):
        df = facts[key]
        facts[f"{key}_study"] = (S.net_qr_study(df, out / "runs" / f"unicycle_{key}", t)
                                 if df is not None and len(df) else None)
    facts["wall_dist"] = S.wall_distances()
    from netsim.models.unicycle.programs import UnicycleEkf

    facts["history"] = UnicycleEkf.Params.model_fields["history"].default
    speed = out / "speed.json"
    facts["speed"] = json.loads(speed.read_text()) if speed.is_file() else None
    if plots:
        from netsim.models.unicycle.figures import report_figures

        report_figures(out, base, qr_runs, t)
    facts["wall_s"] = time.perf_counter() - t0
    text = write_readme(out, T, facts)
    T.frame().to_csv(out / "table.csv", index=False)
    return {"table": T.frame(), "readme": pd.DataFrame({"text": [text]})}


@register("report", "unicycle_delay_aware",
          "2WD cart: only the delay-aware filter study (input_delay); splices its README section, quotes and rows")
def unicycle_delay_aware_report(out_dir: Path | None = None, plots: bool = True, *,
                                workers: int | None = None) -> dict[str, pd.DataFrame]:
    """Run (or resume) ``unicycle_lqr_delay_aware`` and ``unicycle_radio_delay_aware`` and write
    ``delay_aware.csv`` and the README's delay-aware section (with ``template.md``, ``quoted.csv`` and
    ``table.csv`` kept consistent: the section's quotes are ``s5da.*``, its rows ``5 delay-aware``). The rest of
    the report is left as it is (``netsim report unicycle`` runs everything, this section included)."""
    from netsim.models.unicycle.quoting import Quotes
    from netsim.models.unicycle.readme_net import DELAY_AWARE_MARK, delay_aware_frame, delay_aware_section

    out = Path(out_dir) if out_dir is not None else Path("reports") / "unicycle"
    F = {"delay_aware_can": _sweep("unicycle_lqr_delay_aware", out, workers),
         "delay_aware_radio": _sweep("unicycle_radio_delay_aware", out, workers),
         "delay_margin": {0.03: S.delay_margin(0.03)}}
    frame = delay_aware_frame(F["delay_aware_can"], F["delay_aware_radio"])
    frame.drop(columns=["values", "_failed"], errors="ignore").to_csv(out / "delay_aware.csv", index=False)
    q, T = Quotes(), _Table()
    q.section = "s5da"
    marked = "\n".join(delay_aware_section(q, T, F))
    for name, text in (("README.md", Quotes.render(marked)), ("template.md", Quotes.template(marked))):
        lines = splice((out / name).read_text().split("\n"), DELAY_AWARE_MARK, text.split("\n"),
                       "Late samples are fused")
        (out / name).write_text("\n".join(lines))
    quoted = pd.read_csv(out / "quoted.csv", keep_default_na=False, dtype={"text": str})
    quoted = pd.concat([quoted[~quoted["key"].astype(str).str.startswith("s5da.")],
                        q.frame(source=False)], ignore_index=True)
    quoted.to_csv(out / "quoted.csv", index=False)
    table = pd.read_csv(out / "table.csv", keep_default_na=False)
    table = pd.concat([table[table["experiment"] != "5 delay-aware"], T.frame()], ignore_index=True)
    table.to_csv(out / "table.csv", index=False)
    return {"delay_aware": frame, "table": T.frame()}


@register("report", "unicycle_radio_mc",
          "2WD cart: only the radio Monte-Carlo study (per-attempt loss); splices its README section, quotes and rows")
def unicycle_radio_mc_report(out_dir: Path | None = None, plots: bool = True, *,
                             workers: int | None = None) -> dict[str, pd.DataFrame]:
    """Run (or resume) ``unicycle_radio_mc`` and replace the README's radio Monte-Carlo section in place, with
    ``template.md``, ``quoted.csv`` and ``table.csv`` kept consistent
    (:func:`netsim.models.unicycle.readme_net.splice_radio_mc`); the rest of the report is left as it is (``netsim report
    unicycle`` runs everything, this section included)."""
    from netsim.models.unicycle.quoting import Quotes
    from netsim.models.unicycle.readme_net import radio_mc_section, splice_radio_mc

    out = Path(out_dir) if out_dir is not None else Path("reports") / "unicycle"
    q, T = Quotes(), _Table()
    q.section = "s5"  # the section's keys are fixed names (s5.radio_runs, s5.rm_*), the same as in the full report
    marked = radio_mc_section(q, T, {"radio_mc": _sweep("unicycle_radio_mc", out, workers)})
    splice_radio_mc(out, marked, q.frame(source=False), T.frame())
    return {"table": T.frame()}


def _code_hash() -> str:
    """Fingerprint of the study's numeric code: a cached Monte-Carlo result is reused only for the same code."""
    here = Path(__file__).parent
    return code_fingerprint(here / n for n in ("model.py", "design.py", "reference.py", "studies.py", "metrics.py"))


def cached_monte_carlo(facts: dict[str, Any], runs: int, workers: int | None, t: np.ndarray,
                       folder: Path | None) -> dict[str, list[dict]]:
    """:func:`_monte_carlo`, or its facts (JSON) and each run's error ``e`` (``.npz``) from the run cache in
    ``folder`` (:class:`netsim.casestudy.RunCache`, for this code: :func:`_code_hash`); the figures need only ``e``."""
    cache, key = RunCache(folder, _code_hash()), f"monte_carlo_{runs}_runs"
    kept, arrays = cache.get(key), cache.get_arrays(key)
    if kept is not None and arrays is not None:
        facts.update(kept)
        return {name: [{"e": e} for e in arrays[f"e{i}"]] for i, name in enumerate(S.QR_SETTINGS)}
    qr_runs = _monte_carlo(facts, runs, workers, t)
    cache.put(key, {k: facts[k] for k in ("qr", "zcover", "printed_side")})
    cache.put_arrays(key, {f"e{i}": np.stack([r["e"] for r in qr_runs[name]]) for i, name in enumerate(S.QR_SETTINGS)})
    return qr_runs


def _monte_carlo(facts: dict[str, Any], runs: int, workers: int | None, t: np.ndarray) -> dict[str, list[dict]]:
    """The Q/R study, the measurement-band coverage and the printed side-offset study (numpy loop)."""
    qr_runs: dict[str, list[dict]] = {}
    facts["qr"] = {}
    for name, (fq, fr) in S.QR_SETTINGS.items():
        from netsim.models.unicycle.model import Q_REPORT, R_REPORT

        rs = S.mc_runs(runs, seed0=10_000, workers=workers, Q_filter=fq * Q_REPORT, R_filter=fr * R_REPORT)
        qr_runs[name] = rs
        facts["qr"][name] = S.qr_study(rs, t)
        facts["qr"][name]["blackout_monotone"] = float(np.mean([r["m"]["detP_monotone_turn"] for r in rs]))
        facts["qr"][name]["detP_ratio"] = float(np.median([r["m"]["detP_ratio_turn"] for r in rs]))
        for s in ("x", "y", "theta"):
            for p in ("straight", "turn", "front"):
                facts["qr"][name][f"sd_{s}_end_{p}"] = float(np.mean([r["m"][f"sd_{s}_end_{p}"] for r in rs]))
                facts["qr"][name][f"cover_{s}_{p}"] = float(np.mean([r["m"][f"cover_{s}_{p}"] for r in rs]))
    # measurement-prediction band coverage of the actual (noisy) readings, baseline
    zc = []
    for r in qr_runs["(Q, R)"]:
        ok = ~np.isnan(r["z"])
        zc.append(np.abs(r["z"][ok] - r["zhat"][ok]) <= 1.96 * r["zsd"][ok])
    facts["zcover"] = float(np.mean(np.concatenate(zc)))
    facts["printed_side"] = S.printed_side_study(min(runs, 100), workers)
    return qr_runs
