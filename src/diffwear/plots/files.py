"""The one place a figure becomes a file: `save` lays the figure out, writes
the PNG and closes it; `captured` hands every figure saved inside it to the
caller, drawn again as written (same dpi, on its own Agg canvas) and open for
reading (its axes, lines, legends, limits and text extents), so that tests
check what a figure shows from its data instead of its pixels."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

_observers: list[Callable[[Path, Figure, int], None]] = []


def save(fig: Figure, path, *, dpi: int) -> Path:
    """Tight layout (unless the figure has its own layout engine), write
    ``path`` at ``dpi``, close the figure (pyplot forgets it) and hand it to
    any `captured` block."""
    if fig.get_layout_engine() is None:
        fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    for observer in _observers:
        observer(Path(path), fig, dpi)
    return Path(path)


@contextmanager
def captured() -> Iterator[dict[str, Figure]]:
    """``with captured() as figures:`` every figure saved inside the block,
    by file name (the last one saved under a name wins), drawn at the dpi of
    its file so that display coordinates are the file's pixels."""
    figures: dict[str, Figure] = {}

    def keep(path: Path, fig: Figure, dpi: int) -> None:
        FigureCanvasAgg(fig)  # closing left it a canvas that cannot draw
        fig.set_dpi(dpi)
        fig.canvas.draw()
        figures[path.name] = fig

    _observers.append(keep)
    try:
        yield figures
    finally:
        _observers.remove(keep)
