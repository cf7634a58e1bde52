"""The paper style, the plot format and the symbols of netsim.figure_style, and --plot-format on the CLI."""

from __future__ import annotations

from pathlib import Path

import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

from netsim.figure_style import paper_style, plot_format, save_figure, symbol  # noqa: E402


def test_paper_style_is_a_column_wide_with_8_pt_text_inside_the_block_only() -> None:
    before = matplotlib.rcParams["font.size"]
    with paper_style():
        from matplotlib.figure import Figure

        fig = Figure()
        # a two-column paper's column is 3.5 in; the text is 8 pt (the request)
        assert tuple(fig.get_size_inches())[0] == 3.5
        assert matplotlib.rcParams["font.size"] == 8 and matplotlib.rcParams["axes.labelsize"] == 8
    assert matplotlib.rcParams["font.size"] == before


@pytest.mark.parametrize("fmt, magic", [("pdf", b"%PDF"), ("svg", b"<?xml"), ("png", b"\x89PNG")])
def test_save_figure_writes_the_chosen_format(tmp_path: Path, fmt: str, magic: bytes) -> None:
    from matplotlib.figure import Figure

    with plot_format(fmt):
        path = save_figure(Figure(), tmp_path / "surface.png")
    assert path == tmp_path / f"surface.{fmt}"
    assert path.read_bytes().startswith(magic)


def test_an_unknown_plot_format_is_refused_with_the_accepted_ones() -> None:
    with pytest.raises(ValueError, match="png, pdf, svg"):
        with plot_format("jpg"):
            pass


@pytest.mark.parametrize("name, shown", [("sigma_s", r"$\sigma_{s}$"), ("et.GPI", "GPI"), ("et.Uc", "$U_{c}$"),
                                         ("delta_c", r"$\delta_{c}$"), ("act_delay", "act delay"), ("wc", "wc")])
def test_symbol_turns_names_into_printed_symbols(name: str, shown: str) -> None:
    assert symbol(name) == shown


def test_cli_report_and_sweep_take_plot_format() -> None:
    from netsim.cli.parser import build_parser

    parser = build_parser()
    assert parser.parse_args(["report", "x", "--plot-format", "pdf"]).plot_format == "pdf"
    assert parser.parse_args(["sweep", "x.yaml", "--plot-format", "svg"]).plot_format == "svg"
    assert parser.parse_args(["report", "x"]).plot_format == "png"
    with pytest.raises(SystemExit):
        parser.parse_args(["report", "x", "--plot-format", "jpg"])


def test_netsim_report_writes_pdf_figures(tmp_path: Path) -> None:
    import yaml

    import netsim
    from netsim.cli import main

    repo = Path(__file__).resolve().parents[1]
    raw = yaml.safe_load((repo / "scenarios" / "dc_servo_ideal.yaml").read_text())
    raw["duration"] = "0.2 s"
    netsim.run(raw, out=tmp_path / "run")
    assert main(["report", str(tmp_path / "run"), "--out", str(tmp_path / "rep"), "--plot-format", "pdf", "-q"]) == 0
    made = sorted(p.name for p in (tmp_path / "rep").iterdir() if p.suffix in (".pdf", ".png", ".svg"))
    assert made and all(name.endswith(".pdf") for name in made), made
    assert "response_times.pdf" in made
