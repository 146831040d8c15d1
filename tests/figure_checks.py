"""What a figure's legend promises, checked from the figure's data: every
entry names an artist that is drawn, visible, with data inside its axes'
frame (a legend entry for a line off the scale, or never drawn, fails)."""

from __future__ import annotations

import numpy as np
from matplotlib.container import Container
from matplotlib.figure import Figure


def _inside(ax, xy: np.ndarray) -> bool:
    """Any of the display points ``xy`` inside ``ax``'s frame (a pixel of slack)."""
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    box = ax.get_window_extent()
    return bool(np.any((xy[:, 0] >= box.x0 - 1) & (xy[:, 0] <= box.x1 + 1)
                       & (xy[:, 1] >= box.y0 - 1) & (xy[:, 1] <= box.y1 + 1)))


def _shows_data(ax, artist) -> bool:
    """The artist is visible and draws something inside its axes."""
    if isinstance(artist, Container):
        return any(_shows_data(ax, a) for a in artist.get_children())
    if not artist.get_visible():
        return False
    if hasattr(artist, "get_xydata"):  # a line: its points, where line or marker shows
        drawn = (artist.get_linestyle() not in ("None", "", " ")
                 or artist.get_marker() not in ("None", "", " ", None))
        xy = np.asarray(artist.get_xydata(), dtype=float).reshape(-1, 2)
        return drawn and len(xy) > 0 and _inside(ax, artist.get_transform().transform(xy))
    if hasattr(artist, "get_offsets") and len(artist.get_offsets()):  # scatter
        off = np.asarray(artist.get_offsets(), dtype=float)
        if _inside(ax, artist.get_offset_transform().transform(off)):
            return True
    extent = artist.get_window_extent()  # patches, filled areas, images
    box = ax.get_window_extent()
    return bool(extent.width > 0 and extent.height > 0 and extent.x1 > box.x0
                and extent.x0 < box.x1 and extent.y1 > box.y0 and extent.y0 < box.y1)


def _artists(fig: Figure) -> list:
    """(axes, artist) of every labelled thing drawn in the figure."""
    out = []
    for ax in fig.axes:
        for artist in (*ax.lines, *ax.collections, *ax.patches, *ax.images, *ax.containers):
            label = artist.get_label()
            if label and not label.startswith("_"):
                out.append((ax, artist))
    return out


def legend_entries(fig: Figure) -> list[str]:
    """Every legend entry's text, of the axes' legends and the figure's."""
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    legends += list(fig.legends)
    return [t.get_text() for leg in legends for t in leg.get_texts()]


def assert_legend_names_drawn(fig: Figure, name: str = "") -> int:
    """Every legend entry of ``fig`` is the label of an artist drawn inside
    its axes; returns the number of entries checked."""
    fig.canvas.draw()
    artists = _artists(fig)
    entries = legend_entries(fig)
    for entry in entries:
        mine = [(ax, a) for ax, a in artists if a.get_label() == entry]
        assert mine, f"{name}: legend entry {entry!r} names no artist of the figure"
        assert any(_shows_data(ax, a) for ax, a in mine), \
            f"{name}: legend entry {entry!r} names an artist with nothing drawn in its axes"
    return len(entries)
