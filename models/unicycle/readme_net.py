"""Section 5 of the 2WD cart README (:mod:`netsim.models.unicycle.readme`): what only a networked simulator shows.

Sweeps (``facts`` keys): ``net`` (CAN: front rate x Bernoulli loss), ``burst`` (CAN: Bernoulli against
Gilbert-Elliott), ``radio_mc`` (802.15.4: sensor rate x loss model drawn per attempt, 200 replicates:
:func:`radio_mc_section`, which :func:`splice_radio_mc` writes alone), ``delay`` (CAN: command delay with the
report's sensors), ``radio_delay`` (802.15.4: command delay, the report's and accurate sensors);
``zigbee`` is one run's metrics; ``delay_aware_can`` and ``delay_aware_radio`` (issue 26 section 5: the same
command delays with the filter unaware of them and told them, ``input_delay``) feed :func:`delay_aware_section`.
Every number goes through the :class:`~netsim.models.unicycle.quoting.Quotes`.

The section's words are data, in ``models/unicycle/readme_net.md`` (:data:`TEMPLATES`).
"""

from __future__ import annotations

import ast
import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from netsim.casestudy import Templates
from netsim.models.unicycle.model import TS
from netsim.models.unicycle.quoting import Quotes

__all__ = ["network_section", "loss_kind", "stability_limits", "mean_difference", "delay_aware_section",
           "delay_aware_frame", "GROWTH", "LOST_E3", "lost_runs", "DELAY_AWARE_MARK", "RADIO_MC_MARK",
           "radio_mc_section", "splice_radio_mc", "loss_params"]

#: The prose of section 5 (``models/unicycle/readme_net.md``): ``{name}`` placeholders filled with quoted texts.
TEMPLATES = Templates(Path(__file__).with_suffix(".md"))
_text = TEMPLATES.fill


def _marks(name: str) -> tuple[str, str]:
    lines = TEMPLATES[name].split("\n")
    return lines[0], lines[-1]


#: The README lines of the delay-aware study sit between these (``netsim report unicycle_delay_aware`` splices them).
DELAY_AWARE_MARK = _marks("delay_aware")
#: The radio Monte-Carlo study's README lines sit between these (``netsim report unicycle_radio_mc`` splices them).
RADIO_MC_MARK = _marks("radio_mc")
#: Where that study's lines stood in a README written before the markers: its first and last line begin so.
RADIO_MC_LEGACY = ("802.15.4 radio (`unicycle_radio_mc.yaml`", "- Loss")

#: A delay "degrades" the loop when the mean RMS longitudinal error e1 reaches this multiple of the no-delay one.
GROWTH = 3.0
#: A run has "lost" the loop when its heading error exceeds this [rad] (a quarter turn: the cart faces away).
LOST_E3 = math.pi / 2


def loss_kind(values: Any) -> np.ndarray:
    """Names of the loss models of a sweep column (dicts or their text)."""
    text = values.astype(str)
    return np.where(text.str.contains("gilbert"), "Gilbert-Elliott bursts",
                    np.where(text.str.contains("0.0}") | text.str.contains("'p': 0.0"), "none", "Bernoulli"))


def _ms(values: Any) -> Any:
    return values.astype(str).str.replace(" ms", "").astype(float)


def _tol(d: Any, col: str) -> float:
    return 1.96 * float(d[col].std(ddof=1)) / math.sqrt(len(d)) if len(d) > 1 else float("nan")


def mean_difference(q: Quotes, x: Any, y: Any, key: str | None = None) -> tuple[str, bool]:
    """``mean(x) - mean(y) +- 2 SE`` as quoted text (rad), and whether it exceeds two standard errors (quote keys
    ``<key>_diff`` and ``<key>_2se`` when ``key`` is given, running numbers otherwise)."""
    if len(x) < 2 or len(y) < 2:
        return "n/a", False
    d = float(x.mean() - y.mean())
    se = math.sqrt(float(x.var(ddof=1)) / len(x) + float(y.var(ddof=1)) / len(y))
    k1, k2 = (f"{key}_diff", f"{key}_2se") if key else (None, None)
    return f"{q.f(d, 2, k1)} +- {q.f(2 * se, 2, k2)} rad", abs(d) > 2 * se


