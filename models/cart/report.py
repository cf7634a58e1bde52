"""The cart reproduction report (registered as kind ``report``, name ``cart``): ``netsim report cart``.

Runs the two studies of Henningsson & Cervin section VII through :func:`netsim.runner.run` on
``scenarios/cart.yaml`` (the points of ``cart_fig2.yaml`` and ``cart_quant.yaml``; in parallel processes),
or with ``engine="numpy"`` through the plain numpy loop :func:`netsim.models.cart.sim.simulate`, then writes
``reports/cart/``: ``fig2.csv``, ``quant.csv``, ``claims.csv``, the figures ``fig1_time.png``,
``fig2_sigma_vs_ev.png``, ``fig3_ev_vs_q.png``, ``fig4_sigma_vs_q.png`` and ``README.md`` with a verdict and
the numbers for each of the paper's claims. ``instability.csv`` holds the wc = 80 runs of every controller over
:data:`SEEDS_INSTABILITY` (the instability verdict counts its oscillating runs per controller).

Run cache (:class:`netsim.casestudy.RunCache`, :func:`run_cache`): each point's row is kept in
``<out>/runs/<code>/<engine>-<scenario hash>.json`` (not in git): the scenario hash of the point's run (the
scenario, its overrides and seed) names the row, ``<code>`` is a fingerprint of the cart's numeric modules
(:data:`NUMERIC_MODULES`), so a change there runs everything again. Only runs that ended ``ok`` are kept.
Delete the folder to force fresh runs.
"""

from __future__ import annotations

import logging
import math
import os
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from netsim.casestudy import Progress, RunCache, Templates, code_fingerprint, fmt as _fmt, run_all, scenario_key
from netsim.casestudy import log_progress as _progress_logger
from netsim.models.cart.claims import claims as make_claims
from netsim.models.cart.claims import OSC_THRESHOLD, headline, oscillating, pool_sigma, pooling_difference
from netsim.models.cart.metrics import STOP_WINDOW
from netsim.lazy_import import lazy_module
from netsim.registry import register
from netsim.shipped import scenario_path

if TYPE_CHECKING:
    import pandas as pd
else:
    pd = lazy_module("pandas")  # imported at first use: `netsim list` and `netsim docs` import this module too

__all__ = ["cart_report", "run_point", "fig2_points", "quant_points", "sensitivity_points", "instability_points",
           "FRICTIONS", "SEEDS_INSTABILITY", "run_cache", "NUMERIC_MODULES"]

log = logging.getLogger(__name__)
#: The default progress of the report: one INFO line on ``netsim.progress.cart`` every ~10 % of the runs.
log_progress = _progress_logger("netsim.progress.cart", "cart report")

_ROOT = Path(__file__).resolve().parents[2]
SCENARIO = scenario_path("cart")
CTRL = "nodes.cart.tasks[0].params"
ISR = "nodes.cart.handlers[0].params"
#: Control delay of the numpy engine: the controller's response time in the scenario, 100 us of execution
#: started after the ISR's 2 us run at the release tick and interrupted by it every 10 us (RTA: 126 us).
CONTROL_DELAY_NS = 126_000
CONTROLLERS = ("pure_pi", "observer_pi", "basic_event", "position_prediction", "full_event")
WCS = (5, 10, 20, 40, 80)
SEEDS_FIG2 = (1, 2, 3)
SEEDS_QUANT = (1, 2)
#: Friction realizations of the wc = 80 instability runs (every controller; seeds 1-3 are the Fig. 2 runs).
SEEDS_INSTABILITY = tuple(range(1, 21))
#: Friction models of the sensitivity table: label -> the scenario's ``plant.params.friction`` (``None``:
#: the scenario's own, the ``inband`` default). ``inband_10_20`` is the in-band model moved to 10-20 rad/s.
FRICTIONS: dict[str, dict[str, Any] | None] = {
    "inband": None,
    "modes6": {"model": "modes6"},
    "constant": {"model": "constant"},
    "inband_10_20": {"model": "inband", "wavelength": 1.0, "speedup": 3.0},
}
WCS_SENS = (20, 40, 80)
#: Simulated time of a run: reaching 1 m (1.9 s at most, at wc = 5) plus the stop-phase window (2 s).
DURATION_FIG2 = 4.0
#: vref = 0.4: 1 m takes ~2.6 s; the stop phase is not evaluated in the quantization study.
DURATION_QUANT = 3.2


