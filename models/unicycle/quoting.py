"""Every number of ``reports/unicycle/README.md`` is quoted from a computed value (like the pendulum report's).

:class:`Quotes` formats a value for the README and keeps ``(key, value, text)``; the README is written from a
text in which each quoted number sits between markers, so the report also writes

* ``quoted.csv``: ``key, value, text`` of every quoted number, in README order;
* ``template.md``: the README with each quoted number replaced by ``{key}``.

``tests/models/unicycle/test_unicycle_readme.py`` checks that the template holds no digit besides the labels
of :data:`LABEL_PATTERNS` (equation and figure numbers, setting names such as ``(5Q, R)``, file names), that
the template filled with ``quoted.csv`` is the README, and quoted values against fresh computations.
"""

from __future__ import annotations

import math
import re
from typing import Any

from netsim.casestudy import Quotes as _Quotes
from netsim.casestudy import fill, fmt

__all__ = ["Quotes", "LABEL_PATTERNS", "strip_labels", "fill"]

#: Digits that are names, not quantities: equation, figure, section and sample numbers, setting names, state
#: indices, file names, the 95 % band's definition (1.96 sigma), units with exponents, the radio standard.
LABEL_PATTERNS = [
    r"`[^`]*`",  # file names, commands, YAML paths
    r"\beqs? \([^)]*\)(?:[-, ]+(?:and )?\(\d+\))*",  # eq (27), eqs (4)-(9), eqs (12)-(17)
    r"\((?:\d+)\)(?:-\(\d+\))?",  # (6), (12)-(15) in the equation table
    r"\bFigs?\. \d+(?:-\d+)?", r"\bsection \d+(?:\.\d+)?", r"^#+ \d+\.", r"\(section \d+\)",
    r"\((?:5)?Q, (?:5)?R\)", r"\b5Q\b", r"\b5R\b",
    r"\b[kKeEzxPA]_?\d+\b", r"\bk\d\d\b", r"\bsd\[\d\]", r"\[\d+, ?\d+\]", r"\bxi0(?:_hat)?\b", r"\btheta0\b",
    r"\bP0\b", r"\bCA\^2\b", r"\^2\b", r"\bm\^2\b", r"\bcm\^2\b", r"\b802\.15\.4\b", r"\b95 %", r"\b1\.96\b",
    r"\bseed 001\b", r"\bL\d\b", r"\bpi/2\b", r"\bdz\d\b",
]


def strip_labels(text: str) -> str:
    """``text`` without ``{key}`` placeholders and the label patterns (what is left must hold no digit)."""
    s = re.sub(r"\{[A-Za-z0-9_.]+\}", "", text)
    for pat in LABEL_PATTERNS:
        s = re.sub(pat, "", s, flags=re.MULTILINE)
    return s


class Quotes(_Quotes):
    """Quoted numbers of one README, marked inline (:meth:`netsim.casestudy.Quotes.mark`; module docstring).

    Each quote gets the key ``<section>.<name>`` (``name`` given, or a running number); the returned string
    holds the formatted text between markers, which :meth:`render` and :meth:`template` resolve.
    """

    render = staticmethod(_Quotes.unmark)

    def __init__(self) -> None:
        super().__init__(missing="n/a")
        self.section = "s0"
        self._n = 0

    def _add(self, value: Any, text: str, key: str | None) -> str:
        self._n += 1
        k = f"{self.section}.{key if key else f'n{self._n}'}"
        if k in self.rows:
            k = f"{k}_{self._n}"
        v = float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else value
        return self.mark(k, v, text)

    def f(self, x: Any, nd: int = 3, key: str | None = None) -> str:
        """``x`` with ``nd`` significant digits (``n/a`` for None or NaN)."""
        if x is None or (isinstance(x, float) and math.isnan(x)):
            return "n/a"
        return self._add(float(x), fmt(x, nd), key)

    def pct(self, x: float, key: str | None = None) -> str:
        """``x`` as a percentage with one decimal (``n/a`` for NaN)."""
        if x is None or math.isnan(float(x)):
            return "n/a"
        return self._add(float(x), f"{100 * float(x):.1f} %", key)

    def i(self, x: Any, key: str | None = None) -> str:
        """An integer."""
        return self._add(int(x), str(int(x)), key)

    def g(self, x: Any, key: str | None = None) -> str:
        """``x`` in its shortest form (``:g``)."""
        return self._add(float(x), f"{float(x):g}", key)