def lost_runs(d: Any) -> Any:
    """Per run: the loop was lost (``max |e3| >`` :data:`LOST_E3`, or the run's status is diverged or unstable:
    the ``_failed`` column of :func:`netsim.models.unicycle.report.counted_runs`)."""
    lost = d["unicycle.track_max_e3"].astype(float) > LOST_E3
    if "_failed" in d:
        lost = lost | d["_failed"].astype(bool)
    return lost


def stability_limits(d: Any) -> dict[str, float]:
    """Per delay sweep (one sensor setting): the smallest delay [ms] whose mean RMS e1 reaches :data:`GROWTH`
    times the no-delay value, and the smallest at which more than half of the runs lost the loop
    (:func:`lost_runs`; NaN: none in the sweep)."""
    g = d.assign(_lost=lost_runs(d)).groupby("_ms", sort=True)
    e1 = g["unicycle.track_rms_e1"].mean()
    lost = g["_lost"].mean()
    base = float(e1.iloc[0])
    grow = [ms for ms, v in e1.items() if v >= GROWTH * base]
    gone = [ms for ms, v in lost.items() if v > 0.5]
    return {"degrade_ms": float(grow[0]) if grow else float("nan"),
            "lost_ms": float(gone[0]) if gone else float("nan"), "e1_base": base}


def loss_params(value: Any) -> dict[str, Any]:
    """The loss model of one sweep cell (a dict, or its JSON or Python text) as a dict."""
    if isinstance(value, dict):
        return value
    text = str(value)
    try:
        return dict(json.loads(text))
    except ValueError:
        return dict(ast.literal_eval(text))


def _attempt_share(d: Any) -> Any:
    """Per run: the share of the radio's transmission attempts the loss model erased. ``lost_attempts`` is in
    the metrics only when a loss model is set (none for ``p: 0``): no model, nothing erased."""
    lost = d["net.radio.lost_attempts"] if "net.radio.lost_attempts" in d else 0.0 * d["net.radio.attempts"]
    return lost.fillna(0.0) / d["net.radio.attempts"]


