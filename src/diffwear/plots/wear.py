"""Figures of the wear studies (cf. thesis Figs. 5-5, 6-9, 7-4, 7-5)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes

from ..wear.status import RESULTS
from . import references
from .files import save
from .layout import depth_references, legend_outside, wrapped
from .panels import closed, closed_profile, stop_words

# Margin around the locus panel's data, as a fraction of its larger span: the
# curves stay clear of the frame (a line on the frame is half hidden by it).
LOCUS_MARGIN = 0.08


class Lines(NamedTuple):
    """What the wear figures draw beside the run: the ``clearance_mm`` circle,
    the bushing ``wall_mm``, the run's ``label`` and what its history's
    markers are (``markers``), its wear ``status`` (`diffwear.wear.RESULTS`),
    named in the titles when it stopped short, the thesis figures the
    profile compares with (``cf``, e.g. "cf. Figs. 7-4/7-5") and, where the
    run is calibrated to the thesis models' worn volume, what it is
    calibrated to (``calibrated``, words): then their volumes are not drawn
    as if they agreed (only a measured one is)."""

    clearance_mm: float
    wall_mm: float | None = None
    label: str = "diffwear (EFM)"
    markers: str = "simulated dynamic cycles"
    status: RESULTS = RESULTS.ok
    cf: str = ""
    calibrated: str = ""


def wear_figures(out, *, name, theta, depth_mm, history, crank, first, last, thesis,
                 lines: Lines) -> list[str]:
    """The wear profile, the wear against cycles and the contact (the pin's
    locus in the worn bushing, the joint force) of a wear study; ``history``:
    (cycles, max depth [mm], volume [mm^3]) at the steps; ``first``/``last``:
    the contact histories (`diffwear.contact.ContactHistory`) of the first
    and last cycle over ``crank`` [rad]; ``thesis``: the reported values by
    reference ("EFM (Table 7-4)": {"max_wear_depth_mm": ..., ...}), drawn
    with one marker per kind (`references`); ``lines``: what is drawn
    beside (`Lines`)."""
    cycles, dmax, vol = (np.asarray(v, dtype=float) for v in history)
    reached = float(cycles[-1]) if len(cycles) else 0.0
    after = f"after {reached:,.0f} cycles" + (
        f" (stopped: {stop_words(lines.status)})" if bool(lines.status != RESULTS.ok) else "")
    figs = [profile_figure(out.file("wear_profile.png"), name=name, theta=theta,
                           depth_mm=depth_mm, thesis=thesis, lines=lines, after=after).name,
            history_figure(out.file("wear_history.png"), name=name, history=(cycles, dmax, vol),
                           thesis=thesis, lines=lines, after=after).name]

    # constrained layout: tight layout squeezes the square locus panel with
    # its legend beside it out of the figure's left edge
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), layout="constrained")
    locus_panel(axes[0], {"first cycle": np.asarray(first.offset) * 1e3,
                          "last cycle": np.asarray(last.offset) * 1e3},
                clearance_mm=lines.clearance_mm, theta=theta, depth_mm=depth_mm)
    force_panel(axes[1], crank, np.asarray(first.force_magnitude),
                np.asarray(last.force_magnitude))
    figs.append(save(fig, out.file("contact_locus_and_force.png"), dpi=120).name)
    return figs


def profile_figure(path, *, name, theta, depth_mm, thesis, lines: Lines, after: str):
    """The worn profile against the bushing angle; beside it, where the
    thesis reports maxima (it gives no profile), a strip of the maxima: the
    run's and each reference's, one column each (`references.maxima_strip`),
    so that values a few um apart stay apart."""
    maxima = [(f"thesis {k}", float(v["max_wear_depth_mm"])) for k, v in thesis.items()
              if "max_wear_depth_mm" in v]
    deepest = max([float(np.max(depth_mm, initial=0.0))] + [v for _, v in maxima])
    if maxima:
        fig, (ax, strip) = plt.subplots(1, 2, figsize=(10.4, 3.8), sharey=True,
                                        gridspec_kw={"width_ratios": [4.0, 0.3 + 0.75 *
                                                                      len(maxima)]})
    else:
        fig, ax = plt.subplots(figsize=(8.6, 3.6))
    ax.plot(*closed_profile(theta, depth_mm), lw=1.6, label=lines.label)
    note = depth_references(ax, deepest, walls_mm={} if lines.wall_mm is None
                            else {"": lines.wall_mm})
    ax.set(xlabel="bushing angle θ [deg]", ylabel="wear depth [mm]", xlim=(0, 360),
           xticks=np.arange(0, 361, 45))
    ax.grid(alpha=0.3)
    if maxima:
        references.maxima_strip(strip, [(lines.label, float(np.max(depth_mm))), *maxima])
        strip.legend(*ax.get_legend_handles_labels(), fontsize=8, loc="upper left",
                     bbox_to_anchor=(1.06, 1.0), borderaxespad=0.0, title=note or None,
                     title_fontsize=8)
    else:
        legend_outside(ax, title=note or None)
    fig.suptitle(wrapped(f"{name}: bushing wear profile {after}"
                         + (f" ({lines.cf})" if lines.cf else ""), 100), fontsize=10)
    return save(fig, path, dpi=120)


def history_figure(path, *, name, history, thesis, lines: Lines, after: str):
    """Max depth and worn volume against cycles, with the thesis's values at
    the cycles they are for, side by side (`references.side_by_side`); a
    volume the run is calibrated to (``lines.calibrated``) is said in words,
    not drawn as agreement."""
    cycles, dmax, vol = history
    reached = float(cycles[-1]) if len(cycles) else 0.0
    fig, axes = plt.subplots(2, 1, figsize=(8.6, 5), sharex=True)
    axes[0].plot(np.concatenate([[0], cycles]), np.concatenate([[0], dmax]), "o-", ms=3,
                 label=lines.label)
    axes[1].plot(np.concatenate([[0], cycles]), np.concatenate([[0], vol]), "o-", ms=3,
                 label=lines.label)
    depths = [(f"thesis {k}", float(v["max_wear_depth_mm"])) for k, v in thesis.items()
              if "max_wear_depth_mm" in v]
    volumes = [(f"thesis {k}", float(v["wear_volume_mm3"])) for k, v in thesis.items()
               if "wear_volume_mm3" in v and not (lines.calibrated and "measured" not in k)]
    references.side_by_side(axes[0], reached, depths)
    references.side_by_side(axes[1], reached, volumes)
    references.room_right(axes[1], 0.0, reached, max(len(depths), len(volumes)))
    note = depth_references(axes[0], max([float(np.max(dmax, initial=0.0))]
                                         + [v for _, v in depths]),
                            walls_mm={} if lines.wall_mm is None else {"": lines.wall_mm})
    axes[0].set_ylabel("max depth [mm]")
    axes[1].set_ylabel("volume [mm³]")
    axes[1].set_xlabel("cycles")
    if lines.calibrated:
        axes[1].set_title(wrapped(lines.calibrated, 90), fontsize=8)
    for ax in axes:
        ax.grid(alpha=0.3)
    legend_outside(axes[0], title=note or None)
    legend_outside(axes[1])
    axes[0].set_title(wrapped(f"{name}: wear {after} (markers: {lines.markers})"), fontsize=10)
    return save(fig, path, dpi=120)


def force_panel(ax: Axes, crank, first, last) -> None:
    """The joint force over the first and the last cycle: the last dashed over
    the first (on a barely worn joint they coincide), their largest
    difference in the legend."""
    deg = np.degrees(np.asarray(crank))
    ax.plot(deg, first, lw=1.8, label="|F| first cycle")
    gap = float(np.max(np.abs(last - first))) if len(first) else 0.0
    ax.plot(deg, last, lw=1.2, ls="--", label=f"|F| last cycle (differs by at most {gap:.2g} N)")
    ax.set(xlabel="crank angle [deg]", ylabel="joint force [N]", xlim=(0, 360),
           xticks=np.arange(0, 361, 45), title="crank-rod joint force")
    ax.grid(alpha=0.3)
    legend_outside(ax)


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
        # a marker where the cycle starts: a locus of a few um is a dot at this
        # scale, so its span is said in the legend
        span_um = 1e3 * float(np.max(np.ptp(off, axis=0))) if len(off) else 0.0
        ax.plot(off[:, 0], off[:, 1], lw=1.6, marker="o", ms=4, markevery=[0],
                label=f"pin centre, {tag} (spans {span_um:.2g} µm)")
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
