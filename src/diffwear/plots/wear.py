"""Figures of the wear studies (cf. thesis Figs. 5-5, 6-9, 7-4, 7-5)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes

from ..wear.status import STATUS_OK
from .files import save
from .layout import depth_references, legend_outside, wrapped
from .panels import closed, closed_profile, stop_words

# Margin around the locus panel's data, as a fraction of its larger span: the
# curves stay clear of the frame (a line on the frame is half hidden by it).
LOCUS_MARGIN = 0.08


class Lines(NamedTuple):
    """What the wear figures draw beside the run: the ``clearance_mm`` circle,
    the bushing ``wall_mm``, the run's ``label`` and what its history's
    markers are (``markers``), and its wear ``status`` (`diffwear.wear.status`),
    named in the titles when it stopped short."""

    clearance_mm: float
    wall_mm: float | None = None
    label: str = "diffwear (EFM)"
    markers: str = "simulated dynamic cycles"
    status: int = STATUS_OK


def wear_figures(out, *, name, theta, depth_mm, history, crank, first, last, thesis,
                 lines: Lines) -> list[str]:
    """The wear profile, the wear against cycles and the contact (the pin's
    locus in the worn bushing, the joint force) of a wear study; ``history``:
    (cycles, max depth [mm], volume [mm^3]) at the steps; ``first``/``last``:
    the contact histories (`diffwear.contact.ContactHistory`) of the first
    and last cycle over ``crank`` [rad]; ``lines``: what is drawn beside
    (`Lines`)."""
    clearance_mm, wall_mm, label = lines.clearance_mm, lines.wall_mm, lines.label
    markers, status = lines.markers, lines.status
    cycles, dmax, vol = (np.asarray(v, dtype=float) for v in history)
    reached = float(cycles[-1]) if len(cycles) else 0.0
    after = f"after {reached:,.0f} cycles" + (
        f" (stopped: {stop_words(status)})" if status != STATUS_OK else "")
    walls = {} if wall_mm is None else {"": wall_mm}
    deepest = float(np.max(depth_mm, initial=0.0))

    # wear profile with the thesis maxima drawn in
    fig, ax = plt.subplots(figsize=(8.6, 3.6))
    ax.plot(*closed_profile(theta, depth_mm), lw=1.6, label=label)
    for (ref_label, ref), style in zip(thesis.items(), ("--", ":", "-.")):
        if "max_wear_depth_mm" in ref:
            ax.axhline(ref["max_wear_depth_mm"], ls=style, color="0.35", lw=0.9,
                       label=f"thesis {ref_label}: max {ref['max_wear_depth_mm']} mm")
            deepest = max(deepest, ref["max_wear_depth_mm"])
    depth_references(ax, deepest, walls_mm=walls)
    ax.set(xlabel="bushing angle θ [deg]", ylabel="wear depth [mm]", xlim=(0, 360),
           xticks=np.arange(0, 361, 45))
    ax.grid(alpha=0.3)
    legend_outside(ax)
    ax.set_title(wrapped(f"{name}: bushing wear profile {after} "
                         "(cf. Figs. 5-5/6-9/7-4/7-5)"), fontsize=10)
    figs = [save(fig, out.file("wear_profile.png"), dpi=120).name]

    fig, axes = plt.subplots(2, 1, figsize=(8.6, 5), sharex=True)
    axes[0].plot(np.concatenate([[0], cycles]), np.concatenate([[0], dmax]), "o-", ms=3,
                 label=label)
    axes[1].plot(np.concatenate([[0], cycles]), np.concatenate([[0], vol]), "o-", ms=3,
                 label=label)
    for (ref_label, ref), mk in zip(thesis.items(), ("s", "^", "D")):
        if "max_wear_depth_mm" in ref:
            axes[0].plot(reached, ref["max_wear_depth_mm"], mk, label=f"thesis {ref_label}")
        if "wear_volume_mm3" in ref:
            axes[1].plot(reached, ref["wear_volume_mm3"], mk, label=f"thesis {ref_label}")
    depth_references(axes[0], max(float(np.max(dmax, initial=0.0)), deepest), walls_mm=walls)
    axes[0].set_ylabel("max depth [mm]")
    axes[1].set_ylabel("volume [mm³]")
    axes[1].set_xlabel("cycles")
    for ax in axes:
        ax.grid(alpha=0.3)
        legend_outside(ax)
    axes[0].set_title(wrapped(f"{name}: wear {after} (markers: {markers})"), fontsize=10)
    figs.append(save(fig, out.file("wear_history.png"), dpi=120).name)

    # constrained layout: tight layout squeezes the square locus panel with
    # its legend beside it out of the figure's left edge
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), layout="constrained")
    locus_panel(axes[0], {"first cycle": np.asarray(first.offset) * 1e3,
                          "last cycle": np.asarray(last.offset) * 1e3},
                clearance_mm=clearance_mm, theta=theta, depth_mm=depth_mm)
    for hist, tag in ((first, "first cycle"), (last, "last cycle")):
        axes[1].plot(np.degrees(crank), np.asarray(hist.force_magnitude), lw=1,
                     label=f"|F| {tag}")
    axes[1].set(xlabel="crank angle [deg]", ylabel="joint force [N]", xlim=(0, 360),
                xticks=np.arange(0, 361, 45), title="crank-rod joint force")
    axes[1].grid(alpha=0.3)
    legend_outside(axes[1])
    figs.append(save(fig, out.file("contact_locus_and_force.png"), dpi=120).name)
    return figs


def locus_panel(ax: Axes, loci: Mapping[str, np.ndarray], *, clearance_mm: float, theta,
                depth_mm) -> None:
    """The pin centre's loci (offsets [mm], bushing frame) inside the unworn
    clearance circle and the worn bushing's outline, both as the pin centre's
    reach: radius clearance + wear depth(theta) at the bushing angle theta
    (the same frame: theta from the bushing body's x axis).  Equal aspect,
    limits on the data with `LOCUS_MARGIN`, legend beside the axes."""
    t = np.linspace(0.0, 2 * np.pi, 361)
    ax.plot(clearance_mm * np.cos(t), clearance_mm * np.sin(t), "k:", lw=0.9,
            label=f"clearance circle, c = {clearance_mm:.4g} mm")
    th, depth = closed(theta, depth_mm, 2 * np.pi)
    r = clearance_mm + depth
    ax.plot(r * np.cos(th), r * np.sin(th), "-", color="0.45", lw=1.2,
            label="worn bushing: c + wear depth")
    for tag, off in loci.items():
        # a marker where the cycle starts: a locus of a few um is a dot at this scale
        ax.plot(off[:, 0], off[:, 1], lw=1.6, marker="o", ms=4, markevery=[0],
                label=f"pin centre, {tag}")
    # a square frame around the data (equal spans, equal aspect): any shape
    # of the data stays a square panel, never a strip
    points = np.concatenate([line.get_xydata() for line in ax.get_lines()])
    lo, hi = points.min(axis=0), points.max(axis=0)
    mid, half = (lo + hi) / 2, (1 + 2 * LOCUS_MARGIN) * float(np.max(hi - lo)) / 2
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_box_aspect(1.0)  # square box: the layout engine sizes it with its labels
    ax.set_aspect("equal", adjustable="datalim")
    ax.set(xlabel="pin offset x (bushing frame) [mm]", ylabel="pin offset y [mm]",
           title="pin centre locus in the worn bushing")
    ax.grid(alpha=0.3)
    legend_outside(ax)
