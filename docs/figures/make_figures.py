"""Regenerate the README's example figures (one of each kind) into docs/figures/.

Run from the repository root: ``python docs/figures/make_figures.py``.
"""

from __future__ import annotations

from pathlib import Path

import netsim  # first: the BLAS pinning of netsim.blas

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from netsim.sweep.surface import Surface, find_optimum, surface_figure  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
OUT = Path(__file__).resolve().parent
DPI = 72


def main() -> None:
    # three DC servo loops under EDF (the run is ok); the motors' angle and voltage declared as the channels' units
    units = {f"io.{ch}{i}.unit": unit for i in (1, 2, 3) for ch, unit in (("y", "rad"), ("u", "V"))}
    loops = netsim.run(ROOT / "scenarios" / "three_servos_edf.yaml", overrides=units)
    assert loops.status == "ok", loops.status
    loops.plot().savefig(OUT / "responses.png", dpi=DPI)
    # under DM the lowest-priority loop misses its deadlines: the default window shows every job
    dm = netsim.run(ROOT / "scenarios" / "three_servos_dm.yaml", overrides={"duration": "0.3 s"})
    dm.plot_schedule().savefig(OUT / "schedule.png", dpi=DPI)
    radio = netsim.run(ROOT / "scenarios" / "dc_servo_zigbee.yaml",
                       overrides={"duration": "0.3 s", "nodes.interference.tasks[0].params.share": 0.5})
    radio.plot_network().savefig(OUT / "network.png", dpi=DPI)
    gpi = pd.read_csv(ROOT / "reports" / "hdd" / "gpi.csv")
    surface = _surface(gpi, "sigma_s", "sigma_c", "et.GPI")
    # one heat map in the paper style (a 3.5 in column): twice the dpi to be legible beside the others, and a tight
    # box so that the title naming the optimum is not cut
    surface_figure(surface, find_optimum(surface)).savefig(OUT / "surface.png", dpi=2 * DPI, bbox_inches="tight")


def _surface(frame: pd.DataFrame, x: str, y: str, z: str) -> Surface:
    ok = frame[frame["status"] == "ok"] if "status" in frame else frame
    xs = sorted(ok[x].unique())
    ys = sorted(ok[y].unique())
    grid = ok.pivot_table(index=y, columns=x, values=z).reindex(index=ys, columns=xs)
    cells = pd.DataFrame({"x": ok[x].to_numpy(), "y": ok[y].to_numpy(), "z": ok[z].to_numpy(), "runs": 1,
                          "index": range(len(ok))})
    return Surface(x=x, y=y, z=z, cells=cells, xs=np.array(xs), ys=np.array(ys), Z=grid.to_numpy(float),
                   logx=True, logy=True)


if __name__ == "__main__":
    main()