def fig2_points(seeds: tuple[int, ...] = SEEDS_FIG2) -> list[dict[str, Any]]:
    """The Fig. 2 grid: five controllers x five crossover frequencies x friction realizations."""
    return [dict(controller=c, wc=w, q=6, vref=0.8, seed=s, friction="inband") for c in CONTROLLERS for w in WCS
            for s in seeds]


def quant_points(seeds: tuple[int, ...] = SEEDS_QUANT) -> list[dict[str, Any]]:
    """The Figs. 3-4 grid (Basic Event excluded, as in the paper)."""
    return [dict(controller=c, wc=40, q=q, vref=0.4, seed=s, friction="inband") for c in CONTROLLERS
            if c != "basic_event" for q in range(7) for s in seeds]


def sensitivity_points(seeds: tuple[int, ...] = SEEDS_FIG2) -> list[dict[str, Any]]:
    """The Fig. 2 grid at wc = 20, 40, 80 under every non-default friction model of :data:`FRICTIONS`."""
    return [dict(controller=c, wc=w, q=6, vref=0.8, seed=s, friction=f) for f in FRICTIONS if FRICTIONS[f]
            for c in CONTROLLERS for w in WCS_SENS for s in seeds]


def instability_points(seeds: tuple[int, ...] = SEEDS_INSTABILITY) -> list[dict[str, Any]]:
    """Every controller at wc = 80 (q = 6, vref = 0.8, in-band friction) over ``seeds``: the instability runs."""
    return [dict(controller=c, wc=80, q=6, vref=0.8, seed=s, friction="inband") for c in CONTROLLERS for s in seeds]


#: The cart modules whose code decides a run's numbers (the run cache's code fingerprint).
NUMERIC_MODULES = ("controllers.py", "dynamics.py", "encoding.py", "estimators.py", "friction.py", "jmap.py",
                   "metrics.py", "plant.py", "programs.py", "sim.py", "tuning.py")


def run_cache(folder: Path | None) -> RunCache:
    """The run cache of the report's points in ``folder`` (``None``: none), for this code
    (:data:`NUMERIC_MODULES` and the numpy engine's control delay)."""
    here = Path(__file__).parent
    return RunCache(folder, code_fingerprint([here / n for n in NUMERIC_MODULES], str(CONTROL_DELAY_NS)))


def _overrides(point: dict[str, Any]) -> dict[str, Any]:
    """The scenario overrides of a point (its seed is the run's seed)."""
    duration = DURATION_FIG2 if point["vref"] >= 0.6 else DURATION_QUANT
    label = point.get("friction", "inband")
    if label not in FRICTIONS:
        raise ValueError(f"unknown friction label '{label}'; use one of {', '.join(FRICTIONS)}")
    ov = {f"{CTRL}.controller": point["controller"], f"{CTRL}.wc": point["wc"], f"{CTRL}.vref": point["vref"],
          f"{ISR}.q": point["q"], "duration": f"{duration} s"}
    friction = FRICTIONS[label]
    if friction:
        ov["plant.params.friction"] = dict(friction)
    return ov


def cache_key(point: dict[str, Any], engine: str) -> str:
    """A point's run-cache key: the engine and the scenario hash of its run."""
    return f"{engine}-{scenario_key(SCENARIO, _overrides(point), point['seed'])}"


def run_point(point: dict[str, Any], engine: str = "netsim") -> dict[str, Any]:
    """Run one point; returns the point with its metrics (names without the ``cart.`` prefix) and ``cpu_s``
    (the CPU time the run took in its process)."""
    t0 = time.process_time()
    row = _run_point(point, engine)
    row["cpu_s"] = time.process_time() - t0
    return row


