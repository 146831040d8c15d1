"""Reports as data: a `Report` is a title and a list of blocks (paragraphs,
`Table`, `Bullets`, `Figure`, nested `Section`); `render` writes the markdown
of every ``report.md``.  A driver states what to report; how it looks is
decided here, once.  A number may stay a number until then: `Significant`
and `PlusMinus` in a `Text` (a paragraph, a bullet or a cell made of parts)
or in a table's cell are written when the report is rendered.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Union


@dataclass(frozen=True)
class Significant:
    """A number to ``digits`` significant digits (`significant`)."""

    value: float | None
    digits: int = 4


@dataclass(frozen=True)
class PlusMinus:
    """A number with its uncertainty, ``value +- std`` (`plus_minus`)."""

    value: float
    std: float | None


@dataclass(frozen=True)
class Text:
    """A paragraph, a bullet or a cell made of strings, numbers
    (`Significant`, `PlusMinus`) and other `Text`, joined when rendered."""

    parts: Sequence[Any]


@dataclass(frozen=True)
class Table:
    """A markdown table; ``align`` one letter per column, "l" or "r"
    (default: the renderer's left alignment)."""

    header: Sequence[str]
    rows: Sequence[Sequence[Any]]
    align: str = ""

    def __post_init__(self):
        width = len(self.header)
        bad = [i for i, r in enumerate(self.rows) if len(r) != width]
        if bad:
            raise ValueError(f"table {list(self.header)}: rows {bad} do not have {width} cells")
        if self.align and (len(self.align) != width or set(self.align) - {"l", "r"}):
            raise ValueError(f"table align {self.align!r}: one of 'l', 'r' per column")


@dataclass(frozen=True)
class Bullets:
    """A bullet list; ``strong``: each item in bold (warnings, failures)."""

    items: Sequence[str | Text]
    strong: bool = False


@dataclass(frozen=True)
class Figure:
    """An image in the output folder, by file name."""

    file: str


@dataclass(frozen=True)
class Section:
    title: str
    blocks: Sequence[Block] = field(default_factory=tuple)


Block = Union[str, Text, Table, Bullets, Figure, Section]


@dataclass(frozen=True)
class Report:
    title: str
    blocks: Sequence[Block] = field(default_factory=tuple)


def _text(part: Any) -> str:
    """A part of a report as it reads: numbers written, `Text` joined."""
    if isinstance(part, Significant):
        return significant(part.value, part.digits)
    if isinstance(part, PlusMinus):
        return plus_minus(part.value, part.std)
    if isinstance(part, Text):
        return "".join(_text(p) for p in part.parts)
    return str(part)


def _cell(value: Any) -> str:
    return _text(value).replace("|", "\\|").replace("\n", " ")


def _block(block: Block, level: int) -> list[str]:
    if isinstance(block, (str, Text)):
        return [_text(block)]
    if isinstance(block, Table):
        rule = ([":---" if a == "l" else "---:" for a in block.align] if block.align
                else ["---"] * len(block.header))
        return ["| " + " | ".join(_cell(h) for h in block.header) + " |",
                "|" + "|".join(rule) + "|",
                *("| " + " | ".join(_cell(c) for c in row) + " |" for row in block.rows)]
    if isinstance(block, Bullets):
        return [f"- **{_text(item)}**" if block.strong else f"- {_text(item)}"
                for item in block.items]
    if isinstance(block, Figure):
        return [f"![{block.file}]({block.file})"]
    if isinstance(block, Section):
        return _blocks(block.blocks, level + 1, heading=f"{'#' * (level + 1)} {block.title}")
    raise TypeError(f"not a report block: {type(block).__name__}")


def _blocks(blocks: Sequence[Block], level: int, heading: str) -> list[str]:
    lines = [heading]
    for b in blocks:
        if (isinstance(b, (str, Text)) and not _text(b)) or (isinstance(b, Bullets)
                                                              and not b.items):
            continue
        lines += ["", *_block(b, level)]
    return lines


def markdown(block: Block) -> str:
    """One block as markdown (e.g. a table for a notebook or a docstring)."""
    return "\n".join(_block(block, 1))


def render(report: Report) -> str:
    """The report as markdown: ``# title``, then each block, blank-line separated."""
    return "\n".join(_blocks(report.blocks, 1, heading=f"# {report.title}")) + "\n"


__all__ = ["Block", "Bullets", "Figure", "PlusMinus", "Report", "Section", "Significant",
           "Table", "Text", "markdown", "render"]


def significant(value: float | None, digits: int = 4) -> str:
    """``value`` to ``digits`` significant digits, in plain notation between
    1e-3 and 1e5 and scientific outside ("0.8647", "6.074e-04", "n/a")."""
    if value is None or not isinstance(value, (int, float)) or value != value:
        return "n/a"
    if value == 0 or not abs(value) < float("inf"):
        return f"{value:g}"
    if 1e-3 <= abs(value) < 1e5:
        return f"{value:.{digits}g}"
    return f"{value:.{digits - 1}e}"


def plus_minus(value: float, std: float | None) -> str:
    """``value +- std`` with the uncertainty to two significant digits and the
    value to the same decimal place ("6.074e-04 +- 1.4e-06", "0.55 +- 0.12")."""
    if std is None or not std > 0 or std != std or value != value:
        return f"{significant(value)} +- {significant(std, 2)}"
    if value == 0:
        return f"0 +- {significant(std, 2)}"
    from math import floor, log10

    digits = max(2, min(10, floor(log10(abs(value))) - floor(log10(std)) + 2))
    return f"{significant(value, digits)} +- {significant(std, 2)}"
