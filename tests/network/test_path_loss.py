"""Path-loss models as plugins (issue 30, TrueTime's user path-loss function): built-ins against their formulas
computed here, a user's model changing who receives, and a plugin file refused without the user's permission."""

from __future__ import annotations

import math
import textwrap

import pytest

from netsim.errors import ConfigError
from netsim.network import make_network
from netsim.network.path_loss import PathLoss
from netsim.registry import register
from netsim.scenario.loader import check_scenario
from netsim.timebase import MS
from netsim.units import StrictModel


@register("path_loss", "test_linear_db_per_metre", "test double: a loss of k dB per metre")
class LinearLoss(PathLoss):
    """P_rx = P_tx - k d: easy to compute by hand."""

    class Params(StrictModel):
        db_per_metre: float = 6.0

    def loss_db(self, distance_m: float) -> float:
        return self.params.db_per_metre * distance_m


RADIO = {"nodes": ["a", "b", "c"], "positions": {"a": [0, 0], "b": [10, 0], "c": [0, 20]}, "acks": False}


def _received(bench, params):
    b = bench("802.15.4", {**RADIO, **params})
    b.send_at(0, "a", None, 64, tag="bcast")
    b.run(50 * MS)
    return b


def test_a_plugin_path_loss_changes_reception_as_computed_by_hand(bench):
    # default exponent model, a = 3.5, d0 = 1 m, 0 dBm: b at 10 m gets -35 dBm, c at 20 m -35 log10(20) = -45.5 dBm,
    # both above the -85 dBm threshold: both receive the broadcast
    default = _received(bench, {})
    assert [len(default.rx[n].got) for n in ("b", "c")] == [1, 1]
    # 6 dB per metre: b at 10 m gets 0 - 60 = -60 dBm (>= -85: received), c at 20 m 0 - 120 = -120 dBm (< -85: not)
    plugin = _received(bench, {"path_loss": {"type": "test_linear_db_per_metre", "db_per_metre": 6}})
    assert plugin.net.received_power_dbm("a", "b") == pytest.approx(-60.0, abs=1e-12)
    assert plugin.net.received_power_dbm("a", "c") == pytest.approx(-120.0, abs=1e-12)
    assert len(plugin.rx["b"].got) == 1 and plugin.rx["c"].got == []
    (lost,) = [r for r in plugin.net.records if r.receiver == "c"]
    assert lost.drop_reason == "out_of_range"


def test_free_space_is_friis_computed_from_the_wavelength():
    from netsim.env import SimEnv

    net = make_network(SimEnv(), "r", "802.15.4", {
        **RADIO, "transmit_power_dbm": 3.0,
        "path_loss": {"type": "free_space", "frequency_hz": 2.4e9, "tx_gain_dbi": 2.0}})
    # Friis by hand: lambda = c / f = 299792458 / 2.4e9 = 0.1249 m; loss = 20 log10(4 pi d / lambda), d = 10 m
    wavelength = 299_792_458.0 / 2.4e9
    loss = 20 * math.log10(4 * math.pi * 10.0 / wavelength)  # about 60.05 dB
    assert net.received_power_dbm("a", "b") == pytest.approx(3.0 + 2.0 - loss, abs=1e-9)


def test_log_distance_adds_the_reference_loss_to_the_exponent_law():
    from netsim.env import SimEnv

    net = make_network(SimEnv(), "r", "802.15.4", {
        **RADIO, "path_loss": {"type": "log_distance", "exponent": 3, "reference_loss_db": 40}})
    # 0 dBm - 40 dB - 10 x 3 x log10(10 m / 1 m) = -70 dBm; at 20 m: -40 - 30 log10(20) = -79.03 dBm
    assert net.received_power_dbm("a", "b") == pytest.approx(-70.0, abs=1e-12)
    assert net.received_power_dbm("a", "c") == pytest.approx(-40.0 - 30 * math.log10(20), abs=1e-12)


def test_the_default_equals_the_exponent_model_written_out():
    from netsim.env import SimEnv

    default = make_network(SimEnv(), "r", "802.15.4", {**RADIO, "path_loss_exponent": 2.7})
    written = make_network(SimEnv(), "r", "802.15.4", {**RADIO, "path_loss": {"type": "exponent", "exponent": 2.7}})
    for rx in ("b", "c"):
        assert default.received_power_dbm("a", rx) == written.received_power_dbm("a", rx)
    assert default.received_power_dbm("a", "b") == -27.0  # 0 - 10 x 2.7 x log10(10)


def test_bad_path_loss_settings_are_refused():
    from netsim.env import SimEnv

    cases = [({"type": "free_spaec"}, "did you mean 'free_space'"),
             ({"type": "log_distance", "exponent": -1}, "log_distance: exponent"),
             ({"exponent": 2}, "give the model's type"),
             ({"type": "exponent", "bogus": 1}, "bogus")]
    for spec, text in cases:
        with pytest.raises(ConfigError, match=text):
            make_network(SimEnv(), "r", "802.15.4", {**RADIO, "path_loss": spec})
    with pytest.raises(ConfigError, match="give either path_loss or path_loss_exponent"):
        make_network(SimEnv(), "r", "802.15.4", {**RADIO, "path_loss_exponent": 2, "path_loss": {"type": "exponent"}})


PLUGIN = '''
from netsim.network.path_loss import PathLoss
from netsim.registry import register


@register("path_loss", "test_file_wall", "test double from a plugin file")
class Wall(PathLoss):
    def loss_db(self, distance_m):
        return 200.0
'''


def _scenario_file(tmp_path):
    (tmp_path / "wall.py").write_text(PLUGIN, encoding="utf-8")
    (tmp_path / "s.yaml").write_text(textwrap.dedent("""\
        name: wall
        duration: 10 ms
        plugins: [wall.py]
        nodes: {a: {}, b: {}}
        networks:
          r:
            type: ieee802154
            nodes: [a, b]
            positions: {a: [0, 0], b: [1, 0]}
            path_loss: {type: test_file_wall}
        """), encoding="utf-8")
    return tmp_path / "s.yaml"


def test_a_scenario_naming_a_path_loss_plugin_is_refused_without_permission(tmp_path):
    path = _scenario_file(tmp_path)
    refused = [(p.path, p.message) for p in check_scenario(path, allow_plugins=False) if p.severity == "error"]
    assert ("plugins[0]", f"this scenario loads code from {tmp_path / 'wall.py'}; rerun with --allow-plugins if you "
            "trust it (Python: allow_plugins=True)") in refused
    from netsim.registry import plugin_file_loaded

    assert not plugin_file_loaded(tmp_path / "wall.py")  # the model's code never ran


def test_the_same_scenario_is_valid_with_permission(tmp_path):
    path = _scenario_file(tmp_path)
    assert [p.message for p in check_scenario(path, allow_plugins=True) if p.severity == "error"] == []


@register("path_loss", "test_nan_loss", "test double: a broken model")
class NanLoss(PathLoss):
    def loss_db(self, distance_m: float) -> float:
        return float("nan")


def test_a_model_that_returns_no_finite_power_is_reported_with_its_name(bench):
    b = bench("802.15.4", {**RADIO, "path_loss": {"type": "test_nan_loss"}})
    b.send_at(0, "a", None, 64)
    with pytest.raises(ConfigError, match="path-loss model 'test_nan_loss' gave nan dBm from 'a' to"):
        b.run(10 * MS)