def _run_point(point: dict[str, Any], engine: str) -> dict[str, Any]:
    ov = _overrides(point)
    if engine == "numpy":
        from netsim.models.cart.controllers import make_controller
        from netsim.models.cart.encoding import Quantizer
        from netsim.models.cart.friction import Friction, FrictionParams
        from netsim.models.cart.metrics import cart_metrics
        from netsim.models.cart.sim import simulate

        duration = DURATION_FIG2 if point["vref"] >= 0.6 else DURATION_QUANT
        ctrl = make_controller(point["controller"], point["wc"], Quantizer.from_bits(point["q"], rounding="floor"))
        fp = FrictionParams.model_validate(ov.get("plant.params.friction", {}))
        sim = simulate(ctrl, Friction.draw(fp, seed=point["seed"]), vref=point["vref"], q=point["q"],
                       duration=duration, tail=duration, delay_ns=CONTROL_DELAY_NS, rounding="floor")
        m = cart_metrics(sim.t, sim.p, sim.v, sim.u, point["vref"], v_hat=sim.v_hat, edge_times=sim.edge_times,
                         tfilter=ctrl.tuning.Tfilter, counts_full=np.floor(sim.p / 5e-5 + 0.5))
        return {**point, **m, "status": "ok"}
    from netsim.runner import run

    res = run(str(SCENARIO), write=False, seed=point["seed"], overrides=ov)
    m = {str(k)[5:]: float(v) for k, v in res.metrics.items() if str(k).startswith("cart.")}  # names are str
    m["cpu_utilization"] = float(res.metrics.get("cpu.cart.utilization", math.nan))
    return {**point, **m, "status": res.status}


def _run_pair(args: tuple[dict[str, Any], str]) -> dict[str, Any]:
    return run_point(*args)


def _run_all(points: list[dict[str, Any]], engine: str, workers: int | None, progress: Progress | None = None,
             what: str = "runs", cache: RunCache | None = None) -> pd.DataFrame:
    """Run ``points`` (those not in ``cache``) on one pool; one row per point, in the order of ``points``."""
    keys = [cache_key(p, engine) for p in points] if cache is not None else []
    rows: dict[int, dict[str, Any]] = {}
    for i, key in enumerate(keys):
        row = cache.get(key) if cache is not None else None
        if row is not None:
            rows[i] = row
    todo = [i for i in range(len(points)) if i not in rows]

    def keep(j: int, row: dict[str, Any]) -> None:
        rows[todo[j]] = row
        if cache is not None and row.get("status") == "ok":  # a failed run is run again next time
            cache.put(keys[todo[j]], row)

    def report(done: int, total: int, label: str) -> None:
        if progress is not None:
            progress(len(points) - total + done, len(points), label)

    run_all(_run_pair, [(points[i], engine) for i in todo], workers=workers, progress=report, what=what,
            chunksize=2, each=keep)
    if progress is not None and not todo and points:
        progress(len(points), len(points), what)
    return pd.DataFrame([rows[i] for i in range(len(points))])


def _agg(df: pd.DataFrame, by: list[str]) -> pd.DataFrame:
    cols = ["sigma_u_pooled", "sigma_u", "Ev_jmap", "Ev", "Ev_jmap0", "Ev_est", "Ev_half1", "Ev_half2",
            "v_rms_stop", "events_per_tfilter", "reached"]
    d = df.copy()
    d["oscillating"] = oscillating(d).astype(float)
    return d.groupby(by)[cols + ["oscillating"]].mean().reset_index()


def _plots(out: Path, f2: pd.DataFrame, fq: pd.DataFrame, trace: dict[str, Any]) -> list[Path]:
    """Write :func:`netsim.models.cart.figures.cart_figures` into ``out`` in the paper style and the current plot
    format (:mod:`netsim.figure_style`)."""
    from netsim.models.cart.figures import cart_figures
    from netsim.figure_style import paper_style, save_figure

    a = _agg(f2, ["controller", "wc"])
    b = _agg(fq, ["controller", "q"]) if not fq.empty else fq
    with paper_style():
        return [save_figure(fig, out / name) for name, fig in cart_figures(f2, fq, trace, a, b).items()]


