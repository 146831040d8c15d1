"""Figures shared by the studies and `diffwear run`: stacked panels, contact
loci, wear profiles (PNG)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import cast

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.projections.polar import PolarAxes
from numpy.typing import ArrayLike

from ..wear.status import RESULTS, words
from .files import save
from .layout import depth_references, legend_outside, nonzero, wrapped


def stacked(
    path: Path,
    x: np.ndarray,
    panels: Sequence[tuple[str, Mapping[str, ArrayLike]]],
    *,
    xlabel: str,
    title: str,
    logy: Sequence[bool] | None = None,
) -> Path:
    """Vertically stacked panels sharing x; each panel maps a label to a curve.

    A curve that is zero to round-off (`layout.nonzero`, e.g. a ground-fixed
    driver's force) is not drawn, a panel left empty is dropped, and the
    title names what was left out.  On a log panel, values below 1e-15 of
    the panel's largest are not drawn (an exactly assembled start, e.g. a
    constraint residual of 1e-312 at t = 0, would otherwise stretch the axis
    over 300 decades).  Legends right of the panels, off the data; long
    titles wrap."""
    kept, omitted = [], []
    for k, (ylabel, curves) in enumerate(panels):
        log = logy is not None and logy[k]
        drawn, zero = nonzero(curves, log=log)
        omitted += [f"{label} ({ylabel})" for label in zero]
        if drawn:
            kept.append((ylabel, drawn, log))
    if omitted:
        title += "; zero to round-off, not drawn: " + ", ".join(omitted)
    if not kept:  # a figure that says so, rather than none
        fig, ax = plt.subplots(figsize=(8.6, 2.4))
        ax.set_axis_off()
        ax.set_title(wrapped(title), fontsize=10)
        return save(fig, path, dpi=120)
    fig, axes = plt.subplots(len(kept), 1, figsize=(8.6, 0.6 + 2.4 * len(kept)), sharex=True)
    axes = np.atleast_1d(axes)
    for ax, (ylabel, curves, log) in zip(axes, kept):
        for label, y in curves.items():
            if log:
                top = np.nanmax(np.abs(y)) if np.any(np.isfinite(y)) else 0.0
                y = np.where(np.abs(y) > 1e-15 * top, y, np.nan)
            ax.plot(x, y, label=label, lw=1.2)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        if log:
            ax.set_yscale("log")
        legend_outside(ax)
    axes[-1].set_xlabel(xlabel)
    axes[0].set_title(wrapped(title), fontsize=10)
    return save(fig, path, dpi=120)


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
    fig.suptitle(wrapped(title + f"  (radius: {radius_label})", 90), fontsize=9)
    return save(fig, path, dpi=110)


def wear_panels(path: Path, profiles: Mapping[str, tuple[np.ndarray, np.ndarray]],
                histories: Mapping[str, tuple[np.ndarray, np.ndarray]], *, title: str,
                walls: Mapping[str, float] | None = None, limit: float | None = None,
                lives: Mapping[str, float | None] | None = None) -> Path:
    """Per joint: the worn profile against the bushing angle [deg] and the peak
    depth against cycles, both in mm (inputs in m); on both, each joint's
    bushing wall (``walls`` [m]; one far above the wear named in the
    legend's title instead) and the depth ``limit`` [m] as labelled lines,
    and on the history the cycles at which each joint reaches the limit
    (``lives``, where within the run).  Legend off the data."""
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 3.8))
    for name, (theta, depth) in profiles.items():
        a.plot(*closed_profile(theta, np.asarray(depth) * 1e3), label=name)
    for name, (cycles, peak) in histories.items():
        b.plot(cycles, np.asarray(peak) * 1e3, ".-", ms=3, label=name)
    deepest = 1e3 * max([float(np.max(d, initial=0.0)) for _, d in profiles.values()]
                        + [float(np.max(p, initial=0.0)) for _, p in histories.values()])
    walls_mm = {k: w * 1e3 for k, w in (walls or {}).items()}
    limit_mm = None if limit is None else limit * 1e3
    notes = [depth_references(ax, deepest, walls_mm=walls_mm, limit_mm=limit_mm)
             for ax in (a, b)]
    for name, life in (lives or {}).items():
        if (limit_mm is not None and life is not None and np.isfinite(life) and histories
                and life <= max(float(np.max(c, initial=0.0)) for c, _ in histories.values())):
            b.plot([life], [limit_mm], "v", color="tab:red", ms=7,
                   label=f"{name} at the limit: {life:,.0f} cycles")
    a.set(xlabel="bushing angle [deg]", ylabel="wear depth [mm]", xlim=(0, 360),
          xticks=np.arange(0, 361, 45))
    b.set(xlabel="cycles", ylabel="max wear depth [mm]")
    for ax in (a, b):
        ax.grid(alpha=0.3)
    legend_outside(b, title=notes[-1] or None)  # a wall off the scale: named, not drawn
    fig.suptitle(wrapped(title, 100), fontsize=10)
    return save(fig, path, dpi=110)


def film_panels(path: Path, crank_deg: np.ndarray,
                cases: Mapping[str, tuple[np.ndarray, ...]], *, onset: float,
                onset_ratio: float, roughness: float, title: str) -> Path:
    """A lubricated joint over the crank angle [deg]: the minimum film
    thickness (inputs in m, drawn in um) with the onset of mixed lubrication
    lambda_c sigma (``onset`` [m]) as a labelled line, and the asperities' share of
    the load (drawn in percent); one curve per case of ``cases`` ({label:
    (h_min, share)} or {label: (h_min, share, interference)}, e.g. the unworn
    and the worn bushing).  Where a case's pin presses the asperities past the
    mean surfaces (an ``interference`` [m] > 0, no film left there), a middle
    panel draws how far: the film thickness is never drawn negative.  Legends
    off the data."""
    pressed = [(label, c[2]) for label, c in cases.items()
               if len(c) > 2 and float(np.max(c[2])) > 0.0]
    rows = 3 if pressed else 2
    fig, axes = plt.subplots(rows, 1, figsize=(8.6, 5.4 if rows == 2 else 7.4), sharex=True)
    a, b = axes[0], axes[-1]
    colors = {}
    for label, (h_min, share, *_) in cases.items():
        (line,) = a.plot(crank_deg, np.asarray(h_min) * 1e6, lw=1.2, label=label)
        colors[label] = line.get_color()
        b.plot(crank_deg, 100.0 * np.asarray(share), lw=1.2, color=colors[label], label=label)
    a.axhline(onset * 1e6, color="tab:red", ls="--", lw=1.0,
              label=f"mixed-lubrication onset λ σ = {onset_ratio:g} × {roughness * 1e6:.3g} µm")
    a.set_ylabel("min film thickness [µm]")
    if all(float(np.max(c[0])) <= 0.0 for c in cases.values()):
        a.text(0.5, 0.5, "no film left anywhere over the cycle"
               + (" (the interference below)" if pressed else ""),
               transform=a.transAxes, ha="center", va="center", fontsize=9, color="0.3")
    if pressed:
        for label, interference in pressed:
            axes[1].plot(crank_deg, np.asarray(interference) * 1e6, lw=1.2,
                         color=colors[label], label=label)
        axes[1].set_ylabel("asperity interference [µm]\n(no film left: the pin past\n"
                           "the mean surfaces)", fontsize=8)
        axes[1].set_ylim(bottom=0.0)
    # in percent, scaled to the largest share (a mixed film's few percent are
    # invisible on a 0..100 % axis)
    top = max(float(np.max(100.0 * np.asarray(c[1]))) for c in cases.values())
    b.set(xlabel="crank angle [deg]", ylabel="asperity share of load [%]",
          ylim=(0.0, 1.08 * top if top > 0.0 else 1.0))
    first, last = float(np.min(crank_deg)), float(np.max(crank_deg))
    b.set_xlim(first, last + (last - first) / max(len(crank_deg) - 1, 1))
    for ax in axes:
        ax.grid(alpha=0.3)
        legend_outside(ax)
    a.set_title(wrapped(title), fontsize=10)
    return save(fig, path, dpi=120)


def wear_title(subject: str, reached: Mapping[str, float], status: Mapping[str, RESULTS], *,
               model: str) -> str:
    """"<subject>: wear after N cycles (<model> model)", the cycles those
    actually reached, and for a joint whose run stopped short, why (its
    wear ``status``, `diffwear.wear.RESULTS`): "(stopped: wall reached)"."""
    counts = sorted(set(reached.values()))
    if len(counts) == 1:
        text = f"{subject}: wear after {counts[0]:,.0f} cycles"
    else:
        text = f"{subject}: wear after " + ", ".join(f"{c:,.0f} cycles ({n})"
                                                    for n, c in reached.items())
    why = {n: stop_words(s) for n, s in status.items() if s != RESULTS.ok}
    if why:
        single = len(set(why.values())) == 1 and len(why) == len(reached)
        text += " (stopped: " + (next(iter(why.values())) if single else "; ".join(
            f"{n}: {w}" for n, w in why.items())) + ")"
    return f"{text} ({model} model)"


def stop_words(status: RESULTS) -> str:
    """Why a wear run stopped short, in a few words (a title's): the
    `RESULTS` member's name ("wall reached", "cycle model failed")."""
    return words(status)


def closed(x, y, period: float) -> tuple[np.ndarray, np.ndarray]:
    """A periodic curve sampled once over its period (``x`` from its first
    sample, not repeating it a period on) with the first point repeated one
    ``period`` on, so that a line drawn through it closes."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    return np.append(x, x[0] + period), np.append(y, y[0])


def closed_profile(theta, depth) -> tuple[np.ndarray, np.ndarray]:
    """A profile on the bushing grid (theta [rad] from 0, not repeating 2 pi)
    as angle [deg] and value, closed at 360 deg."""
    return closed(np.degrees(np.asarray(theta, dtype=float)), depth, 360.0)