def radio_mc_section(q: Quotes, T: Any, F: dict[str, Any]) -> list[str]:
    """The README lines of the radio Monte-Carlo study (``F["radio_mc"]``, ``unicycle_radio_mc.yaml``) between
    :data:`RADIO_MC_MARK`, and their ``table.csv`` rows (experiment ``5 radio``, settings ending in ``runs``).

    The loss of the sweep is drawn per transmission attempt before the ACK (``docs/loss.md``): a lost attempt is
    retried by the MAC, so the messages lost are far fewer than the attempts erased; both are quoted from the
    runs. Every quote has a fixed key (``s5.radio_runs``, ``s5.rm_*``), so that the full report and
    ``netsim report unicycle_radio_mc`` write the same keys.
    """
    rm = F.get("radio_mc")
    if rm is None or not len(rm):
        return []
    _f, _pct = q.f, q.pct
    short = {"none": "none", "Bernoulli": "bern", "Gilbert-Elliott bursts": "burst"}
    order = {"none": 0, "Bernoulli": 1, "Gilbert-Elliott bursts": 2}
    rm = rm.copy().assign(_fp=_ms(rm["sensor_period"]), _kind=loss_kind(rm["loss_model"]))
    rm = rm.assign(_k=rm["_kind"].map(order), _erased=_attempt_share(rm),
                   _apm=rm["net.radio.attempts"] / rm["net.radio.messages"],
                   _late=rm["control.ekf.filter.late"] / (rm["control.ekf.filter.fused_front"]
                                                          + rm["control.ekf.filter.fused_side"]))
    g = rm.sort_values(["_fp", "_k"]).groupby(["_fp", "_k"], sort=True)
    se = [_tol(d, f"unicycle.cover_{s}_all") for _, d in g for s in ("x", "y", "theta")]
    kinds = set(rm["_kind"])
    model = []
    if "Bernoulli" in kinds:
        bern = loss_params(rm[rm["_kind"] == "Bernoulli"]["loss_model"].iloc[0])
        model.append(_text("rm_bernoulli", p=q.g(bern["p"], "rm_p")))
    if "Gilbert-Elliott bursts" in kinds:
        ge = loss_params(rm[rm["_kind"] == "Gilbert-Elliott bursts"]["loss_model"].iloc[0])
        gb, bg = float(ge["p_good_to_bad"]), float(ge["p_bad_to_good"])
        model.append(_text("rm_bursts", gb=q.g(gb, "rm_p_gb"), bg=q.g(bg, "rm_p_bg"),
                           bad=_pct(gb / (gb + bg), "rm_bad_share"), length=_f(1 / bg, 2, "rm_burst_len")))
    v = {"models": "; ".join(model), "runs": q.i(rm.groupby(["_fp", "_k"]).size().min(), "radio_runs"),
         "tol_lo": _pct(min(se), "rm_tol_lo"), "tol_hi": _pct(max(se), "rm_tol_hi")}
    rows = []
    for (fp, _), d in g:
        kind = d["_kind"].iloc[0]
        k = f"rm_{1e3 / fp:g}hz_{short[kind]}"
        fused = d["control.ekf.filter.fused_front"] + d["control.ekf.filter.fused_side"]
        rows.append(f"| {q.g(1e3 / fp, k + '_hz')} Hz | {kind} | {q.i(len(d), k + '_runs')} | "
                    f"{_pct(d['_erased'].mean(), k + '_erased')} | {_pct(d['net.radio.loss_rate'].mean(), k + '_lost')} | "
                    f"{_f(d['_apm'].mean(), 3, k + '_apm')} | "
                    f"{_f(d['net.radio.mean_delay_s'].mean() * 1e3, 3, k + '_delay')} | "
                    f"{_pct(d['unicycle.cover_x_all'].mean(), k + '_cov_x')} / "
                    f"{_pct(d['unicycle.cover_y_all'].mean(), k + '_cov_y')} / "
                    f"{_pct(d['unicycle.cover_theta_all'].mean(), k + '_cov_theta')} | "
                    f"{_f(d['unicycle.rmse_y_front'].mean() * 1e3, 3, k + '_rms_y')} | "
                    f"{_f(d['unicycle.rmse_theta_all'].mean(), 3, k + '_rms_theta')} | "
                    f"{_f(fused.mean(), 3, k + '_fused')} | {_pct(d['_late'].mean(), k + '_late')} |")
        for col, name in (("unicycle.cover_theta_all", "coverage theta"), ("unicycle.cover_y_all", "coverage y"),
                          ("unicycle.rmse_theta_all", "RMS theta all [rad]"),
                          ("unicycle.rmse_y_front", "RMS y front part [m]"),
                          ("net.radio.loss_rate", "messages lost"), ("_erased", "attempts erased")):
            T.add("5 radio", f"{1e3 / fp:g} Hz, {kind}, {len(d)} runs", name, d[col].mean(), "", "")
    fps = sorted(rm["_fp"].unique())
    at = rm[rm["_fp"] == fps[0]]

    def _mean(kind: str, col: str, fp: float = fps[0]) -> float:
        d = rm[(rm["_fp"] == fp) & (rm["_kind"] == kind)][col]
        return float(d.mean()) if len(d) else float("nan")

    def _diff(kind: str) -> tuple[str, bool]:
        """Mean RMS theta of ``kind`` minus that without loss at the fastest rate, +- two standard errors, and
        whether the difference exceeds them."""
        return mean_difference(q, at[at["_kind"] == kind]["unicycle.rmse_theta_all"],
                               at[at["_kind"] == "none"]["unicycle.rmse_theta_all"], f"rm_{short[kind]}")

    (be_text, be_sig), (ge_text, ge_sig) = _diff("Bernoulli"), _diff("Gilbert-Elliott bursts")
    b, ge_, no = "Bernoulli", "Gilbert-Elliott bursts", "none"
    v.update(rows="\n".join(rows), hz=q.g(1e3 / fps[0], "rm_fast_hz"),
             rate_hi=q.g(1e3 / fps[0], "rm_rate_hi_hz"), rate_lo=q.g(1e3 / fps[-1], "rm_rate_lo_hz"),
             y_hi=_f(_mean(no, "unicycle.rmse_y_front") * 1e3, 3, "rm_y_hi"),
             y_lo=_f(_mean(no, "unicycle.rmse_y_front", fps[-1]) * 1e3, 3, "rm_y_lo"),
             bern_erased=_pct(_mean(b, "_erased"), "rm_bern_erased_fast"),
             bern_lost=_pct(_mean(b, "net.radio.loss_rate"), "rm_bern_lost_fast"),
             none_lost=_pct(_mean(no, "net.radio.loss_rate"), "rm_none_lost_fast"),
             bern_apm=_f(_mean(b, "_apm"), 3, "rm_bern_apm_fast"), none_apm=_f(_mean(no, "_apm"), 3, "rm_none_apm_fast"),
             bern_delay=_f(_mean(b, "net.radio.mean_delay_s") * 1e3, 3, "rm_bern_delay_fast"),
             none_delay=_f(_mean(no, "net.radio.mean_delay_s") * 1e3, 3, "rm_none_delay_fast"),
             bern_late=_pct(_mean(b, "_late"), "rm_bern_late_fast"), none_late=_pct(_mean(no, "_late"), "rm_none_late_fast"),
             none_theta=_f(_mean(no, "unicycle.rmse_theta_all"), 3, "rm_none_theta_fast"),
             bern_theta=_f(_mean(b, "unicycle.rmse_theta_all"), 3, "rm_bern_theta_fast"),
             bern_diff=be_text, bern_sig="beyond" if be_sig else "within",
             burst_erased=_pct(_mean(ge_, "_erased"), "rm_burst_erased_fast"),
             burst_lost=_pct(_mean(ge_, "net.radio.loss_rate"), "rm_burst_lost_fast"),
             burst_theta=_f(_mean(ge_, "unicycle.rmse_theta_all"), 3, "rm_burst_theta_fast"),
             burst_diff=ge_text, burst_sig="beyond" if ge_sig else "within",
             burst_cov=_pct(_mean(ge_, "unicycle.cover_theta_all"), "rm_burst_cov_theta_fast"),
             none_cov=_pct(_mean(no, "unicycle.cover_theta_all"), "rm_none_cov_theta_fast"),
             verdict=_text({(True, True): "rm_verdict_both", (False, True): "rm_verdict_bursts",
                            (True, False): "rm_verdict_independent", (False, False): "rm_verdict_neither"}[
                                (be_sig, ge_sig)]))
    return _text("radio_mc", **v).split("\n") + [""]