def _seed_span(df: pd.DataFrame) -> str:
    """The seeds of a run table, e.g. ``"1-20"`` (contiguous) or ``"1, 3, 7"``."""
    s = sorted(int(x) for x in df.seed.unique())
    return f"{s[0]}-{s[-1]}" if s == list(range(s[0], s[-1] + 1)) and len(s) > 2 else ", ".join(map(str, s))


def _fmt_pct(x: float) -> str:
    """A fraction of vref in words, e.g. ``0.1`` -> ``"10 % of vref"``."""
    return f"{_fmt(100 * x)} % of vref"


def _fig1_traces() -> dict[str, Any]:
    from netsim.models.cart.controllers import make_controller
    from netsim.models.cart.encoding import Quantizer
    from netsim.models.cart.friction import Friction, FrictionParams
    from netsim.models.cart.sim import simulate

    fr = Friction.draw(FrictionParams(), seed=1)
    return {c: simulate(make_controller(c, 20.0, Quantizer.from_bits(6)), fr, vref=0.8, q=6, duration=4.0,
                        tail=0.2) for c in ("pure_pi", "full_event")}


def _friction_ranges(seeds: tuple[int, ...]) -> dict[str, tuple[float, float, float, float]]:
    """Per friction label: the variation's frequency range (rad/s at vref = 0.8) at 0.3 m and at 1 m, over the
    realizations of ``seeds`` (min at 0.3 m, max at 0.3 m, min at 1 m, max at 1 m)."""
    from netsim.models.cart.friction import Friction, FrictionParams

    out = {}
    for label, fr in FRICTIONS.items():
        fp = FrictionParams.model_validate(fr or {})
        r0 = [Friction.draw(fp, seed=s).omega_range(0.8, 0.3, 0.3) for s in seeds]
        r1 = [Friction.draw(fp, seed=s).omega_range(0.8, 1.0, 1.0) for s in seeds]
        out[label] = (min(a for a, _ in r0), max(b for _, b in r0), min(a for a, _ in r1), max(b for _, b in r1))
    return out


_SENS_COLS = (
    ("pi_over_full_40", "Pure PI / Full Event sigma_u, wc=40"),
    ("pi_over_full_80", "Pure PI / Full Event sigma_u, wc=80"),
    ("lti_over_event_40", "best LTI / worst event sigma_u, wc=40"),
    ("lti_over_event_80", "best LTI / worst event sigma_u, wc=80"),
    ("evj_full_over_pi_40", "Full Event / Pure PI JMAP Ev, wc=40"),
    ("evj_full_over_pi_80", "Full Event / Pure PI JMAP Ev, wc=80"),
    ("osc_simplified_80", "Basic + PosPred oscillating at wc=80"),
    ("osc_others", "others oscillating"),
    ("half2_over_half1_20", "later / first half Ev, wc=20"),
)


def sensitivity_table(f2: pd.DataFrame, sens: pd.DataFrame) -> pd.DataFrame:
    """The headline ratios (:func:`netsim.models.cart.claims.headline`) under each friction model, one row per model.

    ``f2`` holds the default model's runs, ``sens`` the others' (``sigma_u`` pooled within each model).
    """
    rows = []
    both = pd.concat([f2[f2.wc.isin(WCS_SENS)], sens], ignore_index=True) if not sens.empty else f2
    for label in FRICTIONS:
        d = both[both.friction == label]
        if d.empty:
            continue
        rows.append({"friction": label, "runs": len(d), **headline(d)})
    return pd.DataFrame(rows)


#: The report's templates (``models/cart/report.md``): the README's layout and prose, ``{key}`` filled by :func:`_readme`.
TEMPLATES = Templates(Path(__file__).with_suffix(".md"))
_render = TEMPLATES.fill


