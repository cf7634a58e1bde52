"""One look for the figures of reports and sweeps: a paper column, symbols for names, one file format.

:data:`PAPER_STYLE` is a matplotlib style (rc parameters) for a figure one journal column wide
(:data:`COLUMN_WIDTH_IN` = 3.5 in) with 8 pt text; :func:`paper_style` applies it to the figures created and
saved inside a ``with`` block. :func:`plot_format` sets the format that :func:`save_figure` writes (``png``,
``pdf`` or ``svg``: ``netsim report --plot-format`` and ``netsim sweep --plot-format``). :func:`symbol` turns
a factor or metric name into its printed symbol (``sigma_s`` -> :math:`\\sigma_s`, ``et.GPI`` -> GPI), so no
figure shows a raw identifier.

Examples
--------
>>> from netsim.figure_style import paper_style, plot_format, save_figure
>>> with paper_style(), plot_format("pdf"):                         # doctest: +SKIP
...     fig = make_figure()
...     save_figure(fig, "reports/x/surface.png")                    # writes reports/x/surface.pdf
"""

from __future__ import annotations

import contextlib
import contextvars
import re
from pathlib import Path
from typing import Any, Iterator

__all__ = [
    "COLUMN_WIDTH_IN",
    "PAPER_STYLE",
    "PLOT_FORMATS",
    "paper_style",
    "plot_format",
    "current_format",
    "save_figure",
    "symbol",
    "TIME_LABEL",
]

#: Width of one column of a two-column paper, in inches.
COLUMN_WIDTH_IN = 3.5

#: The one time-axis label of the report figures.
TIME_LABEL = "time (s)"

#: matplotlib rc parameters of the paper style: 8 pt text, a 3.5 in wide figure, inward ticks on every
#: axis (one tick style), fonts embedded as text in PDF and SVG.
PAPER_STYLE: dict[str, Any] = {
    "figure.figsize": (COLUMN_WIDTH_IN, 2.6),
    "figure.dpi": 100,
    "font.size": 8,
    "axes.titlesize": 8,
    "axes.labelsize": 8,
    "legend.fontsize": 7,
    "legend.frameon": False,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "xtick.direction": "in",
    "ytick.direction": "in",
    "xtick.top": True,
    "ytick.right": True,
    "xtick.major.size": 3,
    "ytick.major.size": 3,
    "xtick.minor.size": 1.5,
    "ytick.minor.size": 1.5,
    "axes.linewidth": 0.6,
    "lines.linewidth": 1.0,
    "lines.markersize": 4,
    "grid.linewidth": 0.4,
    "grid.alpha": 0.4,
    "axes.formatter.use_mathtext": True,
    "mathtext.fontset": "dejavusans",
    "savefig.dpi": 300,
    "savefig.bbox": "tight",
    "savefig.pad_inches": 0.02,
    "pdf.fonttype": 42,
    "svg.fonttype": "none",
}

#: The file formats :func:`save_figure` writes.
PLOT_FORMATS = ("png", "pdf", "svg")

_FORMAT: contextvars.ContextVar[str] = contextvars.ContextVar("netsim_plot_format", default="png")

_GREEK = ("alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "kappa", "lambda", "mu", "nu",
          "xi", "pi", "rho", "sigma", "tau", "phi", "chi", "psi", "omega")
_SYMBOL = re.compile(r"^(?P<head>[A-Za-z]+)_(?P<sub>[A-Za-z0-9]+)$")


@contextlib.contextmanager
def paper_style() -> Iterator[None]:
    """Apply :data:`PAPER_STYLE` to the figures made and saved in the ``with`` block."""
    import matplotlib

    # matplotlib types rc as a dict keyed by a Literal of every rcParam name; PAPER_STYLE's keys are plain str
    with matplotlib.rc_context(PAPER_STYLE):  # type: ignore[arg-type]
        yield


@contextlib.contextmanager
def plot_format(fmt: str | None) -> Iterator[str]:
    """Make :func:`save_figure` write ``fmt`` (``png``, ``pdf`` or ``svg``; None keeps the current one).

    Raises
    ------
    ValueError
        For any other format, naming the accepted ones.
    """
    fmt = current_format() if fmt is None else str(fmt).lower().lstrip(".")
    if fmt not in PLOT_FORMATS:
        raise ValueError(f"plot format '{fmt}' is not one of {', '.join(PLOT_FORMATS)}")
    token = _FORMAT.set(fmt)
    try:
        yield fmt
    finally:
        _FORMAT.reset(token)


def current_format() -> str:
    """The format :func:`save_figure` writes now (``png`` unless :func:`plot_format` says otherwise)."""
    return _FORMAT.get()


def save_figure(fig: Any, path: str | Path, **kwargs: Any) -> Path:
    """Save ``fig`` at ``path`` with the suffix of the current format; returns the written path.

    A PNG written here has a fixed creation date left out of its metadata, so regenerating an unchanged
    figure gives the same bytes.
    """
    out = Path(path).with_suffix("." + current_format())
    if out.suffix == ".png":
        kwargs.setdefault("metadata", {"Software": None})
    elif out.suffix == ".pdf":
        kwargs.setdefault("metadata", {"CreationDate": None})
    elif out.suffix == ".svg":
        kwargs.setdefault("metadata", {"Date": None})
    fig.savefig(out, **kwargs)
    return out


def symbol(name: str) -> str:
    """The printed form of a factor or metric name.

    The metric's family prefix is dropped (``et.GPI`` -> ``GPI``); a Greek letter or a one-letter name with
    a subscript becomes mathtext (``sigma_s`` -> ``$\\sigma_{s}$``, ``U_c`` -> ``$U_{c}$``); other
    underscores become spaces (``act_delay`` -> ``act delay``).

    Examples
    --------
    >>> symbol("sigma_c"), symbol("et.Uc"), symbol("wc"), symbol("act_delay")
    ('$\\\\sigma_{c}$', '$U_{c}$', 'wc', 'act delay')
    """
    short = name.rsplit(".", 1)[-1] if "." in name else name
    known = {"Uc": "U_c", "Ua": "U_a"}
    short = known.get(short, short)
    m = _SYMBOL.match(short)
    if m:
        head = m.group("head")
        if head.lower() in _GREEK:
            head = "\\" + head
            return f"${head}_{{{m.group('sub')}}}$"
        if len(head) == 1:
            return f"${head}_{{{m.group('sub')}}}$"
    if short.lower() in _GREEK:
        return f"$\\{short}$"
    return short.replace("_", " ")
