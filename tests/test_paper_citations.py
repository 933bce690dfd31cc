"""Every "Alg. N line k" citation in ``src/`` names what the paper's listing has on that line.

The listings are ``docs/paper/algorithms.tex``, a verbatim copy of the paper's two
``algorithm`` environments (checked against the paper itself where it is present).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from paper_citations import algorithm_lines, citations, names_match, words

ROOT = Path(__file__).resolve().parents[1]
LISTINGS = ROOT / "docs" / "paper" / "algorithms.tex"
PAPER = ROOT.parent / "shared" / "paper" / "lamp-paper.tex"
SOURCES = sorted((ROOT / "src" / "lamp").rglob("*.py"))


def _listings() -> list[dict[int, str]]:
    return algorithm_lines(LISTINGS.read_text(encoding="utf-8"))


def test_numbering_follows_algpseudocode_noend():
    tex = "\n".join([
        r"\begin{algorithmic}[1]",
        r"\Require $x$",
        r"\State $a$",
        r"\While {$b$}",
        r"\If{$c$} % a comment",
        r"\State $d$ \Comment{note}",
        r"\EndIf",
        r"\EndWhile",
        r"\Function{F}{$y$}",
        r"\Statex unnumbered",
        r"\State \Return $e$",
        r"\EndFunction",
        r"\end{algorithmic}",
        r"\begin{algorithmic}[1]",
        r"\For{$f$}",
        r"\end{algorithmic}",
    ])
    first, second = algorithm_lines(tex)
    assert [first[k].split()[0] for k in sorted(first)] == [
        r"\State", r"\While", r"\If{$c$}", r"\State", r"\Function{F}{$y$}", r"\State"]
    assert list(second) == [1]


def test_the_paper_listings_have_the_lines_the_text_refers_to():
    lamp_astar, lamp_lazy = _listings()
    # The paper's own prose names these lines by label; the labels sit on them.
    assert len(lamp_astar) == 37 and len(lamp_lazy) == 42
    assert r"\label{astar:collide}" in lamp_astar[21]
    assert r"\label{astar:Gspi}" in lamp_astar[23]
    assert r"\label{astar:readdstate}" in lamp_astar[16]
    assert r"\label{lazy:drift}" in lamp_lazy[6]
    assert r"\label{lazy:penalizeedge}" in lamp_lazy[18]
    assert r"\label{lazy:return}" in lamp_lazy[42]


@pytest.mark.skipif(not PAPER.exists(), reason="the paper is not beside this checkout")
def test_listings_copy_matches_the_paper():
    paper = algorithm_lines(PAPER.read_text(encoding="utf-8"))
    assert paper == _listings()


def test_citation_parser_binds_the_latest_algorithm(tmp_path):
    src = tmp_path / "m.py"
    src.write_text('"""Alg. 2 line 6 (Drift), lines 26-33; Alg. 1 lines 21 and 23."""\n'
                   "x = 1  # line 4: Open.pop\n")
    found = [(c.algorithm, c.lines, c.is_range) for c in citations(src)]
    assert found == [(2, (6,), False), (2, tuple(range(26, 34)), True),
                     (1, (21, 23), False), (1, (4,), False)]


def test_words_split_identifiers():
    assert {"addchild", "child"} <= words(r"\textsc{AddChild}(s_{curr}, s)")
    assert names_match(words("manipulation model"), words(r"\mathcal{T}_{manip}"))
    assert not names_match(words("budgets"), words(r"\State $\textbf{if } s_{prev}$"))


def _all_citations():
    return [c for path in SOURCES for c in citations(path)]


def test_sources_cite_the_paper():
    # The check below must have something to check: the planners cite both listings.
    cited = {c.algorithm for c in _all_citations()}
    assert cited == {1, 2}


@pytest.mark.parametrize("citation", _all_citations(),
                         ids=lambda c: f"{c.path.relative_to(ROOT)}:{c.lineno}")
def test_citation_names_the_cited_line(citation):
    listing = _listings()[citation.algorithm - 1]
    missing = [k for k in citation.lines if k not in listing]
    assert not missing, f"Alg. {citation.algorithm} has no line {missing}"
    said = words(re.sub(r"\bAlg\.\s*\d+|\b(?:[Ll]ines?|l\.)\s+\d+", " ", citation.text))
    # A line made only of generic words (``q_curr <- q_next``) is named by those words.
    named = {k: words(listing[k]) or words(listing[k], generic=True) for k in citation.lines}
    said = said | words(citation.text, generic=True) if any(
        not words(listing[k]) for k in citation.lines) else said
    hits = [k for k in citation.lines if names_match(said, named[k])]
    if citation.is_range:
        # A range is named by its first line, unless that line is a bare control line
        # (``if C_R = empty``) with no name in it: then by any line inside.
        first = citation.lines[0]
        assert (first in hits) if words(listing[first]) else hits, (f"{citation.text.strip()!r} names nothing on Alg. {citation.algorithm} "
                      f"lines {citation.lines[0]}-{citation.lines[-1]}")
    else:
        assert hits == list(citation.lines), (
            f"{citation.text.strip()!r}: Alg. {citation.algorithm} "
            + "; ".join(f"line {k} is {listing[k]!r}" for k in citation.lines))