def _readme(out: Path, f2: pd.DataFrame, fq: pd.DataFrame, claims: list[dict[str, str]], sens: pd.DataFrame,
            engine: str, wall: float, n_runs: int, run_time: float, *, inst: pd.DataFrame | None = None,
            reused: int = 0) -> str:
    from netsim.figure_style import current_format

    seeds = tuple(sorted(int(x) for x in f2.seed.unique()))
    ranges = _friction_ranges(seeds)
    (a0, b0, a1, b1), r_m6 = ranges["inband"], ranges["modes6"]
    cpus = os.cpu_count()
    t = {"engine": engine, "n_runs": str(n_runs), "wall_s": f"{wall:.0f}", "cpus": str(cpus),
         "cpu_s": f"{run_time:.0f}", "idle_min": f"{run_time / max(1, cpus or 1) / 60:.1f}", "reused": str(reused),
         "duration_fig2": f"{DURATION_FIG2:g}", "duration_quant": f"{DURATION_QUANT:g}",
         "inband_lo_03": _fmt(a0, 2), "inband_hi_03": _fmt(b0, 2), "inband_lo_1": _fmt(a1, 2),
         "inband_hi_1": _fmt(b1, 2), "modes6_lo": _fmt(r_m6[0], 2), "modes6_hi": _fmt(r_m6[3], 3),
         "pool_f2": _fmt(100 * pooling_difference(f2), 2),
         "pool_q": _fmt(100 * (pooling_difference(fq) if not fq.empty else math.nan), 2),
         "stop_from": f"{STOP_WINDOW[0]:g}", "stop_to": f"{STOP_WINDOW[1]:g}", "osc_pct": f"{100 * OSC_THRESHOLD:g}",
         "claims_rows": "\n".join(f"| {c['claim']} | **{c['verdict']}** | {c['numbers']} | {c['why']} |"
                                  for c in claims),
         "figures": ", ".join(f"`{n}.{current_format()}`" for n in ("fig1_time", "fig2_sigma_vs_ev", "fig3_ev_vs_q",
                                                                    "fig4_sigma_vs_q")),
         "sensitivity": "", "instability": "", "quant": ""}
    if not sens.empty:
        head = ["| friction | runs | " + " | ".join(t for _, t in _SENS_COLS) + " |", "|---|---|" + "---|" * len(_SENS_COLS)]
        rows = [f"| {r.friction} | {int(r.runs)} | " + " | ".join(_fmt(r[k]) for k, _ in _SENS_COLS) + " |"
                for _, r in sens.iterrows()]
        t["sensitivity"] = "\n" + _render("sensitivity", {
            "seeds": ", ".join(map(str, seeds)), "sens_table": "\n".join(head + rows),
            "i1020_lo": _fmt(ranges["inband_10_20"][0], 2), "i1020_hi": _fmt(ranges["inband_10_20"][3], 2)})
    if inst is not None and len(inst):
        osc, ratio, rows = oscillating(inst), inst["v_rms_stop"] / inst["vref"].abs(), []
        for c in CONTROLLERS:
            m = (inst.controller == c).to_numpy()
            if m.any():
                rows.append(f"| {c} | {int(osc[m].fillna(False).astype(bool).sum())}/{int(m.sum())} | "
                            f"{_fmt(float(ratio[m].median()))} | {_fmt(float(ratio[m].max()))} | "
                            f"{_fmt(float(inst.loc[m, 'reached'].mean()))} |")
        t["instability"] = "\n" + _render("instability", {
            "inst_n": str(inst.seed.nunique()), "inst_seeds": _seed_span(inst), "osc_vref": _fmt_pct(OSC_THRESHOLD),
            "inst_rows": "\n".join(rows)})
    t["fig2_rows"] = "\n".join(
        f"| {r.controller} | {int(r.wc)} | {_fmt(r.sigma_u_pooled)} | {_fmt(r.sigma_u)} | {_fmt(r.Ev_jmap)} | "
        f"{_fmt(r.Ev)} | {_fmt(r.Ev_jmap0)} | {_fmt(r.Ev_half2 / r.Ev_half1)} | {_fmt(r.v_rms_stop)} | "
        f"{_fmt(r.oscillating)} | {_fmt(r.events_per_tfilter)} | {_fmt(r.reached)} |"
        for _, r in _agg(f2, ["controller", "wc"]).iterrows())
    if not fq.empty:
        t["quant"] = "\n" + _render("quant", {"quant_rows": "\n".join(
            f"| {r.controller} | {int(r.q)} | {_fmt(r.sigma_u_pooled)} | {_fmt(r.sigma_u)} | {_fmt(r.Ev_jmap)} | "
            f"{_fmt(r.Ev)} | {_fmt(r.Ev_jmap0)} |" for _, r in _agg(fq, ["controller", "q"]).iterrows())})
    text = _render("readme", t) + "\n"
    (out / "README.md").write_text(text, encoding="utf-8")
    return text


