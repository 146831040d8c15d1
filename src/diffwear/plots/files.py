"""The one place a figure becomes a file: `save` lays the figure out, writes
the PNG and closes it; `captured` hands every figure saved inside it to the
caller, open for reading (its axes, lines, legends and limits), so that tests
check what a figure shows from its data instead of its pixels."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

_observers: list[Callable[[Path, Figure], None]] = []


def save(fig: Figure, path, *, dpi: int) -> Path:
    """Tight layout (unless the figure has its own layout engine), write
    ``path`` at ``dpi``, hand the figure to any `captured` block, close it
    (pyplot forgets it; the object stays readable)."""
    if fig.get_layout_engine() is None:
        fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    for observer in _observers:
        observer(Path(path), fig)
    plt.close(fig)
    return Path(path)


@contextmanager
def captured() -> Iterator[dict[str, Figure]]:
    """``with captured() as figures:`` every figure saved inside the block,
    by file name (the last one saved under a name wins), drawn as written."""
    figures: dict[str, Figure] = {}

    def keep(path: Path, fig: Figure) -> None:
        figures[path.name] = fig

    _observers.append(keep)
    try:
        yield figures
    finally:
        _observers.remove(keep)
