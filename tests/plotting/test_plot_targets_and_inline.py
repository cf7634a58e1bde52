"""Plot methods draw where they are told and show inline in Jupyter (issue 27 s2): ``ax=`` for one-axes charts,
``fig=`` for the multi-panel responses figure, and a returned figure that a fresh Jupyter kernel displays as a
PNG without ``%matplotlib inline`` (before, it printed ``<Figure size 900x620 with 2 Axes>``)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

import netsim

ROOT = Path(__file__).resolve().parents[2]
SERVO_CAN = ROOT / "scenarios" / "dc_servo_can.yaml"


@pytest.fixture(scope="module")
def result():
    return netsim.run(SERVO_CAN, overrides={"duration": "0.1 s"})


def test_ax_and_fig_are_drawn_into_and_returned(result):
    from matplotlib.figure import Figure

    mine = Figure()
    top, bottom = mine.subplots(2, 1)
    assert result.plot_schedule(ax=top) is mine and result.plot_network(ax=bottom) is mine
    assert top.get_yticklabels()[0].get_text().startswith("actuator.")  # the Gantt chart's first row, on `top`
    assert bottom.get_ylabel() == "network: sender" and len(mine.axes) == 2  # nothing added
    panels = Figure()
    assert result.plot(fig=panels) is panels and len(panels.axes) == 2  # outputs and references; actuator
    sub = Figure().subfigures(1, 2)[1]
    assert result.plot(fig=sub) is sub and len(sub.axes) == 2


def test_a_returned_figure_has_a_png_repr(result):
    for fig in (result.plot(), result.plot_schedule(), result.plot_network()):
        assert fig._repr_png_()[:4] == b"\x89PNG"


def test_a_fresh_jupyter_kernel_shows_each_plot_inline(tmp_path):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    setup = (f"import netsim\nassert netsim.__file__.startswith({str(ROOT)!r}), netsim.__file__\n"
             f"result = netsim.run({str(SERVO_CAN)!r}, overrides={{'duration': '0.1 s'}})")
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(src) for src in (
        setup, "result.plot()", "result.plot_schedule()", "result.plot_network()")])
    # a kernel as Jupyter starts one: its default (inline) backend named, but pyplot never imported
    env_backup = os.environ.get("MPLBACKEND")
    os.environ.pop("MPLBACKEND", None)
    try:
        client = nbclient.NotebookClient(nb, timeout=240, kernel_name="python3",
                                         resources={"metadata": {"path": str(ROOT)}})
        client.execute()
    finally:
        if env_backup is not None:
            os.environ["MPLBACKEND"] = env_backup
    for cell in nb.cells[1:]:
        data = [out.get("data", {}) for out in cell.outputs if out.get("output_type") == "execute_result"]
        assert data and "image/png" in data[0], json.dumps(cell.outputs)[:500]
