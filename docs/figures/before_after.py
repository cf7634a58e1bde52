"""Draw the three figures of issue 27's before/after comparison into docs/figures/<which>/.

Run from the repository root: ``python docs/figures/before_after.py before`` (or ``after``). The report figure
(``reports/pendulum/closed_loop_lqr.png``) is copied as committed.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import netsim  # first: the BLAS pinning of netsim.blas

ROOT = Path(__file__).resolve().parents[2]
DPI = 72


def main(which: str) -> None:
    out = Path(__file__).resolve().parent / which
    out.mkdir(parents=True, exist_ok=True)
    # after: the channels declare their units (io.<name>.unit, which the code before did not know)
    units = {"io.theta_m.unit": "rad", "io.alpha_m.unit": "rad", "io.u.unit": "V"} if which == "after" else {}
    pend = netsim.run(ROOT / "scenarios" / "pendulum_lqr.yaml", overrides=units)
    pend.plot().savefig(out / "responses_pendulum_lqr.png", dpi=DPI)
    servo = netsim.run(ROOT / "scenarios" / "dc_servo_can.yaml")  # 2 s, 201 sensor jobs of 0.5 ms
    servo.plot_schedule().savefig(out / "schedule_dc_servo_can.png", dpi=DPI)
    shutil.copyfile(ROOT / "reports" / "pendulum" / "closed_loop_lqr.png", out / "report_pendulum_closed_loop_lqr.png")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "after")
