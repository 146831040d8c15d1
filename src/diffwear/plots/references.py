"""Published values drawn beside a run: one marker per kind of reference, the
same in every figure (the thesis's EFM model a square, its FEM model a
triangle, a measurement a diamond), open so that a marker under another still
shows its outline, and set side by side (offset in points, the data kept
exact) so that none hides another where their values nearly coincide."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.transforms import offset_copy

# By the reference's label: its first word names its kind.
STYLES = {"EFM": ("s", "tab:blue"), "FEM": ("^", "tab:orange"), "measured": ("D", "k")}
# Other references (e.g. a simulation of another author) in turn.
OTHER = (("v", "tab:purple"), ("o", "tab:brown"), ("P", "tab:gray"))

# Horizontal step between markers set side by side [pt]: a marker is 6-7 pt
# wide, so 9 pt leaves each one's outline clear of its neighbour's.
STEP_PT = 9.0
# Room right of the data per marker set beside it, as a fraction of the x
# span (`room_right`).
ROOM = 0.035


def style(label: str, k: int = 0) -> tuple[str, str]:
    """(marker, colour) of the reference ``label`` ("EFM (Table 7-4)",
    "measured (Tables 7-5/7-6)", ...); the ``k``-th of the other kinds."""
    for kind, s in STYLES.items():
        if label.startswith(kind) or label.startswith(f"thesis {kind}"):
            return s
    return OTHER[k % len(OTHER)]


def side_by_side(ax: Axes, x: float, values: Sequence[tuple[str, float]], *,
                 first_pt: float = STEP_PT, ms: float = 7.0) -> None:
    """Each (label, value) of ``values`` as an open marker at (x, value), the
    k-th drawn ``first_pt + k STEP_PT`` points right of x (its data stay x:
    the offset is in the drawing only), labelled for the legend."""
    others = 0
    for k, (label, value) in enumerate(values):
        marker, color = style(label, others)
        others += marker in {m for m, _ in OTHER}
        shift = offset_copy(ax.transData, fig=ax.get_figure(root=True),
                            x=first_pt + k * STEP_PT, y=0.0, units="points")
        ax.plot([x], [value], marker, ms=ms, mfc="none", mew=1.4, color=color,
                transform=shift, label=label)
        # an offset transform keeps the point out of the data limits: put it in
        ax.update_datalim([(x, value)])
    ax.autoscale_view()


def room_right(ax: Axes, x_first: float, x_last: float, n: int) -> None:
    """An x range from ``x_first`` with room right of ``x_last`` for ``n``
    markers set there by `side_by_side`: `ROOM` of the span per marker and
    one more (the figures' axes are >= 4.5 in = 324 pt wide, so a marker's
    9 pt step is < 3 % of them)."""
    span = x_last - x_first
    ax.set_xlim(x_first - 0.03 * span, x_last + ROOM * (n + 1) * span)


def maxima_strip(ax: Axes, values: Sequence[tuple[str, float]], *, unit: str = "mm") -> None:
    """A strip of maxima beside a profile (sharing its y axis): one column
    per (label, value), the run's first, each reference's marker at its
    value, the value written beside it; the columns named on the x axis."""
    x = np.arange(len(values))
    others = 0
    for k, (label, value) in enumerate(values):
        if k == 0 or label.startswith("diffwear"):  # the runs: filled circles
            marker, color = "o", f"C{k}"
        else:
            marker, color = style(label, others)
            others += marker in {m for m, _ in OTHER}
        ax.plot([k], [value], marker, ms=7, mfc=color if marker == "o" else "none", mew=1.4,
                color=color)
        ax.annotate(f"{value:.3g}", (k, value), xytext=(0, 7), textcoords="offset points",
                    ha="center", fontsize=7)
    ax.set_xticks(x, [tick(lab) for lab, _ in values], fontsize=6.5)
    ax.set_xlim(-0.6, len(values) - 0.4)
    ax.set_title(f"max depth [{unit}]", fontsize=9)
    ax.grid(alpha=0.3, axis="y")
    ax.tick_params(axis="y", labelleft=False)


def tick(label: str) -> str:
    """A reference's label as a tick of a few short lines: "thesis EFM (Table
    7-4)" -> "EFM\nTable 7-4", "diffwear (FEM route, +-4 deg mean)" ->
    "diffwear\nFEM route\n+-4 deg mean"."""
    label = label.removeprefix("thesis ")
    head, _, source = label.partition(" (")
    return "\n".join([head, *source.rstrip(")").split(", ")] if source else [head])
