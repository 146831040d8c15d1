"""Figures shared by the studies and `diffwear run`: stacked panels, contact
loci, wear profiles (PNG)."""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import cast

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.projections.polar import PolarAxes
from numpy.typing import ArrayLike


def stacked(
    path: Path,
    x: np.ndarray,
    panels: Sequence[tuple[str, Mapping[str, ArrayLike]]],
    *,
    xlabel: str,
    title: str,
    logy: Sequence[bool] | None = None,
    legend_outside: bool = False,
) -> Path:
    """Vertically stacked panels sharing x; each panel maps a label to a curve.

    On a log panel, values below 1e-15 of the panel's largest are not drawn
    (an exactly assembled start, e.g. a constraint residual of 1e-312 at t = 0,
    would otherwise stretch the axis over 300 decades).  ``legend_outside``:
    legends right of the panels, off the data.  Long titles wrap."""
    width = 8.6 if legend_outside else 7.0
    fig, axes = plt.subplots(len(panels), 1, figsize=(width, 2.4 * len(panels)), sharex=True)
    axes = np.atleast_1d(axes)
    for k, (ax, (ylabel, curves)) in enumerate(zip(axes, panels)):
        log = logy is not None and logy[k]
        for label, y in curves.items():
            y = np.asarray(y, dtype=float)
            if log:
                top = np.nanmax(np.abs(y)) if np.any(np.isfinite(y)) else 0.0
                y = np.where(np.abs(y) > 1e-15 * top, y, np.nan)
            ax.plot(x, y, label=label, lw=1.2)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        if log:
            ax.set_yscale("log")
        if len(curves) > 1:
            if legend_outside:
                ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
            else:
                ax.legend(fontsize=8, loc="best")
    axes[-1].set_xlabel(xlabel)
    axes[0].set_title(textwrap.fill(title, 70), fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def polar_loci(path: Path, loci: Mapping[str, tuple[np.ndarray, np.ndarray]], *,
               title: str, radius_label: str = "|e| [mm]", radius_scale: float = 1e3,
               rmax: float | None = None) -> Path:
    """Contact loci in the bushing frame: one polar panel per case (titled by
    its key), radius x ``radius_scale``; ``rmax``: one radial scale for all."""
    n = len(loci)
    cols = min(4, n)
    rows = -(-n // cols)
    fig = plt.figure(figsize=(3.0 * cols, 3.0 * rows))
    for k, (label, (theta, radius)) in enumerate(loci.items()):
        ax = fig.add_subplot(rows, cols, k + 1, projection="polar")
        ax.scatter(theta, radius * radius_scale, s=2)
        if rmax is not None:
            cast(PolarAxes, ax).set_rmax(rmax)
        ax.set_title(label, fontsize=8)
        ax.tick_params(labelsize=6)
    fig.suptitle(textwrap.fill(title + f"  (radius: {radius_label})", 90), fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def wear_panels(path: Path, profiles: Mapping[str, tuple[np.ndarray, np.ndarray]],
                histories: Mapping[str, tuple[np.ndarray, np.ndarray]], *, title: str) -> Path:
    """Per joint: the worn profile against the bushing angle [deg] and the peak
    depth against cycles, both in mm, legends off the data."""
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 3.6))
    for name, (theta, depth) in profiles.items():
        a.plot(np.degrees(theta), depth * 1e3, label=name)
    for name, (cycles, peak) in histories.items():
        b.plot(cycles, peak * 1e3, ".-", ms=3, label=name)
    a.set(xlabel="bushing angle [deg]", ylabel="wear depth [mm]", xlim=(0, 360))
    b.set(xlabel="cycles", ylabel="max wear depth [mm]")
    for ax in (a, b):
        ax.grid(alpha=0.3)
    b.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.suptitle(textwrap.fill(title, 100), fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
