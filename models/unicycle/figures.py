"""Figures of the 2WD cart report (``netsim report unicycle``).

Kept apart from :mod:`netsim.models.unicycle.report`, which runs the studies and writes the tables and README.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["report_figures"]


def report_figures(out: Path, base: Any, qr: dict[str, list[dict]], t: np.ndarray) -> None:
    """Write the report's figures: ``fig1_qr_rms.png``, ``fig2_bands.png``, ``fig3_measurements.png``, ``detP.png``."""
    import matplotlib.pyplot as plt

    sig = base.to_pandas()
    fig, ax = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    for j, (s, unit) in enumerate((("x", "m"), ("y", "m"), ("theta", "rad"))):
        tt = sig.index.to_numpy()
        m, sd = sig[f"xhat[{j}]"].to_numpy(), sig[f"sd[{j}]"].to_numpy()
        ax[j].fill_between(tt, m - 1.96 * sd, m + 1.96 * sd, color="C0", alpha=0.25, label="95 % band")
        ax[j].plot(tt, m, "C0", label="estimate")
        ax[j].plot(tt, sig[s].to_numpy(), "k--", lw=1, label="truth")
        ax[j].axvspan(4, 6, color="0.9")
        ax[j].set_ylabel(f"{s} [{unit}]")
    ax[0].legend(loc="best", fontsize=8)
    ax[-1].set_xlabel("time [s] (grey: both sensors off)")
    fig.tight_layout()
    fig.savefig(out / "fig2_bands.png", dpi=90)
    plt.close(fig)
    fig, ax = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    for j, name in enumerate(("front", "side")):
        tt = sig.index.to_numpy()
        m, sd = sig[f"zhat[{j}]"].to_numpy(), sig[f"zsd[{j}]"].to_numpy()
        ax[j].fill_between(tt, m - 1.96 * sd, m + 1.96 * sd, color="C1", alpha=0.25, label="95 % band of z")
        ax[j].plot(tt, m, "C1", label="predicted reading")
        ax[j].plot(tt, sig["z_front" if j == 0 else "z_side"].to_numpy(), "k--", lw=1, label="noiseless reading")
        ax[j].set_ylabel(f"z {name} [m]")
    ax[0].legend(fontsize=8)
    ax[-1].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(out / "fig3_measurements.png", dpi=90)
    plt.close(fig)
    fig, ax = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    for name, runs in qr.items():
        E = np.stack([r["e"] for r in runs]).astype(float)
        for j, s in enumerate(("x", "y", "theta")):
            ax[j].plot(t, np.sqrt(np.mean(E[:, :, j] ** 2, axis=0)), label=name)
            ax[j].set_ylabel(f"RMS error {s}")
    ax[0].legend(fontsize=8)
    ax[-1].set_xlabel(f"time [s] ({len(next(iter(qr.values())))} runs per setting)")
    fig.tight_layout()
    fig.savefig(out / "fig1_qr_rms.png", dpi=90)
    plt.close(fig)
    fig, ax = plt.subplots(1, 1, figsize=(8, 3.5))
    ax.semilogy(sig.index.to_numpy(), sig["detP"].to_numpy())
    ax.axvspan(4, 6, color="0.9")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("det P")
    fig.tight_layout()
    fig.savefig(out / "detP.png", dpi=90)
    plt.close(fig)
