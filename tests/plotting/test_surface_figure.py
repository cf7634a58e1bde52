"""The GPI heat map places each cell at its log-spaced edges (issue 21) and keeps the legend off the cells."""

from __future__ import annotations

import numpy as np
import pandas as pd

from netsim.sweep.surface import Surface, cell_edges, find_optimum, surface_figure


def test_log_cell_edges_are_geometric_midpoints_and_every_cell_is_equally_wide_in_log10():
    xs = np.logspace(-9, -1, 21)
    edges = cell_edges(xs, log=True)
    assert len(edges) == 22
    # independent: half a decade step (0.4 decades) on each side of each centre, in log10
    np.testing.assert_allclose(np.log10(edges), np.linspace(-9.2, -0.8, 22), atol=1e-12)
    assert np.all(np.diff(np.log10(edges)) > 0.39)  # no sliver column: pcolormesh(shading="nearest") gave the
    # first column edges at linear midpoints, [1e-9 - 2.5e-9 ...]: a negative or vanishing width on a log axis


def test_linear_cell_edges_are_arithmetic_midpoints():
    np.testing.assert_allclose(cell_edges(np.array([1.0, 2.0, 4.0]), log=False), [0.5, 1.5, 3.0, 5.0])


def _surface() -> Surface:
    xs, ys = np.logspace(-7, -3, 5), np.logspace(-4, 0, 4)
    X, Y = np.meshgrid(xs, ys)
    Z = (np.log10(X) + 5) ** 2 + (np.log10(Y) + 2) ** 2
    cells = pd.DataFrame({"x": X.ravel(), "y": Y.ravel(), "z": Z.ravel(), "runs": 1, "index": np.arange(Z.size)})
    return Surface(x="sigma_s", y="sigma_c", z="et.GPI", cells=cells, xs=xs, ys=ys, Z=Z, logx=True, logy=True)


def test_heat_map_uses_the_log_edges_on_log_axes_and_the_optimum_is_named_outside_the_cells():
    surf = _surface()
    fig = surface_figure(surf, find_optimum(surf))
    heat = fig.axes[0]
    assert heat.get_xscale() == "log" and heat.get_yscale() == "log"
    mesh = heat.collections[0]
    coords = mesh.get_coordinates()  # (ny + 1, nx + 1, 2): the cell corners
    np.testing.assert_allclose(coords[0, :, 0], cell_edges(surf.xs, True))
    np.testing.assert_allclose(coords[:, 0, 1], cell_edges(surf.ys, True))
    assert heat.get_xlim()[0] <= cell_edges(surf.xs, True)[0] * 1.0000001  # the first column is whole
    assert heat.get_ylim()[0] <= cell_edges(surf.ys, True)[0] * 1.0000001  # the bottom row is not cut
    assert heat.get_legend() is None  # the optimum is written in the title (issue 27), above the cells
    assert heat.get_title().startswith("min GPI = ")
    assert heat.get_xlabel() == r"$\sigma_{s}$" and heat.get_ylabel() == r"$\sigma_{c}$"
