"""The radio Monte-Carlo part of the 2WD cart README (netsim.models.unicycle.readme_net.radio_mc_section) and its splice
into an existing report folder (splice_radio_mc, used by ``netsim report unicycle_radio_mc``).

Since issue 26 s7 the radios draw ``loss:`` per transmission attempt before the ACK, so the section must quote
two different shares from the runs: the attempts the loss model erased (``lost_attempts / attempts``) and the
messages lost after the MAC's retries (``loss_rate``). The sweeps here are constructed, with values chosen so
that every expected number is a hand computation written next to it.
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

from netsim.models.unicycle.quoting import Quotes, fill
from netsim.models.unicycle.readme_net import RADIO_MC_MARK, loss_params, radio_mc_section, splice_radio_mc
from netsim.models.unicycle.report import _Table

BERN = {"model": "bernoulli", "p": 0.3}
GE = {"model": "gilbert_elliott", "p_good_to_bad": 0.06, "p_bad_to_good": 0.14}
NONE = {"model": "bernoulli", "p": 0.0}


def _run(period: str, loss: dict, *, erased: float | None, lost: float, theta: float) -> dict:
    row = {"sensor_period": period, "loss_model": json.dumps(loss), "status": "ok",
           "net.radio.attempts": 1000.0, "net.radio.messages": 800.0, "net.radio.loss_rate": lost,
           "net.radio.mean_delay_s": 0.003, "unicycle.cover_x_all": 0.95, "unicycle.cover_y_all": 0.9,
           "unicycle.cover_theta_all": 0.8, "unicycle.rmse_y_front": 0.012, "unicycle.rmse_theta_all": theta,
           "control.ekf.filter.fused_front": 200.0, "control.ekf.filter.fused_side": 100.0,
           "control.ekf.filter.late": 150.0}
    if erased is not None:  # the radio reports lost_attempts only when a loss model is set
        row["net.radio.lost_attempts"] = erased * 1000.0
    return row


def _sweep(burst_theta: tuple[float, ...] = (0.10, 0.11, 0.12)) -> pd.DataFrame:
    rows = []
    for period in ("40 ms", "100 ms"):
        for th in (0.070, 0.071, 0.072):  # no loss: no lost_attempts metric at all
            rows.append(_run(period, NONE, erased=None, lost=0.001, theta=th))
        for er, lo, th in ((0.28, 0.01, 0.070), (0.30, 0.02, 0.071), (0.32, 0.03, 0.072)):
            rows.append(_run(period, BERN, erased=er, lost=lo, theta=th))
        for er, lo, th in zip((0.25, 0.30, 0.35), (0.06, 0.08, 0.10), burst_theta):
            rows.append(_run(period, GE, erased=er, lost=lo, theta=th))
    return pd.DataFrame(rows)


def _section(df: pd.DataFrame) -> tuple[Quotes, _Table, list[str]]:
    q, T = Quotes(), _Table()
    q.section = "s5"
    return q, T, radio_mc_section(q, T, {"radio_mc": df})


def test_radio_section_quotes_erased_attempts_and_lost_messages_separately() -> None:
    q, T, lines = _section(_sweep())
    v = {k: value for k, (value, _text, _source) in q.rows.items()}
    # attempts erased = mean(lost_attempts / attempts) = mean(0.28, 0.30, 0.32) = 0.30; messages lost = mean of
    # loss_rate = mean(0.01, 0.02, 0.03) = 0.02 (Bernoulli); bursts: mean(0.25, 0.30, 0.35), mean(0.06, 0.08, 0.10)
    assert v["s5.rm_25hz_bern_erased"] == pytest.approx(0.30)
    assert v["s5.rm_25hz_bern_lost"] == pytest.approx(0.02)
    assert v["s5.rm_10hz_burst_erased"] == pytest.approx(0.30)
    assert v["s5.rm_10hz_burst_lost"] == pytest.approx(0.08)
    assert v["s5.rm_25hz_none_erased"] == 0.0  # no loss model: nothing erased (the metric is absent)
    assert v["s5.rm_25hz_bern_apm"] == pytest.approx(1000 / 800)  # attempts per message
    assert v["s5.radio_runs"] == 3.0
    # the burst model's stationary bad share p_gb / (p_gb + p_bg) = 0.06 / 0.2 and mean burst 1 / 0.14 attempts
    assert v["s5.rm_bad_share"] == pytest.approx(0.3)
    assert v["s5.rm_burst_len"] == pytest.approx(1 / 0.14)
    text = Quotes.render("\n".join(lines))
    assert lines[0] == RADIO_MC_MARK[0] and RADIO_MC_MARK[1] in lines
    assert "before the ACK" in text and "per attempt" in text and "after the radio's MAC" not in text
    assert "| 25 Hz | Bernoulli | 3 | 30.0 % | 2.0 % | 1.25 |" in text
    rows = T.frame()
    assert set(rows["quantity"]) >= {"messages lost", "attempts erased"}
    assert rows["setting"].str.endswith(" runs").all()


def test_radio_section_verdict_follows_the_two_standard_error_test() -> None:
    # bursts 0.10-0.12 against 0.070-0.072 without loss: difference 0.039, two standard errors
    # 2 * sqrt(0.01^2 / 3 + 0.001^2 / 3) = 0.0116, beyond; Bernoulli equal to no loss: within
    text = Quotes.render("\n".join(_section(_sweep())[2]))
    assert "bursts move the mean heading error beyond two standard errors; independent loss does not" in text
    # bursts spread around the no-loss mean: neither kind is beyond
    calm = Quotes.render("\n".join(_section(_sweep((0.05, 0.071, 0.09)))[2]))
    assert "neither independent loss nor bursts moves the mean heading error beyond two standard errors" in calm


def test_loss_params_reads_the_sweeps_cells() -> None:
    assert loss_params(json.dumps(GE)) == GE
    assert loss_params(str(BERN)) == BERN  # Python text of a dict
    assert loss_params(BERN) is BERN


def _legacy_report(folder: Path) -> None:
    """A report folder written before the markers: section 5 opens with the radio study (keys s5.n1-n3), then
    the CAN part (s5.n4) follows; table.csv has two radio Monte-Carlo rows and the one-run radio row."""
    template = "\n".join([
        "# Report {s0.a}", "", "## 5. What only a networked simulator shows", "",
        "802.15.4 radio (`unicycle_radio_mc.yaml`, base `unicycle_zigbee.yaml`): loss after the MAC, "
        "{s5.radio_runs} runs.", "", "| a |", "|---|", "| {s5.n1} |", "",
        "- Rate: {s5.n2}", "- Loss: {s5.n3} of the frames", "",
        "CAN bus: {s5.n4} runs.", ""])
    quoted = pd.DataFrame({"key": ["s0.a", "s5.radio_runs", "s5.n1", "s5.n2", "s5.n3", "s5.n4"],
                           "value": ["1.0", "200.0", "0.5", "2.0", "0.3", "20.0"],
                           "text": ["1", "200", "50.0 %", "2", "30.0 %", "20"]})
    (folder / "template.md").write_text(template)
    (folder / "README.md").write_text(fill(template, dict(zip(quoted["key"], quoted["text"]))))
    quoted.to_csv(folder / "quoted.csv", index=False)
    pd.DataFrame({"experiment": ["4 LQR", "5 radio", "5 radio", "5 radio", "5 CAN"],
                  "setting": ["a", "25 Hz, none, 200 runs", "25 Hz, Bernoulli, 200 runs", "802.15.4 radio, one run",
                              "b"],
                  "quantity": ["q"] * 5, "ours": ["1", "2", "3", "320", "5"], "source": [""] * 5,
                  "reason": [""] * 5}).to_csv(folder / "table.csv", index=False)


def test_splice_replaces_only_the_radio_section_its_keys_and_rows(tmp_path: Path) -> None:
    _legacy_report(tmp_path)
    q, T, lines = _section(_sweep())
    splice_radio_mc(tmp_path, lines, q.frame(source=False), T.frame())
    readme, template = (tmp_path / "README.md").read_text(), (tmp_path / "template.md").read_text()
    quoted = pd.read_csv(tmp_path / "quoted.csv", dtype=str, keep_default_na=False)
    assert fill(template, dict(zip(quoted["key"], quoted["text"]))) == readme
    assert not {"s5.n1", "s5.n2", "s5.n3"} & set(quoted["key"])  # the old section's quotes are gone
    assert {"s0.a", "s5.n4", "s5.radio_runs", "s5.rm_25hz_bern_lost"} <= set(quoted["key"])
    keys = list(quoted["key"])
    assert keys[0] == "s0.a" and keys[-1] == "s5.n4"  # the new quotes sit where the old ones were
    assert "loss after the MAC" not in readme and "of the frames" not in readme
    assert readme.startswith("# Report 1\n\n## 5. What only a networked simulator shows\n\n" + RADIO_MC_MARK[0])
    assert readme.endswith(RADIO_MC_MARK[1] + "\n\nCAN bus: 20 runs.\n")
    table = pd.read_csv(tmp_path / "table.csv", dtype=str, keep_default_na=False)
    assert list(table["experiment"][:1]) == ["4 LQR"] and list(table["experiment"][-2:]) == ["5 radio", "5 CAN"]
    assert "802.15.4 radio, one run" in set(table["setting"])  # not a Monte-Carlo row: kept
    assert not table["setting"].str.endswith("200 runs").any()
    assert (table["setting"].str.endswith("3 runs")).sum() == len(T.frame()) == 6 * 6
    # a second splice finds the markers and writes the same files
    before = {n: (tmp_path / n).read_text() for n in ("README.md", "template.md", "quoted.csv", "table.csv")}
    q2, T2, lines2 = _section(_sweep())
    splice_radio_mc(tmp_path, lines2, q2.frame(source=False), T2.frame())
    assert {n: (tmp_path / n).read_text() for n in before} == before
