"""Reproduction report of the HDD case study (``netsim report hdd``).

Runs ``scenarios/hdd_case1.yaml`` .. ``hdd_case6.yaml`` (each with its Case 1 baseline), puts the paper's
numbers (section 5 of Cuenca et al.) beside ours, and writes ``reports/hdd/table.csv``,
``reports/hdd/README.md`` and figures like the paper's Figs. 6-13 (output vs reference, control signal,
per-sample bars of sensor->controller and controller->actuator transmissions, multiplicity N).
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pandas as pd

from netsim.registry import register

__all__ = ["PAPER", "hdd_report"]

log = logging.getLogger(__name__)

ROOT = Path(__file__).resolve().parents[1]

#: Section 5 of the paper (NaN: not printed). Ua of Cases 5-6 computed from Nca/464 (not printed).
PAPER = pd.DataFrame(
    [
        (1, 464, 464, 1.00, 1.00, 66, 3.75, np.nan, np.nan),
        (2, 250, 78, 0.54, 0.16, 35, 3.75, 0.54, 0.14),
        (3, 120, 50, 0.26, 0.10, 17, 3.75, np.nan, np.nan),
        (4, 203, 77, 0.44, 0.15, 29, 3.75, np.nan, 0.09),
        (5, 338, 231, 0.73, 231 / 464, 48, 3.75, np.nan, 0.02),
        (6, 360, 315, 0.78, 315 / 464, 53, 3.75, np.nan, 0.01),
    ],
    columns=["case", "Nsc", "Nca", "Uc", "Ua", "Cc_pct", "ISE", "ISEP", "NE"],
)

_COLS = {"Nsc": "et.Nsc", "Nca": "et.Nca", "Uc": "et.Uc", "Ua": "et.Ua", "Cc_pct": "et.Cc", "ISE": "et.ISE",
         "ISEP": "et.ISEP", "NE": "et.NE", "GPI": "et.GPI"}

REASONS = {
    1: "ISE 4.16 vs 3.75: the reference is not stated (we use a unit step at t = 0) and our plant reading "
       "(unit-gain resonances, attenuating notch) is documented in models/hdd.py; the MRCI (interlaced, eq 19) "
       "is not identical to C(z) (ISE with the plain C(z): 4.36).",
    2: "More transmissions than the paper (Uc 0.75 vs 0.54) and a larger NE: our controller without NUMRE "
       "steps only at arrivals (interlaced by k mod m) and holds u; the paper's Case 2 detail (e.g. whether "
       "the controller catches up the skipped periods) is not stated. Ordering as in the paper: fewer "
       "transmissions than TTS, NE clearly worse.",
    3: "Close to the paper (Uc 0.28 vs 0.26, Ua 0.09 vs 0.10). NE 0.10 (not printed in the paper, which "
       "says the TTS output is achieved): the residual comes from eq (22) holding packets back; with every "
       "packet sent the NUMRE reproduces the TTS output (NE < 0.01, tested).",
    4: "Noise std 1e-3 and Cov(w) = 1e-7 are our choices (unstated); same ordering: Uc rises from Case 3, NE "
       "of the same order as the paper's 0.09.",
    5: "Narrower thresholds raise Uc/Ua and lower NE, as in the paper; our Uc is higher (0.83 vs 0.73) "
       "because with the squared-norm reading of eq (6) the threshold sqrt(1e-7(1+y^2)) = 4.5e-4 is below "
       "our noise std 1e-3.",
    6: "Reproduced in kind: NE 0.029 vs Case 5's 0.032 (paper 0.01 vs 0.02), Uc 0.81 vs 0.83 (paper 0.78 vs "
       "0.73), Nca 316 vs 191 (paper 315 vs 231: more controller->actuator packets with the DOB). The DOB is the "
       "H-infinity problem (17) in its estimator form (stable D by construction, D1 ~ -1, D2 ~ G^-1 below 1 kHz); "
       "the closed-loop LFT of eq (18) gives an unstable D for this plant (it only has to be stable in the loop "
       "through C(z)) and diverged inside the NUMRE cascade (NE 4.5), so it is refused at build time. The paper "
       "gives no weights for (17); ours (1 kHz, 1 % low-frequency error) were chosen before the run; NE over "
       "seeds 1-5 is 0.02-0.03 (Case 5: 0.025-0.045), with a DOB bandwidth of 300 Hz / 2 kHz (seeds 1-2) 0.036-0.056 / "
       "0.015-0.019 (Ua 0.47 / 0.81); without the DOB the plant-only NUMRE gives NE 0.07-0.18 (seeds 1-2).",
}


def _run_cases(cases):
    from netsim.runner import run

    out = {}
    for n in cases:
        res = run(ROOT / "scenarios" / f"hdd_case{n}.yaml", write=False)
        if res.meta.get("status") != "ok":
            log.warning("hdd_case%d: %s", n, res.meta.get("error"))
        out[n] = res
    return out


def _table(results) -> pd.DataFrame:
    rows = []
    for n, res in results.items():
        m = res.metrics
        paper = PAPER.set_index("case").loc[n]
        row = {"case": n}
        for col, key in _COLS.items():
            ours = float(m[key]) if key in m else np.nan
            row[f"{col}_ours"] = ours
            if col in paper.index:
                row[f"{col}_paper"] = float(paper[col])
                row[f"{col}_diff"] = ours - float(paper[col])
        row["reason"] = REASONS.get(n, "")
        rows.append(row)
    return pd.DataFrame(rows)


def _figures(results, out_dir: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = []
    T = 20e-6
    for n, res in results.items():
        s = res.signals
        t = s["time_s"].to_numpy() * 1e3
        fig, ax = plt.subplots(4, 1, figsize=(7, 8), sharex=True)
        ax[0].plot(t, s["r"], "k--", label="r")
        ax[0].plot(t, s["y"], label="y")
        if "y_hat" in s:
            ax[0].plot(t, s["y_hat"], ":", label="y_hat")
        ax[0].legend(loc="lower right")
        ax[0].set_ylabel("output")
        ax[1].plot(t, s["u"], drawstyle="steps-post")
        ax[1].set_ylabel("u")
        msgs = res.messages
        for tag, lvl, lab in (("y", 1.0, "sensor->controller"), ("u", 0.5, "controller->actuator")):
            ts = msgs.loc[msgs["tag"] == tag, "sent_s"].to_numpy()
            ax[2].vlines(np.floor(ts / T) * T * 1e3, 0, lvl, lw=0.6, label=lab,
                         color="C0" if tag == "y" else "k")
        ax[2].set_ylabel("use")
        ax[2].legend(loc="upper right", fontsize=7)
        if "N" in s:
            ax[3].plot(t, s["N"], drawstyle="steps-post")
        ax[3].set_ylabel("N")
        ax[3].set_xlabel("time (ms)")
        fig.suptitle(f"HDD Case {n}")
        fig.tight_layout()
        name = f"case{n}.png"
        fig.savefig(out_dir / name, dpi=90)
        plt.close(fig)
        names.append(name)
    return names


def _fmt(v) -> str:
    if isinstance(v, float):
        return "" if np.isnan(v) else f"{v:.3g}"
    return str(v)


def _readme(table: pd.DataFrame, figs: list[str]) -> str:
    cols = ["Nsc", "Nca", "Uc", "Ua", "Cc_pct", "ISE", "ISEP", "NE"]
    lines = ["# HDD case study: reproduction of Cuenca, Zheng, Tomizuka, Sanchez, section 5", "",
             "Generated by `netsim report hdd` (models/hdd_report.py). Scenarios: `scenarios/hdd_case1..6.yaml`;",
             "choices for values the paper leaves unstated are in the scenario headers, readings of the printed",
             "model parameters in the docstring of `models/hdd.py`.", "",
             "| case | " + " | ".join(f"{c} paper / ours" for c in cols) + " |",
             "|---" * (len(cols) + 1) + "|"]
    for _, r in table.iterrows():
        cells = [f"{_fmt(r.get(c + '_paper', np.nan))} / {_fmt(r[c + '_ours'])}" for c in cols]
        lines.append(f"| {int(r['case'])} | " + " | ".join(cells) + " |")
    lines += ["", "## Why the numbers differ", ""]
    for _, r in table.iterrows():
        lines.append(f"- **Case {int(r['case'])}**: {r['reason']}")
    lines += ["", "Thresholds (for sweeps): `nodes.sensor.handlers[0].params.sigma_s`, `...delta_s`,",
              "`nodes.controller.tasks[0].params.sigma_c`, `...delta_c`.", "", "## Figures", ""]
    lines += [f"![{f}]({f})" for f in figs]
    return "\n".join(lines) + "\n"


@register("report", "hdd", "HDD Cases 1-6 vs the paper: reports/hdd/README.md, table.csv and figures")
def hdd_report(out_dir: Path | None = None, plots: bool = True) -> dict[str, pd.DataFrame]:
    """Run Cases 1-6 and write the reproduction report; return ``{"table": ..., "paper": ...}``."""
    out = Path(out_dir) if out_dir is not None else ROOT / "reports" / "hdd"
    out.mkdir(parents=True, exist_ok=True)
    results = _run_cases(range(1, 7))
    table = _table(results)
    table.to_csv(out / "table.csv", index=False)
    figs = _figures(results, out) if plots else []
    (out / "README.md").write_text(_readme(table, figs))
    return {"table": table, "paper": PAPER}