def _region(lines: list[str], marks: tuple[str, str], legacy: tuple[str, str]) -> tuple[int, int]:
    """``[i, j)`` of a spliced section in README or template lines: from the first marker to the closing one and
    the blank line after it; a README written before the markers: from the line starting ``legacy[0]`` to the
    first line starting ``legacy[1]`` after it and the blank line after that."""
    if marks[0] in lines:
        i, j = lines.index(marks[0]), lines.index(marks[1]) + 1
    else:
        i = next(n for n, ln in enumerate(lines) if ln.startswith(legacy[0]))
        j = next(n for n in range(i, len(lines)) if lines[n].startswith(legacy[1])) + 1
    return i, j + 1 if j < len(lines) and lines[j] == "" else j


def splice_radio_mc(out: Path, marked: list[str], quotes: Any, table: Any) -> None:
    """Write the radio Monte-Carlo section into an existing report folder ``out`` and leave the rest alone.

    ``marked`` are the section's lines with quote markers (:func:`radio_mc_section`), ``quotes`` the
    :class:`Quotes` frame (``key, value, text``), ``table`` its ``table.csv`` rows. In ``README.md`` and ``template.md`` the section
    (between :data:`RADIO_MC_MARK`, or where it stood before the markers) is replaced; the keys the old template
    lines held leave ``quoted.csv`` and the new quotes take the place of the first of them; in ``table.csv`` the
    radio Monte-Carlo rows (experiment ``5 radio``, setting ending in ``runs``) are replaced in place.
    """
    import pandas as pd

    marked_text = "\n".join(marked)
    tpl = (out / "template.md").read_text().split("\n")
    md = (out / "README.md").read_text().split("\n")
    i, j = _region(tpl, RADIO_MC_MARK, RADIO_MC_LEGACY)
    if _region(md, RADIO_MC_MARK, RADIO_MC_LEGACY) != (i, j):
        raise ValueError(f"{out}: README.md and template.md do not line up at the radio Monte-Carlo section")
    old_keys = set(re.findall(r"\{([A-Za-z0-9_.]+)\}", "\n".join(tpl[i:j])))
    tpl[i:j] = Quotes.template(marked_text).split("\n")
    md[i:j] = Quotes.render(marked_text).split("\n")
    quoted = pd.read_csv(out / "quoted.csv", dtype=str, keep_default_na=False)
    gone = quoted["key"].isin(old_keys)
    new = pd.DataFrame(quotes, columns=["key", "value", "text"]).astype(str)
    clash = set(new["key"]) & set(quoted.loc[~gone, "key"])
    if clash:
        raise ValueError(f"{out / 'quoted.csv'}: keys of the radio section already used elsewhere: {sorted(clash)}")
    at = int(np.argmax(gone.to_numpy())) if gone.any() else len(quoted)
    quoted = pd.concat([quoted[:at][~gone[:at]], new, quoted[at:][~gone[at:]]], ignore_index=True)
    tab = pd.read_csv(out / "table.csv", dtype=str, keep_default_na=False)
    mine = (tab["experiment"] == "5 radio") & tab["setting"].str.endswith(" runs")
    at = int(np.argmax(mine.to_numpy())) if mine.any() else len(tab)
    tab = pd.concat([tab[:at][~mine[:at]], table.astype(str), tab[at:][~mine[at:]]], ignore_index=True)
    (out / "template.md").write_text("\n".join(tpl))
    (out / "README.md").write_text("\n".join(md))
    quoted.to_csv(out / "quoted.csv", index=False)
    tab.to_csv(out / "table.csv", index=False)


