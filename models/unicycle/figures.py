"""Figures of the 2WD cart report (``netsim report unicycle``), in the paper style.

Kept apart from :mod:`netsim.models.unicycle.report`, which runs the studies and writes the tables and README.
Each ``*_figure`` function builds one figure (one paper column wide, states as symbols with their units, time in
seconds); :func:`report_figures` saves the four into the report folder in the current plot format
(:func:`netsim.figure_style.save_figure`); :func:`regenerate` redraws them from fresh runs of the scenario and of
the Monte-Carlo loop (about a minute), without the report's sweeps.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["STATES", "bands_figure", "measurements_figure", "qr_rms_figure", "det_p_figure", "report_figures",
           "regenerate"]

#: The filter's states: (signal name, symbol, unit).
STATES = (("x", "$x$", "m"), ("y", "$y$", "m"), ("theta", r"$\theta$", "rad"))
#: The blackout (both sensors off) of the scenario, in seconds: shaded in the figures.
BLACKOUT_S = (4.0, 6.0)


def _figure(height: float, rows: int) -> tuple[Any, Any]:
    from matplotlib.figure import Figure

    from netsim.figure_style import COLUMN_WIDTH_IN

    fig = Figure(figsize=(COLUMN_WIDTH_IN, height), layout="constrained")
    return fig, fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]


def _blackout(ax: Any, label: bool = False) -> None:
    ax.axvspan(*BLACKOUT_S, color="0.88", lw=0, zorder=0, label="both sensors off" if label else None)


def _band_figure(sig: Any, height: float, panels: list[tuple[str, str, str, str]], color: str,
                 labels: tuple[str, str], ncols: int, blackout: bool) -> Any:
    """One panel per ``(mean, sd, reference, ylabel)`` column names of ``sig``: the mean with its 95 % band
    (1.96 sd) against the dashed reference; ``labels`` name the mean and the reference in the legend."""
    from netsim.figure_style import TIME_LABEL

    fig, ax = _figure(height, len(panels))
    tt = sig.index.to_numpy(float)
    for j, (mean, sd_col, ref, ylabel) in enumerate(panels):
        m, sd = sig[mean].to_numpy(float), sig[sd_col].to_numpy(float)
        if blackout:
            _blackout(ax[j], j == 0)
        ax[j].fill_between(tt, m - 1.96 * sd, m + 1.96 * sd, color=color, alpha=0.25, lw=0, label="95 % band")
        ax[j].plot(tt, m, color, label=labels[0])
        ax[j].plot(tt, sig[ref].to_numpy(float), "--", color="k", lw=0.8, label=labels[1])
        ax[j].set_ylabel(ylabel)
    ax[-1].set_xlabel(TIME_LABEL)
    fig.legend(*ax[0].get_legend_handles_labels(), loc="outside lower center", ncols=ncols)
    return fig


def bands_figure(sig: Any) -> Any:
    """The estimate of each state with its 95 % band against the truth (``sig``: the run's signals indexed by
    time in seconds, with ``xhat[j]``, ``sd[j]`` and the true ``x``, ``y``, ``theta``)."""
    panels = [(f"xhat[{j}]", f"sd[{j}]", s, f"{sym} ({unit})") for j, (s, sym, unit) in enumerate(STATES)]
    return _band_figure(sig, 3.6, panels, "C0", ("estimate", "truth"), 2, True)


def measurements_figure(sig: Any) -> Any:
    """The predicted reading of each distance sensor with its 95 % band against the noiseless reading."""
    panels = [(f"zhat[{j}]", f"zsd[{j}]", col, f"{name} distance (m)")
              for j, (col, name) in enumerate((("z_front", "front"), ("z_side", "side")))]
    return _band_figure(sig, 2.8, panels, "C1", ("predicted reading", "noiseless reading"), 3, False)


def qr_rms_figure(qr: dict[str, list[dict]], t: np.ndarray) -> Any:
    """RMS estimation error of each state over the Monte-Carlo runs, one line per (Q, R) setting."""
    from netsim.figure_style import TIME_LABEL

    fig, ax = _figure(3.6, 3)
    for name, runs in qr.items():
        E = np.stack([r["e"] for r in runs]).astype(float)
        for j in range(len(STATES)):
            ax[j].plot(t, np.sqrt(np.mean(E[:, :, j] ** 2, axis=0)), label=name, lw=0.8)
    for j, (_, sym, unit) in enumerate(STATES):
        _blackout(ax[j])
        ax[j].set_ylabel(f"RMS error {sym} ({unit})")
    n = len(next(iter(qr.values()))) if qr else 0
    ax[-1].set_xlabel(f"{TIME_LABEL}; {n} runs per setting")
    fig.legend(*ax[0].get_legend_handles_labels(), loc="outside lower center", ncols=4,
               title="filter's (Q, R) against the truth's")
    return fig


def det_p_figure(sig: Any) -> Any:
    """The determinant of the filter's covariance over time (log axis)."""
    from netsim.figure_style import TIME_LABEL

    fig, ax = _figure(1.9, 1)
    _blackout(ax[0], True)
    ax[0].semilogy(sig.index.to_numpy(float), sig["detP"].to_numpy(float), color="C0")
    ax[0].set_xlabel(TIME_LABEL)
    ax[0].set_ylabel(r"$\det P$")
    ax[0].legend(loc="upper left")
    return fig


def report_figures(out: Path, base: Any, qr: dict[str, list[dict]], t: np.ndarray) -> list[Path]:
    """Write the report's figures into ``out``: ``fig1_qr_rms``, ``fig2_bands``, ``fig3_measurements``, ``detP``
    (in the current plot format); ``base`` is the ``unicycle_ekf`` run, ``qr`` the Monte-Carlo runs by setting."""
    from netsim.figure_style import paper_style, save_figure

    out = Path(out)
    sig = base.to_pandas()
    with paper_style():
        return [save_figure(bands_figure(sig), out / "fig2_bands.png"),
                save_figure(measurements_figure(sig), out / "fig3_measurements.png"),
                save_figure(qr_rms_figure(qr, t), out / "fig1_qr_rms.png"),
                save_figure(det_p_figure(sig), out / "detP.png")]


def regenerate(out: Path, runs: int = 200, workers: int | None = 1) -> list[Path]:
    """Redraw the four figures in ``out``: the ``unicycle_ekf`` run and the Monte-Carlo runs of each (Q, R)
    setting again, as :func:`netsim.models.unicycle.report.unicycle_report` makes them (same seeds)."""
    import netsim
    from netsim.models.unicycle import studies as S
    from netsim.models.unicycle.model import Q_REPORT, R_REPORT

    from netsim.shipped import scenario_path

    base = netsim.run(scenario_path("unicycle_ekf"))
    t = np.arange(int(round(10 / 0.01)) + 1) * 0.01
    qr = {name: S.mc_runs(runs, seed0=10_000, workers=workers, Q_filter=fq * Q_REPORT, R_filter=fr * R_REPORT)
          for name, (fq, fr) in S.QR_SETTINGS.items()}
    return report_figures(out, base, qr, t)
