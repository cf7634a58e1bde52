"""The template filler of :mod:`netsim.casestudy` and the reports' template files (issue 28: the prose is data).

* :func:`fill` puts each quoted text in place of its ``{key}``, and nothing else: a missing quote is an error naming
  the placeholder and the template; a quote no placeholder names is harmless (one set of quotes fills several
  templates), and :func:`unused_quotes` lists it;
* :func:`load_templates` reads the ``[[name]]`` sections of a template file;
* every report's template file ships in the wheel (setup.py's package data and MANIFEST.in name ``*.md`` under
  models/), and no pickle is loaded from disk by the reports' code.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from netsim.casestudy import MissingQuote, fill, load_templates, placeholders, unused_quotes

ROOT = Path(__file__).resolve().parents[1]


def test_fill_puts_each_quoted_text_in_place_of_its_placeholder():
    assert fill("ISE {c1_ISE} vs {p1.ISE} ({c1_ISE})", {"c1_ISE": "1.23", "p1.ISE": "3.75"}) == "ISE 1.23 vs 3.75 (1.23)"


def test_fill_leaves_braces_that_are_not_placeholders_and_runs_no_code():
    text = "`friction: {model: inband}` {x.__class__} {0:>5} {{x}}"
    # only {x} of "{{x}}" is a placeholder; the others are not names, so they stay as they are
    assert fill(text, {"x": "X", "x.__class__": "C"}) == "`friction: {model: inband}` C {0:>5} {X}"


def test_a_quoted_text_is_not_filled_again():
    assert fill("{a}", {"a": "{b}", "b": "no"}) == "{b}"


def test_a_missing_quote_is_an_error_naming_the_placeholder_and_the_template():
    with pytest.raises(MissingQuote) as err:
        fill("NE {c2_NE} and {c2_Nsc}", {"c2_Nsc": "3"}, "hdd_report.md [[reason2]]")
    assert str(err.value) == "hdd_report.md [[reason2]]: no quoted value for the placeholder {c2_NE}"
    assert isinstance(err.value, KeyError)  # callers that caught the old KeyError still do


def test_an_unused_quote_is_harmless_and_listed():
    texts = {"a": "1", "b": "2", "c": "3"}
    assert fill("{a}", texts) == "1"
    assert fill("{b}", texts) == "2"
    assert unused_quotes(["{a}", "{b} {a}"], texts) == ["c"]
    assert placeholders("{b} {a} {b}") == ["b", "a"]


def test_load_templates_reads_named_sections_without_trailing_blank_lines(tmp_path):
    f = tmp_path / "t.md"
    f.write_text("a comment\n[[one]]\nline {x}\n\nsecond\n\n\n[[two]]\n\n## heading\n")
    assert load_templates(f) == {"one": "line {x}\n\nsecond", "two": "\n## heading"}


@pytest.mark.parametrize("text, message", [("[[a]]\nx\n[[a]]\ny\n", r"\[\[a\]\] is given twice"),
                                           ("no names\n", "no template")])
def test_load_templates_refuses_a_repeated_name_and_a_file_without_names(tmp_path, text, message):
    f = tmp_path / "t.md"
    f.write_text(text)
    with pytest.raises(ValueError, match=message):
        load_templates(f)


def test_every_report_template_is_package_data():
    templates = sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "models").rglob("*.md"))
    assert templates, "the reports keep their prose in models/**/*.md"
    setup = (ROOT / "setup.py").read_text()
    assert re.search(r'name\.startswith\("netsim\.models"\)', setup) and '["*.md"]' in setup
    assert re.search(r"^recursive-include models .*\*\.md", (ROOT / "MANIFEST.in").read_text(), re.MULTILINE)
    for t in templates:  # each lies in a package folder, so the per-package "*.md" pattern takes it
        assert (ROOT / t).parent.joinpath("__init__.py").is_file(), t


def test_templates_fill_by_name_and_a_missing_quote_names_the_file_and_the_template(tmp_path):
    from netsim.casestudy import Templates

    (tmp_path / "study").mkdir()
    f = tmp_path / "study" / "report.md"
    f.write_text("[[intro]]\n{name} ran {runs} runs\n")
    t = Templates(f)
    # "name" is a placeholder like any other: the template's own name is positional
    assert t.fill("intro", {"runs": "3"}, name="cart") == "cart ran 3 runs"
    with pytest.raises(MissingQuote, match=r"^study/report\.md \[\[intro\]\]: no quoted value for the placeholder \{runs\}$"):
        t.fill("intro", name="cart")