@register("report", "cart", "Henningsson & Cervin cart: Fig. 2 and Figs. 3-4 studies, claims table")
def cart_report(out_dir: Path | None = None, plots: bool = True, *, engine: str = "netsim",
                workers: int | None = None, quant: bool = True, sensitivity: bool = True,
                seeds: tuple[int, ...] | None = None, instability: bool = True,
                inst_seeds: tuple[int, ...] | None = None, use_cache: bool = True,
                progress: Progress | None = log_progress) -> dict[str, pd.DataFrame]:
    """Run the studies and write ``reports/cart`` (or ``out_dir``); returns the tables by name.

    Parameters
    ----------
    out_dir
        Output folder (default ``reports/cart``).
    plots
        Write the figures.
    engine
        ``"netsim"`` (the scenario through :func:`netsim.runner.run`) or ``"numpy"`` (the reference loop).
    workers
        Parallel processes (default: one per CPU).
    quant, sensitivity
        Also run the Figs. 3-4 study and the friction sensitivity grid.
    seeds
        Friction realizations of the Fig. 2 and sensitivity grids (default ``SEEDS_FIG2``; the Figs. 3-4
        grid uses ``SEEDS_QUANT``), e.g. ``(1,)`` for a quick check.
    instability, inst_seeds
        Also run every controller at wc = 80 over ``inst_seeds`` (default :data:`SEEDS_INSTABILITY`) for the
        instability verdict (``instability.csv``).
    use_cache
        Reuse the rows of points already run with the same code (:func:`run_cache` in ``<out>/runs``).
    progress
        Called as ``progress(done, total, study)`` after each run (default: :func:`log_progress`); ``None``
        for silence.
    """
    t0 = time.perf_counter()
    out = Path(out_dir) if out_dir is not None else Path("reports") / "cart"
    out.mkdir(parents=True, exist_ok=True)
    sd = tuple(seeds) if seeds else SEEDS_FIG2
    cache = run_cache(out / "runs" if use_cache else None)
    f2 = pool_sigma(_run_all(fig2_points(sd), engine, workers, progress, "Fig. 2", cache))
    fq = (pool_sigma(_run_all(quant_points(), engine, workers, progress, "Figs. 3-4", cache)) if quant
          else pd.DataFrame())
    sr = (pool_sigma(_run_all(sensitivity_points(sd), engine, workers, progress, "friction sensitivity", cache),
                     by=("friction", "vref")) if sensitivity else pd.DataFrame())
    inst = (_run_all(instability_points(inst_seeds or SEEDS_INSTABILITY), engine, workers, progress,
                     "wc = 80 instability", cache) if instability else pd.DataFrame())
    f2.to_csv(out / "fig2.csv", index=False)
    if quant:
        fq.to_csv(out / "quant.csv", index=False)
    sens = sensitivity_table(f2, sr) if sensitivity else pd.DataFrame()
    if sensitivity:
        sr.to_csv(out / "sensitivity_runs.csv", index=False)
        sens.to_csv(out / "sensitivity.csv", index=False)
    if instability:
        inst.to_csv(out / "instability.csv", index=False)
    claims = make_claims(f2, fq, inst if instability else None)
    cl = pd.DataFrame(claims)
    cl.to_csv(out / "claims.csv", index=False)
    if plots:
        _plots(out, f2, fq, _fig1_traces())
    runs = [d for d in (f2, fq, sr, inst) if len(d)]
    run_time = float(sum(d["cpu_s"].sum() for d in runs if "cpu_s" in d))
    _readme(out, f2, fq, claims, sens, engine, time.perf_counter() - t0, sum(len(d) for d in runs), run_time,
            inst=inst, reused=cache.reused)
    return {"fig2": f2, "quant": fq, "sensitivity": sens, "instability": inst, "claims": cl}
