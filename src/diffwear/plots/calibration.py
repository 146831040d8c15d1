"""Figures of the calibration against measured wear data (``diffwear calibrate``)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .files import save
from .layout import legend_outside


@dataclass(frozen=True)
class SeriesFit:
    """One measured series and the models' predictions at its points (SI;
    ``scale`` converts to the plotted ``unit``; ``x`` as plotted, an angle in
    degrees)."""

    name: str
    kind: str
    unit: str
    xlabel: str
    scale: float
    x: np.ndarray
    y: np.ndarray
    sigma: float
    holdout: np.ndarray
    base: np.ndarray
    chosen: np.ndarray | None  # the final model, when it is not the base fit
    chosen_label: str
    cycles: float | None


def series_fit(path: Path, f: SeriesFit) -> Path:
    """The data with error bars against the base fit and the final model."""
    fig, ax = plt.subplots(figsize=(8.4, 3.6))
    ax.errorbar(f.x, f.y * f.scale, yerr=f.sigma * f.scale, fmt=".", ms=3, color="k",
                label="data", alpha=0.7)
    order = np.argsort(f.x)
    few = f.x.size < 3  # a line through one or two points shows nothing: markers
    ax.plot(f.x[order], f.base[order] * f.scale, "s" if few else "-", mfc="none",
            label="base fit")
    if f.chosen is not None:
        ax.plot(f.x[order], f.chosen[order] * f.scale, "D" if few else "--", mfc="none",
                label=f.chosen_label)
    if f.holdout.any():
        ax.plot(f.x[f.holdout], f.y[f.holdout] * f.scale, "o", mfc="none", color="r", ms=6,
                label="held out")
    title = f.name + (f" (N = {f.cycles:g})" if f.cycles is not None else "")
    ax.set(xlabel=f.xlabel, ylabel=f"{f.kind} [{f.unit}]", title=title)
    if "[deg]" in f.xlabel:
        ax.set_xticks(np.arange(0, 361, 45))
    legend_outside(ax)
    return _save(fig, path)


def residual_structure(path: Path, fits: Sequence[SeriesFit], residuals: Sequence[np.ndarray],
                       cycles: Sequence[np.ndarray], harmonics: dict | None) -> Path:
    """The base fit's normalised residual against bushing angle (profiles) and
    against cycle count (every series), and the force residual's crank
    orders."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 3.6))
    for f, r, n in zip(fits, residuals, cycles):
        if f.kind == "profile":
            axes[0].plot(f.x, r, ".", ms=3, label=f"N = {f.cycles:g}")
        axes[1].plot(n, r, ".", ms=3, label=f.name)
    axes[0].set(xlabel="bushing angle [deg]", ylabel="base residual [sigma]",
                title="profile residual vs angle", xticks=np.arange(0, 361, 90))
    axes[1].set(xlabel="cycles", ylabel="base residual [sigma]", title="residual vs cycles")
    for ax in axes[:2]:
        ax.axhline(0, color="0.5", lw=0.8)
        legend_outside(ax, fontsize=6)
    if not any(f.kind == "profile" for f in fits):
        axes[0].text(0.5, 0.5, "no profile measured", ha="center", va="center",
                     transform=axes[0].transAxes, color="0.4")
    if harmonics:
        axes[2].bar(list(harmonics), list(harmonics.values()))
        axes[2].set(xlabel="crank order", ylabel="amplitude [sigma]",
                    title="force residual harmonics")
    else:
        axes[2].set_axis_off()
    return _save(fig, path)


def candidates(path: Path, effects: Sequence[str], statistics: Sequence[float],
               critical: float) -> Path:
    """The score statistic of each candidate effect against its critical value."""
    fig, ax = plt.subplots(figsize=(8.4, 3.2))
    ax.barh(list(effects)[::-1], list(statistics)[::-1])
    ax.axvline(critical, color="r", ls="--", lw=1, label="p = 0.001 (a strength)")
    ax.set(xscale="symlog", xlabel="score statistic (chi-square(1) under 'no effect')")
    legend_outside(ax)
    return _save(fig, path)


def discrepancy(path: Path, x, delta, band, xlabel: str, title: str) -> Path:
    """The learned discrepancy delta(x) of the wear coefficient, in per cent,
    with its 1-sigma band."""
    fig, ax = plt.subplots(figsize=(6.4, 3.4))
    x, d, b = np.asarray(x), 100 * np.asarray(delta), 100 * np.asarray(band)
    ax.fill_between(x, d - b, d + b, alpha=0.3, label="1 sigma")
    ax.plot(x, d, label="delta")
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set(xlabel=xlabel, ylabel="k (1 + delta): delta [%]", title=title)
    if xlabel.endswith("[MPa]") or xlabel.endswith("[mm/s]"):
        ax.set_xscale("log")
    if xlabel.startswith("bushing angle"):
        ax.set_xticks(np.arange(0, 361, 45))
        ax.set_xlim(0, 360)
    legend_outside(ax)
    return _save(fig, path)


def _save(fig, path: Path) -> Path:
    return save(fig, path, dpi=110)