def network_section(q: Quotes, T: Any, F: dict[str, Any]) -> list[str]:
    """The README lines of section 5 (and their ``table.csv`` rows)."""
    _f, _pct, g_, i_ = q.f, q.pct, q.g, q.i
    q.section = "s5"
    L = ["## 5. What only a networked simulator shows", ""]
    L += radio_mc_section(q, T, F)
    # ------------------------------------------------------------ CAN sweeps (fewer runs)
    net = F.get("net")
    if net is not None and len(net):
        net = net.copy().assign(_fp=_ms(net["front_period"]))
        g = net.sort_values(["_fp", "loss"]).groupby(["_fp", "loss"], sort=True)
        se = [_tol(d, f"unicycle.cover_{s}_all") for _, d in g for s in ("x", "y", "theta")]
        v = {"side_hz": g_(1 / (4 * TS)), "runs": i_(g.size().min()), "tol_lo": _pct(min(se)), "tol_hi": _pct(max(se))}
        rows = []
        for (fp, lo), d in g:
            rows.append(f"| {g_(fp)} ms | {g_(lo)} | {i_(len(d))} | {_pct(d['unicycle.cover_x_all'].mean())} / "
                        f"{_pct(d['unicycle.cover_y_all'].mean())} / {_pct(d['unicycle.cover_theta_all'].mean())} | "
                        f"{_f(d['unicycle.rmse_y_front'].mean() * 1e3)} | {_f(d['unicycle.sd_y_end_front'].mean() * 1e3)} | "
                        f"{_f(d['control.ekf.filter.fused_front'].mean())} |")
            T.add("5 CAN", f"front {fp:g} ms, loss {lo}", "coverage y", d["unicycle.cover_y_all"].mean(), "", "")
            T.add("5 CAN", f"front {fp:g} ms, loss {lo}", "RMS y front part [m]", d["unicycle.rmse_y_front"].mean(),
                  "", "")
        L += _text("can_net", rows="\n".join(rows), **v).split("\n") + [""]
    bu = F.get("burst")
    if bu is not None and len(bu):
        bu = bu.copy().assign(_kind=loss_kind(bu["loss_model"]))
        rows = []
        for kind, d in bu.groupby("_kind"):
            rows.append(f"| {kind} | {i_(len(d))} | {_pct(d['net.can.loss_rate'].mean())} | "
                        f"{_pct(d['unicycle.cover_x_all'].mean())} / {_pct(d['unicycle.cover_y_all'].mean())} / "
                        f"{_pct(d['unicycle.cover_theta_all'].mean())} | {_f(d['unicycle.rmse_y_front'].mean() * 1e3)} | "
                        f"{_f(d['unicycle.rmse_theta_all'].mean())} |")
            T.add("5 CAN", f"{kind}", "RMS theta all [rad]", d["unicycle.rmse_theta_all"].mean(), "", "")
        x = bu[bu["_kind"] == "Gilbert-Elliott bursts"]["unicycle.rmse_theta_all"]
        y = bu[bu["_kind"] == "Bernoulli"]["unicycle.rmse_theta_all"]
        text, sig = mean_difference(q, x, y)
        L += _text("can_burst", rows="\n".join(rows), diff=text, sig="beyond" if sig else "within",
                   runs=i_(min(len(x), len(y)))).split("\n") + [""]
    zb, dm = F["zigbee"], F["delay_margin"]
    L += _text("zigbee", mean_ms=_f(zb["net.radio.mean_delay_s"] * 1e3), max_ms=_f(zb["net.radio.max_delay_s"] * 1e3),
               retries=i_(zb["net.radio.retransmissions"]), late=i_(zb["control.ekf.filter.late"]),
               fused=i_(zb["control.ekf.filter.fused_front"] + zb["control.ekf.filter.fused_side"]),
               lost=i_(zb["net.radio.dropped"]), margin_samples=i_(dm[0.03], "margin_samples"),
               margin_ms=g_(dm[0.03] * TS * 1e3, "margin_ms"), v_fast=g_(0.03), slow_samples=i_(dm[0.015]),
               v_slow=g_(0.015)).split("\n") + [""]
    T.add("5 radio", "802.15.4 radio, one run", "late samples fused at their sample time",
          zb["control.ekf.filter.late"], "", "")
    # ------------------------------------------------------------ command delay
    rd = F.get("radio_delay")
    if rd is not None and len(rd):
        rd = rd.copy().assign(_ms=_ms(rd["delay"]))
        v = {"r_scale": g_(1e4)}
        rows, limits = [], {}
        d_max = {sens: float(rd[rd["sensors"] == sens]["_ms"].max()) for sens in ("report", "accurate")}
        for sens in ("report", "accurate"):
            d0 = rd[rd["sensors"] == sens]
            if not len(d0):
                continue
            limits[sens] = stability_limits(d0)
            for dv, d in d0.groupby("_ms", sort=True):
                rows.append(f"| {sens} | {g_(dv)} ms | {i_(len(d))} | {_f(d['unicycle.track_rms_e1'].mean() * 1e3)} | "
                            f"{_f(d['unicycle.track_rms_e2'].mean() * 1e3)} | {_f(d['unicycle.track_rms_e3'].mean())} | "
                            f"{_f(d['unicycle.track_max_e3'].mean())} | {_pct(np.mean(lost_runs(d)))} | "
                            f"{_pct(d['unicycle.cover_y_all'].mean())} / {_pct(d['unicycle.cover_theta_all'].mean())} |")
                T.add("5 delay radio", f"{sens} sensors, {dv:g} ms", "RMS e1 [m]", d["unicycle.track_rms_e1"].mean(),
                      "", "")

        def _lim(sens: str) -> str:
            lim = limits.get(sens)
            if lim is None:
                return "not run"
            top = g_(d_max[sens])
            deg = (f"reaches {g_(GROWTH)}x its no-delay value from {g_(lim['degrade_ms'], f'degrade_ms_{sens}')} ms"
                   if not math.isnan(lim["degrade_ms"]) else
                   f"stays below {g_(GROWTH)}x its no-delay value up to {top} ms")
            lost = (f"most runs lose the loop from {g_(lim['lost_ms'], f'lost_ms_{sens}')} ms"
                    if not math.isnan(lim["lost_ms"]) else f"no delay up to {top} ms makes most runs lose the loop")
            return f"the mean RMS e1 {deg}, and {lost}"

        v.update(rows="\n".join(rows), accurate=_lim("accurate"), margin=g_(dm[0.03] * TS * 1e3), report=_lim("report"))
        L += _text("radio_delay", **v).split("\n") + [""]
        for sens, lim in limits.items():
            T.add("5 delay radio", f"{sens} sensors", "delay at which RMS e1 grows 3x [ms]", lim["degrade_ms"],
                  "", "linear margin: " + f"{dm[0.03] * TS * 1e3:g} ms")
            T.add("5 delay radio", f"{sens} sensors", "delay at which most runs lose the loop [ms]", lim["lost_ms"],
                  "", "")
    dl = F.get("delay")
    if dl is not None and len(dl):
        dl = dl.copy().assign(_ms=_ms(dl["delay"])).sort_values("_ms")
        rows = []
        for dv, d in dl.groupby("_ms", sort=True):
            rows.append(f"| {g_(dv)} ms | {i_(len(d))} | {_f(d['unicycle.track_rms_e1'].mean() * 1e3)} | "
                        f"{_f(d['unicycle.track_rms_e2'].mean() * 1e3)} | {_f(d['unicycle.track_rms_e3'].mean())} | "
                        f"{_f(d['unicycle.track_max_e3'].mean())} | {_pct(d['unicycle.cover_y_all'].mean())} / "
                        f"{_pct(d['unicycle.cover_theta_all'].mean())} |")
            T.add("5 delay CAN", f"command delay {dv:g} ms", "RMS e3 [rad]", d["unicycle.track_rms_e3"].mean(), "", "")
        L += _text("can_delay", rows="\n".join(rows)).split("\n") + [""]
    L += delay_aware_section(q, T, F)
    L += _text("late_samples", history=i_(F.get("history"), "history")).split("\n") + [""]
    sp = F.get("speed")
    if sp:
        L += _text("speed", ratio=_f(sp["ratio"], 2, "speed_ratio"), repeats=i_(sp["repeats"]),
                   netsim_s=_f(sp["netsim_s"]), numpy_s=_f(sp["numpy_s"]), pool_runs=i_(sp["pool_runs"], "pool_runs"),
                   pool_wall_s=_f(sp["pool_wall_s"], 3, "pool_wall_s"), workers=i_(sp["pool_workers"]),
                   rate=_f(sp["pool_runs"] / sp["pool_wall_s"], 3, "pool_runs_per_s"),
                   load=(f" (load average {_f(sp['load_average'], 2)} at the end)" if "load_average" in sp else "")
                   ).split("\n") + [""]
    return L


