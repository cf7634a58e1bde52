"""The notebook gallery of examples/ (issue 27 s3): each notebook runs top to bottom in a fresh Jupyter kernel
(nbclient), in an empty temporary folder so that it cannot lean on the checkout, and fails on its own
``assert`` cells, which check the run against numbers computed independently inside the notebook (by hand, by
python-control, by netsim.analysis.lqg, or from the metric's definition). The committed files carry no outputs.

The DC servo notebook (about 15 s) runs in the default suite; the others are slow-marked (20 s to 1 min each).
"""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
NOTEBOOKS = sorted(EXAMPLES.glob("*.ipynb"))
FAST = "01_dc_servo_can.ipynb"
SLOW = ["02_delay_jitter_lqg.ipynb", "03_threshold_sweep_surface.ipynb", "04_python_control_plant.ipynb",
        "05_pendulum_hold_still.ipynb"]


def _runner():
    """tests/examples/notebook_runner.py (a script without pytest, also run from the wheel's venv)."""
    spec = importlib.util.spec_from_file_location("notebook_runner", Path(__file__).with_name("notebook_runner.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


RUNNER = _runner()


def _execute(name: str, folder: Path) -> nbformat.NotebookNode:
    """Run the notebook in a fresh python3 kernel whose working folder is ``folder``; a failing cell raises
    :class:`nbclient.exceptions.CellExecutionError` naming the cell and its traceback."""
    return RUNNER.execute(EXAMPLES / name, folder)


def _images(nb: nbformat.NotebookNode) -> int:
    return RUNNER.image_count(nb)


def test_the_gallery_holds_the_five_studies():
    assert sorted(p.name for p in NOTEBOOKS) == sorted([FAST, *SLOW])


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_committed_notebooks_carry_no_outputs(path: Path):
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    code = [cell for cell in nb.cells if cell.cell_type == "code"]
    assert code, "a notebook without code"
    for i, cell in enumerate(code):
        assert cell.outputs == [], f"code cell {i} of {path.name} has outputs: clear them before committing"
        assert cell.execution_count is None, f"code cell {i} of {path.name} has an execution count"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebooks_read_files_only_through_the_shipped_scenarios(path: Path):
    # from an installed wheel there is no checkout: no scenarios/ folder, no path relative to the repository
    source = "\n".join(cell.source for cell in nbformat.read(path, as_version=4).cells if cell.cell_type == "code")
    assert "from netsim.shipped import scenario_path" in source
    for pattern in (r"scenarios/", r"\.parents\[", r"__file__", r"/work/", r"\.\./"):
        assert not re.search(pattern, source), f"{path.name} uses a checkout path ({pattern})"


def test_the_dc_servo_notebook_runs_and_shows_its_figures_inline(tmp_path: Path):
    nb = _execute(FAST, tmp_path)
    # result.plot(), plot_schedule(), plot_network() and the interference run's plot() display as PNGs
    assert _images(nb) >= 4
    # its run folder went to the working folder, not to the checkout
    assert (tmp_path / "dc_servo_can_run" / "meta.json").is_file()


@pytest.mark.slow
@pytest.mark.parametrize("name", SLOW)
def test_the_slow_notebooks_run(name: str, tmp_path: Path):
    nb = _execute(name, tmp_path)
    assert _images(nb) >= 1
