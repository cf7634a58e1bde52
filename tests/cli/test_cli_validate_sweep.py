"""``netsim validate`` on sweep files: the sweep schema, the base scenario and every factor level."""

from __future__ import annotations

import textwrap
from pathlib import Path

from netsim.cli import main


def _sweep(folder: Path, good: str, factors: str) -> Path:
    (folder / "base.yaml").write_text(good)
    path = folder / "sweep.yaml"
    path.write_text("sweep: s\nbase: base.yaml\nseed: 1\nfactors:\n" + textwrap.indent(textwrap.dedent(factors), "  "))
    return path


def test_valid_sweep_is_reported_valid(tmp_path, capsys, good):
    path = _sweep(tmp_path, good, """\
        rate:
          paths:
            - networks.net.bitrate
          values: [80 kbit/s, 1 Mbit/s]
        """)
    assert main(["validate", str(path)]) == 0
    assert capsys.readouterr().out == f"{path}: valid\n"


def test_a_bad_factor_value_is_reported_with_its_point_and_path(tmp_path, capsys, good):
    # a bit rate must be positive (netsim.units.Bitrate): '-5 kbit/s' is wrong, the other two are fine
    path = _sweep(tmp_path, good, """\
        rate:
          paths:
            - networks.net.bitrate
          values: [80 kbit/s, -5 kbit/s, 1 Mbit/s]
        """)
    assert main(["validate", str(path)]) == 1
    out = capsys.readouterr().out
    assert "point (rate='-5 kbit/s'): networks.net.bitrate: " in out
    assert "80 kbit/s'" not in out and "1 Mbit/s'" not in out


def test_a_misspelt_factor_path_gets_a_suggestion(tmp_path, capsys, good):
    path = _sweep(tmp_path, good, """\
        rate:
          paths:
            - networks.net.bitrat
          values: [1000]
        """)
    assert main(["validate", str(path)]) == 1
    out = capsys.readouterr().out
    assert "did you mean 'bitrate'" in out
    assert out.count(str(path)) == 1  # the file is named once per problem line


def test_a_parameter_left_at_its_default_can_be_swept(tmp_path, capsys, good):
    # the base scenario does not write the task's deadline (default: its period): the factor sets it
    path = _sweep(tmp_path, good, """\
        deadline:
          paths:
            - nodes.a.tasks[0].deadline
          values: [5 ms, 8 ms]
        """)
    assert main(["validate", str(path)]) == 0, capsys.readouterr().out
    from netsim.sweep.spec import load_sweep

    sweep = load_sweep(path)
    assert [sweep.point_raw(p)["nodes"]["a"]["tasks"][0]["deadline"] for p in sweep.points] == ["5 ms", "8 ms"]


def test_an_absent_key_that_is_no_parameter_is_reported_per_level(tmp_path, capsys, good):
    # 'colour' is close to no key of networks.net, so the path check lets it through; the network's parameter
    # model then refuses it at each level
    path = _sweep(tmp_path, good, """\
        colour:
          paths:
            - networks.net.colour
          values: [red]
        """)
    assert main(["validate", str(path)]) == 1
    out = capsys.readouterr().out
    assert "point (colour='red')" in out and "colour" in out.split("point (colour='red')", 1)[1]


def test_shipped_sweep_files_validate(capsys):
    files = sorted(str(p) for p in Path("scenarios").glob("*.yaml") if "sweep:" in p.read_text())
    assert len(files) >= 3  # hdd_gpi_sweep, cart_fig2, cart_quant
    assert main(["validate", *files]) == 0
