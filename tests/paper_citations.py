"""Numbered lines of the paper's algorithm listings and the citations of them in our sources.

The paper typesets its listings with ``algpseudocode`` in ``[noend]`` mode, numbering every
line (``\\begin{algorithmic}[1]``). A line is numbered when it starts with a statement or a
block opener (``\\State``, ``\\If``, ``\\For``, ``\\While``, ``\\Function``...); ``\\Require``,
``\\Statex`` and comments are not numbered, nor are the block ends, which ``noend`` hides
(``\\EndFunction`` is hidden by ``\\algtext*`` as well).

A citation in our sources is ``Alg. N line k``, ``Alg. N lines k-m`` or ``Alg. N lines k and m``;
a bare ``line k`` refers to the algorithm named last before it in the same file. ``Alg. N``
is reserved for the LAMP paper: another paper's algorithm is written out ("Algorithm 1 of
Okumura et al.").
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

_NUMBERED = ("\\State", "\\If", "\\ElsIf", "\\Else", "\\For", "\\ForAll", "\\While",
             "\\Repeat", "\\Until", "\\Loop", "\\Function", "\\Procedure")
_UNNUMBERED = ("\\Statex", "\\Require", "\\Ensure", "\\End", "\\Comment")


def algorithm_lines(tex: str) -> list[dict[int, str]]:
    """For each ``algorithmic`` environment in ``tex`` (in order: Alg. 1, Alg. 2, ...), its
    numbered lines as {line number: LaTeX source of that line}."""
    listings: list[dict[int, str]] = []
    current: dict[int, str] | None = None
    for raw in tex.splitlines():
        line = raw.strip()
        if line.startswith("\\begin{algorithmic}"):
            current = {}
            continue
        if line.startswith("\\end{algorithmic}"):
            listings.append(current or {})
            current = None
            continue
        if current is None or not line or line.startswith("%"):
            continue
        command = re.match(r"\\[A-Za-z]+", line)
        if command is None or command.group(0).startswith(_UNNUMBERED):
            continue
        if command.group(0) in _NUMBERED:
            current[len(current) + 1] = line
    return listings


_STOP = {"curr", "next", "prev", "then", "else", "return", "each", "state", "init", "textbf",
         "textsc", "mathcal", "leftarrow", "line", "lines", "last",
         "with", "from", "that", "this", "when", "into", "over", "text", "comment", "emptyset"}


def words(text: str, generic: bool = False) -> set[str]:
    """Lower-case words of four or more letters in ``text``, identifiers split at ``_`` and at
    camel-case humps as well as kept whole (``AddChild`` gives addchild, child); generic
    words (curr, next, then...) are left out unless ``generic``."""
    text = re.sub(r"\\label\{[^}]*\}", " ", text).replace("\\Return", " return ")
    text = re.sub(r"\\(?:textsc|textbf|mathcal|rm|text)\b", " ", text)
    text = re.sub(r"\\[A-Za-z]+", " ", text)
    found: set[str] = set()
    for token in re.findall(r"[A-Za-z]+", text):
        parts = [token, *re.findall(r"[A-Z]?[a-z]+|[A-Z]+(?![a-z])", token)]
        found.update(p.lower() for p in parts if len(p) >= 4)
    return found if generic else found - _STOP


def names_match(source: set[str], listing: set[str]) -> bool:
    """Whether a word of the citing text names a word of the cited line (either a prefix of
    the other: "manipulation" names ``T_manip``)."""
    return any(a.startswith(b) or b.startswith(a) for a in source for b in listing)


@dataclass(frozen=True)
class Citation:
    path: Path
    lineno: int
    algorithm: int
    lines: tuple[int, ...]
    #: The citing text: the comment of a code line, or the whole docstring line.
    text: str
    #: A range "lines k-m" (the name must match a line inside it) or a list "k and m"
    #: (the name must match each of them).
    is_range: bool


_ALG = re.compile(r"\bAlg\.\s*(\d+)")
_CITE = re.compile(r"(?i:(?<![A-Za-z])(?:lines?|l\.))\s+(\d+)(?:\s*(-|–|and)\s*(\d+))?")


def citations(path: Path) -> list[Citation]:
    """Every citation of the paper's numbered lines in the Python file ``path``."""
    found: list[Citation] = []
    algorithm: int | None = None
    for lineno, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        comment = line.split("#", 1)[1] if "#" in line else ""
        text = comment if _CITE.search(comment) else line
        # Walk the line left to right so that "Alg. 2 ... line 6" binds the latest algorithm.
        events = sorted([(m.start(), "alg", m) for m in _ALG.finditer(line)]
                        + [(m.start(), "cite", m) for m in _CITE.finditer(line)],
                        key=lambda e: e[0])
        for _, kind, match in events:
            if kind == "alg":
                algorithm = int(match.group(1))
                continue
            if algorithm is None:
                continue
            first = int(match.group(1))
            last = int(match.group(3)) if match.group(3) else None
            if last is None:
                cited, is_range = (first,), False
            elif match.group(2) == "and":
                cited, is_range = (first, last), False
            else:
                cited, is_range = tuple(range(first, last + 1)), True
            found.append(Citation(path, lineno, algorithm, cited, text, is_range))
    return found
