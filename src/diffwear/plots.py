"""Matplotlib figures in the style of the thesis plots (Agg backend, PNG)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def stacked(
    path: Path,
    x: np.ndarray,
    panels: Sequence[tuple[str, Mapping[str, np.ndarray]]],
    *,
    xlabel: str,
    title: str,
    logy: Sequence[bool] | None = None,
) -> Path:
    """Vertically stacked panels sharing x; each panel maps a label to a curve."""
    fig, axes = plt.subplots(len(panels), 1, figsize=(7, 2.4 * len(panels)), sharex=True)
    axes = np.atleast_1d(axes)
    for k, (ax, (ylabel, curves)) in enumerate(zip(axes, panels)):
        for label, y in curves.items():
            ax.plot(x, y, label=label, lw=1.2)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        if logy is not None and logy[k]:
            ax.set_yscale("log")
        if len(curves) > 1:
            ax.legend(fontsize=8, loc="best")
    axes[-1].set_xlabel(xlabel)
    axes[0].set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
