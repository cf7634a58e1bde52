"""netsim from Python and notebooks (issue 21): dir(netsim), netsim.run writes nothing unless asked, an exact
to_csv -> RunResult.read round trip, figures returned as matplotlib objects, a notebook summary."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import netsim
from netsim.results import RunResult

ROOT = Path(__file__).resolve().parents[1]
SERVO_CAN = ROOT / "scenarios" / "dc_servo_can.yaml"


def test_dir_lists_the_lazy_public_api():
    names = dir(netsim)
    for public in ("run", "load_scenario", "run_sweep", "make_report", "RunResult", "__version__"):
        assert public in names
    assert "_LAZY" not in names and "TYPE_CHECKING" not in names


def test_run_from_python_writes_no_folder_unless_asked(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = netsim.run(SERVO_CAN, overrides={"duration": "0.1 s"})
    assert result.out_dir is None and not (tmp_path / "reports").exists()
    assert len(result.signals) > 10 and "y.ISE" in result.metrics
    written = netsim.run(SERVO_CAN, overrides={"duration": "0.1 s"}, write=True)
    assert written.out_dir is not None and (written.out_dir / "meta.json").exists()
    assert Path(written.out_dir).resolve().is_relative_to((tmp_path / "reports").resolve())
    chosen = netsim.run(SERVO_CAN, overrides={"duration": "0.1 s"}, out=tmp_path / "mine")
    assert (tmp_path / "mine" / "signals.csv").exists() and chosen.out_dir == tmp_path / "mine"


@pytest.mark.parametrize("name, overrides", [
    ("dc_servo_can.yaml", {"duration": "0.3 s"}),
    # a radio with drops: an empty drop_reason stays text, and a run with non-empty reasons reads back too
    ("dc_servo_zigbee.yaml", {"duration": "0.3 s", "nodes.interference.tasks[0].params.share": 0.5}),
])
def test_to_csv_then_read_restores_the_same_values_and_dtypes(tmp_path, name, overrides):
    result = netsim.run(ROOT / "scenarios" / name, overrides=overrides)
    # an integer-valued float signal (the square-wave reference r holds +-1.0) must come back as float, not int64
    assert np.all(result.signals["r"].dropna() == np.round(result.signals["r"].dropna()))
    result.to_csv(tmp_path / "run")
    back = RunResult.read(tmp_path / "run")
    for table in ("signals", "jobs", "messages"):
        pd.testing.assert_frame_equal(getattr(back, table), getattr(result, table), check_exact=True)
    pd.testing.assert_series_equal(back.metrics, result.metrics, check_exact=True)
    assert back.signals["r"].dtype == np.float64


def test_plots_are_matplotlib_figures_and_save_writes_the_pngs(tmp_path):
    from matplotlib.figure import Figure

    result = netsim.run(SERVO_CAN, overrides={"duration": "0.2 s"})
    fig = result.plot()
    assert isinstance(fig, Figure) and len(fig.axes) == 2  # outputs and references; actuator
    assert isinstance(result.plot_schedule(window=(0.0, 0.05)), Figure)
    assert isinstance(result.plot_network(), Figure)
    assert isinstance(result.plot(save=tmp_path / "figs"), Figure)
    assert sorted(p.name for p in (tmp_path / "figs").glob("*.png")) == ["network.png", "responses.png",
                                                                        "schedule.png"]


def test_notebook_summary_shows_status_duration_and_key_metrics():
    result = netsim.run(SERVO_CAN, overrides={"duration": "0.2 s"})
    html = result._repr_html_()
    assert "dc_servo_can" in html and ">ok<" in html and "0.2 s simulated" in html
    # control first, then timing: the first metric row is the loop's ISE family, the CAN loss row comes later
    rows = re.findall(r"<tr><td>([^<]*)</td>", html)
    assert rows[0].startswith("y.") and "net.can" in rows and rows.index("net.can") > rows.index("y.ISE")
    assert "worst delay 1 ms" in html  # the CAN frame delay at 80 kbit/s: net.can.max_delay_s = 0.001
    frame = result.to_pandas()
    assert frame.index.name == "time_s" and list(frame.columns) == list(result.signals.columns[1:])


def _readme_block(title: str) -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text[text.index(title):]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_the_readme_from_python_example_runs(tmp_path, monkeypatch):
    code = _readme_block("### From Python").replace('"scenarios/', f'"{ROOT}/scenarios/')
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(code, "README.md", "exec"), scope)  # noqa: S102 - the README's own example
    assert (tmp_path / "responses.pdf").stat().st_size > 5000
    assert (tmp_path / "out" / "run" / "meta.json").exists()
    pd.testing.assert_frame_equal(scope["back"].signals, scope["result"].signals, check_exact=True)
    assert not (tmp_path / "reports").exists()  # netsim.run from Python wrote no folder of its own


def test_the_readme_shows_one_figure_of_each_kind():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    for name in ("responses", "schedule", "network", "surface"):
        assert f"](docs/figures/{name}.png)" in text
        assert (ROOT / "docs" / "figures" / f"{name}.png").stat().st_size > 5000


def test_an_empty_result_still_plots_and_summarises():
    from matplotlib.figure import Figure

    empty = RunResult()
    assert all(isinstance(f, Figure) for f in (empty.plot(), empty.plot_schedule(), empty.plot_network()))
    assert empty._repr_html_() == "<div><b>run</b>: <span style='color:green'>ok</span><p>no metrics</p></div>"
