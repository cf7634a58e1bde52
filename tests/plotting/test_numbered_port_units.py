"""A unit declared on an io channel that names its plant port by number (``output: 0``) reaches the plant
output's axis (the cart's encoder: its position ``p`` was drawn under "unit not declared")."""

import matplotlib

matplotlib.use("Agg")

import netsim  # noqa: E402
from netsim.signal_kinds import signal_units  # noqa: E402


def test_a_numbered_port_takes_the_channels_unit_when_the_plant_names_are_known():
    io = {"io": {"enc": {"type": "encoder", "output": 0, "unit": "m"}, "u": {"type": "dac", "input": 0, "unit": "V"}}}
    assert signal_units(io) == {"enc": "m", "u": "V", "u.command": "V"}  # names unknown: the ports stay unnamed
    assert signal_units(io, (["p", "v"], ["volts"])) == {"enc": "m", "p": "m", "u": "V", "volts": "V",
                                                         "u.command": "V"}


def test_the_carts_position_is_drawn_in_metres(tmp_path):
    # scenarios/cart.yaml: enc {type: encoder, output: 0, unit: m}; the cart plant's output 0 is p
    result = netsim.run("scenarios/cart.yaml", overrides={"duration": "0.05 s"}, out=tmp_path)
    fig = result.plot()
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert any(label.endswith("(m)") for label in labels), labels
    (position_axis,) = [ax for ax in fig.axes if ax.get_ylabel().endswith("(m)")]
    assert [t.get_text() for t in position_axis.get_legend().get_texts()] == ["$p$"]  # typeset name of output p
