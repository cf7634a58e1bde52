"""README and table rows of the 2WD cart report from the computed facts (:func:`netsim.models.unicycle.report`).

Sections 0-4 are here, section 5 (the networked experiments) in :mod:`netsim.models.unicycle.readme_net`. Every number
of the prose goes through :class:`~netsim.models.unicycle.quoting.Quotes` (``q.f``, ``q.pct``, ``q.i``, ``q.g``): the
report writes ``quoted.csv`` and ``template.md`` besides the README, and a test checks that the template holds
no typed-in number.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from netsim.models.unicycle.design import LQR_Q, LQR_R, PHASES
from netsim.models.unicycle.model import (
    ALPHA, BETA, GAMMA, HALF_WHEELBASE, P0, R_REPORT, TS, WALL_FRONT, WALL_SIDE, WHEEL_RADIUS, XI0_HAT,
)
from netsim.casestudy import Templates
from netsim.models.unicycle.quoting import Quotes

__all__ = ["write_readme"]


#: Sections 0-4 of the README (``models/unicycle/readme.md``): prose with ``{name}`` placeholders.
TEMPLATES = Templates(Path(__file__).with_suffix(".md"))
_section = TEMPLATES.fill


def write_readme(out: Path, T: Any, F: dict[str, Any]) -> str:
    """Fill the table ``T`` and write ``out/README.md``, ``out/quoted.csv`` and ``out/template.md``; returns the
    README's text. Each section's values are quoted in the order the text shows them (a quote's key is its
    running number)."""
    from netsim.models.unicycle.readme_net import network_section

    q = Quotes()
    _f, _pct, g, i = q.f, q.pct, q.g, q.i
    n, qr = F["runs"], F["qr"]
    b = qr["(Q, R)"]
    st, tu, fo = PHASES
    sdR = np.sqrt(R_REPORT)
    q.section = "s0"
    secs = [_section("s0", {
        "wall_s": q.f(F["wall_s"], 2, "wall_s"), "ts_ms": g(TS * 1e3, "ts_ms"), "r": g(WHEEL_RADIUS),
        "a": g(HALF_WHEELBASE), "wall_front": g(WALL_FRONT[2]), "wall_side": g(WALL_SIDE[2]), "x0": g(XI0_HAT[0]),
        "y0": g(XI0_HAT[1]), "th0": g(XI0_HAT[2]), "st_dur": g(st.duration), "st_v": g(st.v),
        "f_front": g(1 / (2 * TS)), "f_side": g(1 / (4 * TS)), "turn_deg": g(math.degrees(tu.w * tu.duration)),
        "tu_dur": g(tu.duration), "tu_v": g(tu.v), "fo_dur": g(fo.duration), "fo_v": g(fo.v), "ts_ms_q": g(TS * 1e3),
        "q1": g(LQR_Q[0, 0]), "q2": g(LQR_Q[1, 1]), "q3": g(LQR_Q[2, 2]), "q1_cm": g(100 / math.sqrt(LQR_Q[0, 0])),
        "q2_cm": g(100 / math.sqrt(LQR_Q[1, 1])), "q3_rad": g(1 / math.sqrt(LQR_Q[2, 2])), "r1": g(LQR_R[0, 0]),
        "r2": g(LQR_R[1, 1]), "r1_cms": g(100 / math.sqrt(LQR_R[0, 0])), "r2_rads": g(1 / math.sqrt(LQR_R[1, 1])),
        "th0_b": g(XI0_HAT[2]), "wall_side_b": g(WALL_SIDE[2]), "wall_front_b": g(WALL_FRONT[2]),
        "R1": g(R_REPORT[0]), "R2": g(R_REPORT[1]), "sd1_cm": q.f(sdR[0] * 100, 2), "sd2_cm": q.f(sdR[1] * 100, 2),
        "wd_lo": q.f(F["wall_dist"][0] * 100, 2), "wd_hi": q.f(F["wall_dist"][1] * 100, 2),
        "sd1_mm": q.f(sdR[0] * 10, 2), "sd2_mm": q.f(sdR[1] * 10, 2)})]
    # ---------------------------------------------------------------- equations
    pl, ps, lq = F["printed_lqr"], F["printed_side"], F["lqr"]
    q.section = "eq"
    eig_p = max(abs(lq[0.03]['eig_printed_on_true']))
    secs.append(_section("eq", {
        "theta_zero": i(0), "printed_rmse": _f(ps["printed_rmse_theta_straight"]),
        "derived_rmse": _f(ps["derived_rmse_theta_straight"]), "printed_cover": _pct(ps["printed_cover_theta"]),
        "derived_cover": _pct(ps["derived_cover_theta"]), "side_sd_cm": q.f(sdR[1] * 100, 2),
        "eig_printed": _f(eig_p, 6, "eig_printed"), "one": i(1),
        "doubling_s": q.f(math.log(2) / math.log(eig_p) * TS, 2, "doubling_s"),
        "printed_e2": _f(pl["printed_e2_max"] * 1e3), "derived_e2": _f(pl["derived_e2_max"] * 1e3),
        "printed_final": _f(pl["printed_final"] * 1e3), "derived_final": _f(pl["derived_final"] * 1e3)}))
    T.add("equations", "eq 6 side offset", "theta RMS error straight, printed [rad]", ps["printed_rmse_theta_straight"],
          "eq (6) puts gamma along +Y'", "the text says -Y'; derived used, printed kept as side_model: printed")
    T.add("equations", "eq 26 sign", "max |eig| of true loop with printed-design K", max(abs(lq[0.03]["eig_printed_on_true"])),
          "A_d[1,2] = -Ts v_ref", "derivation gives +Ts v_ref; the printed sign destabilises the lateral loop")
    # ---------------------------------------------------------------- experiment 1
    q.section = "s1"
    v: dict[str, str] = {"runs": i(n, "runs")}
    rows = []
    for s in ("x", "y", "theta"):
        rows.append(f"| {s} | {_pct(b[f'cover_{s}_straight'])} | {_pct(b[f'cover_{s}_turn'])} | "
                    f"{_pct(b[f'cover_{s}_front'])} | {_pct(b[f'cover_{s}'])} +- {_pct(1.96 * b[f'cover_se_{s}'])} |")
        T.add("1 bands", f"(Q, R), {n} runs", f"coverage {s}", b[f"cover_{s}"], "95 % bands (Figs. 2-3)",
              "filter noise model equals the truth's")
    v.update(coverage_rows="\n".join(rows), zcover=_pct(F["zcover"]), net_paragraphs="")
    T.add("1 bands", f"(Q, R), {n} runs", "coverage of readings by measurement bands", F["zcover"], "Fig. 3", "")
    for net_name, key, scen in (("CAN bus", "qr_can", "unicycle_ekf.yaml"), ("802.15.4 radio", "qr_radio",
                                                                        "unicycle_zigbee.yaml")):
        d = F.get(key)
        if d is None or not len(d):
            continue
        b0 = d[d["setting"] == "(Q, R)"]
        c = [b0[f"unicycle.cover_{s}_all"].mean() for s in ("x", "y", "theta")]
        se = [1.96 * b0[f"unicycle.cover_{s}_all"].std(ddof=1) / math.sqrt(len(b0)) for s in ("x", "y", "theta")]
        v["net_paragraphs"] += "\n\n" + _section("s1_net", {
            "net": net_name, "scen": scen, "n": i(len(b0)), "key": key, "cx": _pct(c[0]), "sex": _pct(se[0]),
            "cy": _pct(c[1]), "sey": _pct(se[1]), "cth": _pct(c[2]), "seth": _pct(se[2])})
        T.add("1 bands", f"netsim {net_name}, {len(b0)} replicates", "coverage x / y / theta",
              " / ".join(q.render(_pct(x)) for x in c), "", "sensor samples fused at their sample times")
    secs.append(_section("s1", v))
    # ---------------------------------------------------------------- experiment 2
    bm, ob = F["base"], F["obs"]
    q.section = "s2"
    rows = []
    for s, u in (("x", "m"), ("y", "m"), ("theta", "rad")):
        rows.append(f"| sigma {s} [{u}] | {_f(b[f'sd_{s}_end_straight'])} | {_f(b[f'sd_{s}_end_turn'])} | "
                    f"{_f(b[f'sd_{s}_end_front'])} |")
        T.add("2 blackout", "(Q, R)", f"sigma {s} end of turn / start", b[f"sd_{s}_end_turn"] / b[f"sd_{s}_end_straight"],
              "bands widen monotonically in the turn", "Q is tiny: the widening is small")
    sd0 = np.sqrt(np.diag(P0))
    secs.append(_section("s2", {
        "sigma_rows": "\n".join(rows), "st_dur": g(st.duration), "sd0_x": _f(sd0[0]), "sd0_y": _f(sd0[1]),
        "sd0_th": _f(sd0[2]), "sd_x": _f(b["sd_x_end_straight"]), "sd_y": _f(b["sd_y_end_straight"]),
        "sd_th": _f(b["sd_theta_end_straight"]), "shrink_y": _f(sd0[1] / b["sd_y_end_straight"], 2),
        "shrink_x": _f(sd0[0] / b["sd_x_end_straight"], 2), "off_lo": q.f(min(ALPHA, BETA, GAMMA) * 100, 2),
        "off_hi": q.f(max(ALPHA, BETA, GAMMA) * 100, 2), "noise_lo": q.f(sdR[0] * 100, 2),
        "noise_hi": q.f(sdR[1] * 100, 2), "monotone": _pct(b["blackout_monotone"]), "det_a": i(1), "q_zero": i(0),
        "tu_dur": g(tu.duration), "detp_ratio": _f(b["detP_ratio"]),
        **{f"grow_{s}": _pct(b[f"sd_{t}_end_turn"] / b[f"sd_{t}_end_straight"] - 1)
           for s, t in (("x", "x"), ("y", "y"), ("th", "theta"))},
        "rank_straight": i(ob["straight"]["rank_O"], "rank_O_straight"), "rank_c_straight": i(ob["straight"]["rank_C"]),
        "sigma_min": _f(ob["straight"]["sigma_min_O"]), "rank_front": i(ob["front"]["rank_O"], "rank_O_front"),
        "rank_c_front": i(ob["front"]["rank_C"]), "recovery_y": _f(bm["unicycle.recovery_y_s"], 3, "recovery_y_s"),
        "recovery_x": _f(bm["unicycle.recovery_x_s"]), "recovery_th": _f(bm["unicycle.recovery_theta_s"])}))
    T.add("2 blackout", "(Q, R)", "sigma theta end of straight / sqrt(P0)", b["sd_theta_end_straight"] / sd0[2],
          "P decreases rapidly with both sensors", "theta barely observable through the 7 cm offsets")
    T.add("2 blackout", "(Q, R)", "share of runs with det P increasing at every blackout sample", b["blackout_monotone"],
          "P grows by A P A' + Q", "")
    T.add("2 blackout", "(Q, R)", "det P end/start of turn (median)", b["detP_ratio"], "", "report gives no number")
    T.add("2 blackout", "straight, both sensors", "rank of observability matrix", ob["straight"]["rank_O"],
          "C rank 2, all states observable", "agrees")
    T.add("2 blackout", "front only, theta = pi/2", "rank of observability matrix", ob["front"]["rank_O"],
          "rank 1; x and theta observable through the motion coupling",
          "the coupling vanishes at theta = pi/2: only y observable")
    T.add("2 blackout", "netsim baseline run", "recovery of sigma y after the turn [s]", bm["unicycle.recovery_y_s"], "", "")
    # ---------------------------------------------------------------- experiment 3
    q.section = "s3"
    v = {"w1a": g(6), "w1b": g(7), "w2a": g(9), "w2b": g(10)}
    studies = [("numpy loop", qr)] + [(w, F[k]) for w, k in (("netsim CAN", "qr_can_study"),
                                                            ("netsim radio", "qr_radio_study")) if F.get(k)]
    rows = []
    for name in qr:
        for where, study in studies:
            qs = study[name]
            rows.append(f"| {name} | {where} | {i(qs['runs'])} | {_f(qs['rmse_y_straight'] * 1e3)} | "
                        f"{_f(qs['rough_y_straight'] * 1e3)} | {_f(qs['rough_theta_straight'] * 1e3)} | "
                        f"{_f(qs['rmse_y_6to7'] * 1e3)} | {_f(qs['rmse_y_9to10'] * 1e3)} | {_f(qs['rmse_theta_front'])} | "
                        f"{_f(qs['bias_y_turn'] * 1e3)} (+-{_f(qs['bias_se_y_turn'] * 1e3, 2)}) | {_pct(qs['cover_x'])} / "
                        f"{_pct(qs['cover_y'])} / {_pct(qs['cover_theta'])} |")
            for k in ("rmse_y_straight", "rough_y_straight", "rough_theta_straight", "rmse_y_6to7",
                      "rmse_theta_front", "bias_y_turn", "cover_theta"):
                T.add("3 Q/R", f"{name}, {where}", k, qs[k], "Fig. 1 (qualitative)", "")
    verdicts = {}
    for where, study in studies:
        b_, q5_, r5_ = study["(Q, R)"], study["(5Q, R)"], study["(Q, 5R)"]
        verdicts[where] = {"noisier": q5_["rough_y_straight"] > b_["rough_y_straight"],
                           "faster": q5_["rmse_y_6to7"] < b_["rmse_y_6to7"],
                           "smoother": r5_["rough_y_straight"] < b_["rough_y_straight"],
                           "slower": r5_["rmse_y_6to7"] > b_["rmse_y_6to7"]}
    q5, r5, qq = qr["(5Q, R)"], qr["(Q, 5R)"], qr["(5Q, 5R)"]
    yes = dict(verdicts["numpy loop"])
    dbias = r5["bias_y_turn"] - b["bias_y_turn"]
    se_d = math.hypot(r5["bias_se_y_turn"], b["bias_se_y_turn"])
    biased = abs(dbias) > 2 * se_d

    def _same(key: str) -> str:
        vals = {w: v[key] for w, v in verdicts.items()}
        if len(set(vals.values())) == 1:
            return f"the same verdict in all {i(len(vals))} (numpy loop and netsim)"
        return "verdicts differ: " + ", ".join(f"{w} {'yes' if v else 'no'}" for w, v in vals.items())

    v.update({"qr_rows": "\n".join(rows), "noisier": "yes" if yes["noisier"] else "no",
              "q5_rough": _f(q5["rough_y_straight"] * 1e3), "b_rough": _f(b["rough_y_straight"] * 1e3),
              "same_noisier": _same("noisier"), "faster": "yes" if yes["faster"] else "no",
              "q5_rmse67": _f(q5["rmse_y_6to7"] * 1e3), "b_rmse67": _f(b["rmse_y_6to7"] * 1e3),
              "same_faster": _same("faster"), "five_q": i(5), "smoother": "yes" if yes["smoother"] else "no",
              "r5_rough": _f(r5["rough_y_straight"] * 1e3), "same_smoother": _same("smoother"),
              "slower": "yes" if yes["slower"] else "no", "r5_rmse67": _f(r5["rmse_y_6to7"] * 1e3),
              "same_slower": _same("slower"), "dbias": _f(dbias * 1e3), "dbias_2se": _f(2 * se_d * 1e3, 2),
              "biased": "a bias" if biased else "no bias beyond the Monte-Carlo error", "five_p0": i(5),
              "qq_rmse": _f(qq["rmse_y_straight"] * 1e3), "b_rmse": _f(b["rmse_y_straight"] * 1e3)})
    secs.append(_section("s3", v))
    for setting, what, key in (("(5Q, R)", "noisier in straight part", "noisier"),
                               ("(5Q, R)", "faster after turn (y error 6-7 s)", "faster"),
                               ("(Q, 5R)", "smoother", "smoother"), ("(Q, 5R)", "slower after turn", "slower")):
        T.add("3 Q/R", f"{setting} vs (Q, R)", what, "yes" if yes[key] else "no", "yes", "")
    T.add("3 Q/R", "(Q, 5R) vs (Q, R)", "lateral (y) bias in turn beyond 2 SE", "yes" if biased else "no", "yes",
          "no correction in the blackout for any R")
    # ---------------------------------------------------------------- experiment 4
    nf, ff, lm = F["lqr_nf"], F["lqr_ff_nf"], F["lqr_run"]
    q.section = "s4"
    rows = []
    for vr, d in F["lqr"].items():
        K = d["K"]
        rows.append(f"| {g(vr)} | {_f(K[0, 0], 4, f'k11_{vr}')} | {_f(K[1, 1], 4, f'k22_{vr}')} | "
                    f"{_f(K[1, 2], 4, f'k23_{vr}')} | k12 = {g(K[0, 1], f'k12_{vr}')}, k13 = {g(K[0, 2], f'k13_{vr}')}, "
                    f"k21 = {g(K[1, 0], f'k21_{vr}')} | {', '.join(_f(abs(e), 5) for e in d['eig'])} (moduli) |")
        T.add("4 LQR", f"v_ref = {vr}", "k11 / k22 / k23", f"{K[0, 0]:.4g} / {K[1, 1]:.4g} / {K[1, 2]:.4g}",
              "structure of eq (27)", "weights our choice (report gives none)")
        T.add("4 LQR", f"v_ref = {vr}", "max |closed-loop eigenvalue|", max(abs(d["eig"])), "", "inside the unit circle")
    lag = F["lqr"][0.03]["lag_e1"]
    secs.append(_section("s4", {
        "k_rows": "\n".join(rows), "lag_mm": _f(lag * 1e3, 3, "lag_mm"), "v_lag": g(0.03),
        "nf_e1": _f(nf["e1_straight_mean"] * 1e3), "nf_e3_turn": _f(nf["e3_turn_end"]), "ff_e3": _f(ff["e3_max"]),
        "ff_e12": _f(max(ff["e1_max"], ff["e2_max"]) * 1e3), "rms_e1": _f(lm["unicycle.track_rms_e1"] * 1e3),
        "rms_e2": _f(lm["unicycle.track_rms_e2"] * 1e3), "rms_e3": _f(lm["unicycle.track_rms_e3"]),
        "max_e3": _f(lm["unicycle.track_max_e3"]), "sd_lo_cm": _f(b["sd_y_end_straight"] * 100, 2),
        "sd_hi_cm": _f(b["sd_x_end_front"] * 100, 2), "sd_th_rad": _f(b["sd_theta_end_straight"], 2)}))
    T.add("4 LQR", "noise-free, no feed-forward", "lag e1 [m]", nf["e1_straight_mean"], "(not given)",
          f"predicted v_ref/(-k11) = {lag:.4g}")
    T.add("4 LQR", "netsim, EKF in loop", "RMS e1 / e2 [m], e3 [rad]",
          f"{lm['unicycle.track_rms_e1']:.3g} / {lm['unicycle.track_rms_e2']:.3g} / {lm['unicycle.track_rms_e3']:.3g}",
          "section 4.3 has no results", "")
    # ---------------------------------------------------------------- networked
    marked = "\n\n".join(secs) + "\n\n" + "\n".join(network_section(q, T, F))
    text = Quotes.render(marked)
    (out / "README.md").write_text(text, encoding="utf-8")
    (out / "template.md").write_text(Quotes.template(marked), encoding="utf-8")
    q.frame(source=False).to_csv(out / "quoted.csv", index=False)
    return text
