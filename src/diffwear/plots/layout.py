"""Layout rules every figure follows: legends beside the axes (never over the
data), series that are zero to round-off left out (and named), the bushing
wall and the depth limit drawn as labelled lines on a wear-depth axis (a wall
far above the wear named in words, never a legend entry for a line not
drawn)."""

from __future__ import annotations

import math
import textwrap
from collections.abc import Mapping

import numpy as np
from matplotlib.axes import Axes
from matplotlib.legend import Legend
from numpy.typing import ArrayLike

# A series whose largest |value| is below this fraction of its panel's largest
# is zero to round-off: float64 carries 16 digits and the solvers' tolerances
# (rtol >= 1e-12) leave a constrained-zero quantity (a ground-fixed driver's
# force, a slider's y) at 1e-16 .. 1e-12 of the panel's scale; a real signal
# this small could not be seen on the panel either (a pixel is ~3e-3 of it).
ROUND_OFF = 1e-9

# Characters of a title line at 9-10 pt over the axes of the 6-8.6 in figures
# (~5 in beside a legend or colour bar: 360 pt at ~4.7-5 pt a character).
TITLE_WIDTH = 70

# A bushing wall more than this many times the deepest wear (or the limit)
# is not drawn (on the same axis the wear would be squeezed into the bottom
# third of the panel) and so not in the legend: `depth_references` names it
# in words.
WALL_IN_VIEW = 3.0


def wrapped(title: str, width: int = TITLE_WIDTH) -> str:
    """A title broken into lines that fit its axes (`TITLE_WIDTH`; a figure's
    suptitle over several axes passes its own width)."""
    return textwrap.fill(title, width)


def legend_outside(ax: Axes, *, fontsize: float = 8, below: bool = False,
                   **kwargs) -> Legend | None:
    """The axes' legend right of its frame, top-aligned (``below``: under the
    axis label, for axes with a colour bar on the right), off the data (none
    when nothing is labelled and no ``title`` is given: a legend may hold only
    its title, a note such as a wall off the scale)."""
    if not ax.get_legend_handles_labels()[0] and not kwargs.get("title"):
        return None
    if kwargs.get("title"):
        kwargs.setdefault("title_fontsize", fontsize)
    if below:
        return ax.legend(fontsize=fontsize, loc="upper center", bbox_to_anchor=(0.5, -0.16),
                         borderaxespad=0.0, **kwargs)
    return ax.legend(fontsize=fontsize, loc="upper left", bbox_to_anchor=(1.02, 1.0),
                     borderaxespad=0.0, **kwargs)


def nonzero(curves: Mapping[str, ArrayLike], *, log: bool = False
            ) -> tuple[dict[str, np.ndarray], list[str]]:
    """The ``curves`` that are not zero to round-off (`ROUND_OFF` of the
    largest in the mapping; on a ``log`` axis only exact zeros, as there a
    small value is still drawn), and the labels of those left out."""
    arrays = {k: np.asarray(v, dtype=float) for k, v in curves.items()}
    size = {k: float(np.nanmax(np.abs(y), initial=0.0)) for k, y in arrays.items()}
    top = max(size.values(), default=0.0)
    floor = 0.0 if log else ROUND_OFF * top
    kept = {k: y for k, y in arrays.items() if size[k] > floor}
    return kept, [k for k in arrays if k not in kept]


def depth_references(ax: Axes, deepest_mm: float, *, walls_mm: Mapping[str, float] | None = None,
                     limit_mm: float | None = None) -> str:
    """On a wear-depth axis [mm]: the depth ``limit_mm`` and each joint's
    bushing wall (``walls_mm`` by joint name; "" for a single joint) as
    labelled horizontal lines, and the y range from 0 to the deepest of the
    wear, the limit and every wall within `WALL_IN_VIEW` of them.  A wall
    further up is not drawn (so not in the legend): the returned note names
    it ("bushing wall 6.342 mm: off this scale"; "" when every wall is drawn),
    for the caller's legend title or caption."""
    top = max(deepest_mm, limit_mm or 0.0)
    if limit_mm is not None:
        ax.axhline(limit_mm, color="tab:red", ls="--", lw=1.0,
                   label=f"depth limit {limit_mm:g} mm")
    scale = top
    finite = {k: w for k, w in (walls_mm or {}).items() if math.isfinite(w)}
    if len(set(finite.values())) == 1:  # one wall for all: one line
        finite = {"": next(iter(finite.values()))}
    off_scale = []
    for joint, wall in finite.items():
        name = f"bushing wall{' ' + joint if joint else ''}"
        if scale > 0 and wall > WALL_IN_VIEW * scale:
            off_scale.append(f"{name} {wall:.4g} mm")
            continue
        top = max(top, wall)
        ax.axhline(wall, color="k", ls="-.", lw=1.0, label=f"{name}: {wall:.4g} mm")
    if top > 0:
        ax.set_ylim(-0.04 * top, 1.08 * top)
    return (", ".join(off_scale) + ": off this scale") if off_scale else ""
