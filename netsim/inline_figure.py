"""The figure class netsim's figures are made of: a matplotlib ``Figure`` that a fresh Jupyter kernel shows inline.

:class:`InlineFigure` has a ``_repr_png_``, so IPython shows it without pyplot or ``%matplotlib inline`` (a bare
``Figure`` shows there as its text repr unless the inline backend is active). :func:`new_figure` and
:func:`figure_and_axes` are the two ways the run figures (:mod:`netsim.plotting`, :mod:`netsim.timeline_figures`)
start: a new figure, or the axes a caller passed in.
"""

from __future__ import annotations

from typing import Any

from matplotlib.figure import Figure  # not pyplot: no backend, no global figure list

__all__ = ["InlineFigure", "new_figure", "figure_and_axes"]


class InlineFigure(Figure):
    """A matplotlib ``Figure`` that IPython and Jupyter show as a PNG, without pyplot or the inline backend.

    Examples
    --------
    >>> fig = InlineFigure(figsize=(2, 1))
    >>> fig._repr_png_()[:4] == bytes([0x89]) + b"PNG"
    True
    """

    def _repr_png_(self) -> bytes:
        import io

        buf = io.BytesIO()
        self.savefig(buf, format="png", bbox_inches="tight")
        return buf.getvalue()


def new_figure(width: float, height: float) -> Any:
    """A new :class:`InlineFigure` of this size (inches), 100 dpi, constrained layout."""
    return InlineFigure(figsize=(width, height), dpi=100, layout="constrained")


def figure_and_axes(ax: Any, width: float, height: float) -> tuple[Any, Any]:
    """``(figure, axes)``: the given axes and their figure, else one new axes on a new figure of this size."""
    if ax is not None:
        try:
            return ax.get_figure(root=True), ax  # the figure itself, also for axes in a subfigure
        except TypeError:  # matplotlib < 3.10: no root argument
            return ax.figure, ax
    fig = new_figure(width, height)
    return fig, fig.subplots()
