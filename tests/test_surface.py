"""GPI surface: the optimum is the arg-min of the stored surface (computed here with plain numpy)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from netsim.errors import ConfigError
from netsim.sweep.surface import describe_optimum, find_optimum, load_surface, surface_from_summary


def _summary(path: Path, z: np.ndarray, xs: np.ndarray, ys: np.ndarray, *, replicates: int = 1,
             failed: set[int] = frozenset()) -> Path:
    rows, index = [], 0
    rng = np.random.default_rng(3)  # test data only (not simulation randomness)
    for i, x in enumerate(xs):
        for j, y in enumerate(ys):
            for r in range(replicates):
                noise = 0.0 if replicates == 1 else rng.normal(0, 0.01)
                ok = index not in failed
                rows.append({"index": index, "replicate": r, "sx": x, "sy": y,
                             "GPI": z[i, j] + noise if ok else np.nan, "Uc": x, "status": "ok" if ok else "error"})
                index += 1
    pd.DataFrame(rows).to_csv(path, index=False)
    return path


def test_optimum_is_the_argmin_of_the_stored_surface(tmp_path: Path) -> None:
    xs, ys = np.logspace(-7, -3, 21), np.logspace(-4, 0, 21)
    X, Y = np.meshgrid(np.log10(xs), np.log10(ys), indexing="ij")
    z = (X + 5.2) ** 2 + 0.5 * (Y + 1.9) ** 2 + 0.1 * np.sin(3 * X)  # a bowl with a wiggle
    path = _summary(tmp_path / "summary.csv", z, xs, ys, failed={5, 77})
    opt, files = surface_from_summary(path, x="sx", y="sy", z="GPI", logx=True, logy=True, out=tmp_path)
    stored = pd.read_csv(files["surface"])
    k = int(np.nanargmin(stored["GPI"].to_numpy()))
    assert (opt["x_value"], opt["y_value"], opt["z_value"]) == tuple(stored.loc[k, ["sx", "sy", "GPI"]])
    i, j = np.unravel_index(np.argmin(z), z.shape)  # independent: arg-min of the generating grid
    assert (opt["x_value"], opt["y_value"]) == (xs[i], ys[j])
    assert json.loads(files["optimum"].read_text())["index"] == opt["index"] == i * 21 + j
    assert opt["missing"] == 2 and stored["GPI"].isna().sum() == 2
    assert files["figure"].stat().st_size > 20_000
    assert "GPI = " in describe_optimum(opt) and "sx = " in describe_optimum(opt)


def test_replicates_are_averaged_before_the_argmin(tmp_path: Path) -> None:
    xs, ys = np.array([1.0, 2.0, 3.0]), np.array([10.0, 20.0])
    z = np.array([[3.0, 2.0], [1.0, 4.0], [5.0, 6.0]])
    path = _summary(tmp_path / "s.csv", z, xs, ys, replicates=3)
    surf = load_surface(path, x="sx", y="sy", z="GPI")
    df = pd.read_csv(path)
    means = df.groupby(["sx", "sy"])["GPI"].mean()
    assert surf.Z.shape == (2, 3)
    assert math.isclose(surf.Z[0, 1], means[(2.0, 10.0)], rel_tol=1e-12)
    opt = find_optimum(surf)
    assert (opt["x_value"], opt["y_value"], opt["runs"]) == (2.0, 10.0, 3)
    assert math.isclose(opt["metrics"]["Uc"], 2.0)


def test_ties_go_to_the_first_cell_in_sweep_order(tmp_path: Path) -> None:
    z = np.array([[2.0, 1.0], [1.0, 3.0]])
    surf = load_surface(_summary(tmp_path / "s.csv", z, np.array([1.0, 2.0]), np.array([1.0, 2.0])),
                        x="sx", y="sy")
    assert find_optimum(surf)["index"] == 1


def test_surface_without_successful_runs_or_with_unknown_column_is_refused(tmp_path: Path) -> None:
    z = np.ones((2, 2))
    path = _summary(tmp_path / "s.csv", z, np.array([1.0, 2.0]), np.array([1.0, 2.0]), failed={0, 1, 2, 3})
    with pytest.raises(ConfigError, match="nothing to minimise"):
        find_optimum(load_surface(path, x="sx", y="sy"))
    with pytest.raises(ConfigError, match="no column 'sigma'"):
        load_surface(path, x="sigma", y="sy")
