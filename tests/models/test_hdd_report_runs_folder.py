"""``netsim report hdd --out DIR`` keeps the GPI sweeps' run folders under DIR/runs, not under ./reports/hdd/runs
(seen from an installed wheel: a report written elsewhere still filled the working folder's reports/)."""

from pathlib import Path
from types import SimpleNamespace

import pandas as pd

from netsim.models import hdd_report as hr


def test_the_gpi_sweeps_run_under_the_reports_own_folder(tmp_path, monkeypatch):
    seen: list[Path] = []

    def fake_sweep(path, out, **_):  # stands in for the 441-point sweeps: records where they would run
        seen.append(Path(out))
        return SimpleNamespace(summary=pd.DataFrame({"sigma_s": [1e-3], "sigma_c": [1e-3], "et.GPI": [0.1]}),
                               wall_time_s=0.0, n_executed=1, n_resumed=0)

    monkeypatch.setattr(hr, "run_study_sweep", fake_sweep)
    monkeypatch.setattr(hr, "_run_variants", lambda names: {})
    out = tmp_path / "elsewhere"
    hr.collect([], runs=out / "runs")
    assert seen == [out / "runs" / "gpi", out / "runs" / "gpi_case4"]


def test_the_report_passes_its_output_folder_to_the_runs(tmp_path, monkeypatch):
    class Stop(Exception):
        pass

    def fake_collect(*args, **kwargs):
        raise Stop(kwargs.get("runs"))

    monkeypatch.setattr(hr, "collect", fake_collect)
    try:
        hr.hdd_report(tmp_path / "out", plots=False)
    except Stop as stop:
        assert stop.args[0] == tmp_path / "out" / "runs"
    else:
        raise AssertionError("hdd_report did not collect its runs")
