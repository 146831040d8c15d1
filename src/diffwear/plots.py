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


def polar_loci(path: Path, loci: Mapping[str, tuple[np.ndarray, np.ndarray]], *,
               title: str) -> Path:
    """Contact loci in the bushing frame: one polar panel per case, radius = |e|."""
    n = len(loci)
    cols = min(4, n)
    rows = -(-n // cols)
    fig = plt.figure(figsize=(3.0 * cols, 3.0 * rows))
    for k, (label, (theta, radius)) in enumerate(loci.items()):
        ax = fig.add_subplot(rows, cols, k + 1, projection="polar")
        ax.scatter(theta, radius * 1e3, s=2)
        ax.set_title(label, fontsize=8)
        ax.tick_params(labelsize=6)
    fig.suptitle(title + "  (radius: |e| [mm])", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
