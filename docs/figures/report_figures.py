"""Redraw the committed figures of the case-study reports from the reports' own data, without their sweeps.

Run from the repository root: ``python docs/figures/report_figures.py [pendulum] [unicycle] [hdd]`` (default:
all three; a few minutes on one core). Each report's tables and README are left as they are:

* pendulum: the three closed-loop LQR runs the figure draws (seed 1, as the report runs them) and
  ``reports/pendulum/delay_cost.csv``;
* unicycle: the ``unicycle_ekf`` run and the Monte-Carlo runs of each (Q, R) setting (same seeds as the report);
* hdd: Cases 1-6 again (the case figures) and ``reports/hdd/gpi.csv`` / ``gpi4.csv`` (the GPI surfaces).

The cart report's figures come from its cached points: ``netsim report cart`` redraws them.
"""

from __future__ import annotations

import sys
from pathlib import Path

import netsim  # noqa: F401 - first: the BLAS pinning of netsim.blas

ROOT = Path(__file__).resolve().parents[2]


def pendulum(out: Path = ROOT / "reports" / "pendulum") -> list[Path]:
    import pandas as pd

    from netsim.models.pendulum.figures import closed_loop_figure, delay_figure
    from netsim.models.pendulum.report import FIGURE_ESTIMATORS, closed_loop_cases, run_case

    signals = {}
    for case in closed_loop_cases():
        if case.get("keep_signals") and case.get("estimator") in FIGURE_ESTIMATORS:
            signals[case["estimator"]] = run_case(case)["_signals"]
    return [closed_loop_figure(out, {e: signals[e] for e in FIGURE_ESTIMATORS if e in signals}),
            delay_figure(out, pd.read_csv(out / "delay_cost.csv"))]


def unicycle(out: Path = ROOT / "reports" / "unicycle") -> list[Path]:
    from netsim.models.unicycle.figures import regenerate

    return regenerate(out, runs=200, workers=1)


def hdd(out: Path = ROOT / "reports" / "hdd") -> list[Path]:
    import pandas as pd

    from netsim.models.hdd_figures import case_figures, save_gpi_figure
    from netsim.models.hdd_report import PAPER_OPT, collect

    results, _, _ = collect([f"case{n}" for n in range(1, 7)], gpi=False)
    written = [out / name for name in case_figures(results, out)]
    for name in ("gpi", "gpi4"):
        save_gpi_figure(pd.read_csv(out / f"{name}.csv"), out, f"{name}.png", PAPER_OPT)
        written.append(out / f"{name}.png")
    return written


if __name__ == "__main__":
    for which in sys.argv[1:] or ["pendulum", "unicycle", "hdd"]:
        for path in {"pendulum": pendulum, "unicycle": unicycle, "hdd": hdd}[which]():
            print(path.relative_to(ROOT) if path.is_relative_to(ROOT) else path)