def delay_aware_frame(can: Any, radio: Any) -> Any:
    """The two delay-aware sweeps' summaries as one frame: ``network``, ``sensors``, ``_ms`` (command delay),
    ``filter`` (``unaware``: ``input_delay`` 0; ``told the delay``), and the run metrics."""
    import pandas as pd

    parts = []
    for net, d in (("CAN", can), ("radio", radio)):
        if d is None or not len(d):
            continue
        d = d.copy()
        d["network"] = net
        if "sensors" not in d.columns:
            d["sensors"] = "report"
        d["_ms"] = _ms(d["delay"])
        told = d["input_delay"].astype(float) > 0
        d["filter"] = np.where(told | (d["_ms"] == 0), "told the delay", "unaware")
        zero = d[d["_ms"] == 0].copy()  # delay 0: one run serves both rows
        zero["filter"] = "unaware"
        parts += [d, zero]
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()


def delay_aware_section(q: Quotes, T: Any, F: dict[str, Any]) -> list[str]:
    """The README lines of the delay-aware study (and their ``table.csv`` rows), between :data:`DELAY_AWARE_MARK`."""
    d = delay_aware_frame(F.get("delay_aware_can"), F.get("delay_aware_radio"))
    if not len(d):
        return []
    _f, _pct, g_ = q.f, q.pct, q.g
    runs = {net: int(g.groupby(["sensors", "_ms", "filter"]).size().min()) for net, g in d.groupby("network")}
    v = {"runs": ", ".join(f"{q.i(n, f'da_runs_{net}')} on {net}" for net, n in runs.items())}
    rows, limits = [], []
    for (net, sens, ms, filt), g in d.groupby(["network", "sensors", "_ms", "filter"], sort=True):
        rows.append(f"| {net} | {sens} | {g_(ms)} ms | {filt} | {q.i(len(g))} | "
                    f"{_f(g['unicycle.track_rms_e1'].mean() * 1e3)} | {_f(g['unicycle.track_rms_e3'].mean())} | "
                    f"{_f(g['unicycle.track_max_e3'].mean())} | {_pct(np.mean(lost_runs(g)))} | "
                    f"{_pct(g['unicycle.cover_y_all'].mean())} / {_pct(g['unicycle.cover_theta_all'].mean())} |")
        T.add("5 delay-aware", f"{net}, {sens} sensors, {ms:g} ms, {filt}", "RMS e1 [m]",
              g["unicycle.track_rms_e1"].mean(), "", "")
    for (net, sens), g in d.groupby(["network", "sensors"], sort=True):
        top = g_(float(g["_ms"].max()))
        said = []
        for filt in ("unaware", "told the delay"):
            lim = stability_limits(g[g["filter"] == filt])
            key = f"da_{net}_{sens}_{'told' if filt != 'unaware' else 'unaware'}"
            deg = (f"RMS e1 reaches {g_(GROWTH)}x its no-delay value from {g_(lim['degrade_ms'], key + '_degrade')} ms"
                   if not math.isnan(lim["degrade_ms"]) else f"RMS e1 stays below {g_(GROWTH)}x up to {top} ms")
            lost = (f"most runs lose the loop from {g_(lim['lost_ms'], key + '_lost')} ms"
                    if not math.isnan(lim["lost_ms"]) else f"no delay up to {top} ms makes most runs lose the loop")
            said.append(f"{filt}: {deg}, {lost}")
            for what, col in (("delay at which RMS e1 grows 3x [ms]", "degrade_ms"),
                              ("delay at which most runs lose the loop [ms]", "lost_ms")):
                T.add("5 delay-aware", f"{net}, {sens} sensors, {filt}", what, lim[col], "", "")
        limits.append(f"- {net}, {sens} sensors: " + "; ".join(said) + ".")
    # where the loop with the told filter still holds: is its estimate better (theta band coverage)?
    better = total = 0
    for (net, sens), g in d.groupby(["network", "sensors"], sort=True):
        lost_ms = stability_limits(g[g["filter"] == "told the delay"])["lost_ms"]
        for ms, h in g[(g["_ms"] > 0) & ((g["_ms"] < lost_ms) if not math.isnan(lost_ms) else True)].groupby("_ms"):
            cov = h.groupby("filter")["unicycle.cover_theta_all"].mean()
            if len(cov) == 2:
                total += 1
                better += int(cov["told the delay"] >= cov["unaware"])
    dm = F.get("delay_margin")
    v.update(rows="\n".join(rows), limits="\n".join(limits),
             margin=(f" ({g_(dm[0.03] * TS * 1e3, 'da_margin_ms')} ms on the linear error model with the true error, "
                     "above)") if dm else "")
    v.update(better=q.i(better, "da_cover_better"), points=q.i(total, "da_cover_points"))
    return _text("delay_aware", **v).split("\n") + [""]
