"""Figures of the ``pin-pivot`` study (cf. thesis Figs. 4-7, 4-9)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from . import references
from .files import save
from .layout import legend_outside
from .panels import closed  # profiles on -180 .. 180 deg, closed at +180


def profile_figure(path, *, angle_deg, simulated, direct, pressure, title):
    """Wear profiles of pin and pivot (each in its own frame, angle from the
    load direction at mid-stroke) after the simulated sweeps and after the
    direct run, and the contact pressure at mid-stroke at the end."""
    order = np.argsort(angle_deg)
    a = angle_deg[order]
    fig, axes = plt.subplots(2, 1, figsize=(9.5, 6), sharex=True)
    for label, prof in simulated.items():
        axes[0].plot(*closed(a, prof[order], 360.0), "-", lw=1.6, label=label)
    for label, prof in direct.items():
        axes[0].plot(*closed(a, prof[order], 360.0), "--", lw=1.2, label=label)
    axes[0].set_ylabel("wear depth [mm]")
    axes[0].grid(alpha=0.3)
    legend_outside(axes[0])
    axes[0].set_title(title, fontsize=10)
    axes[1].plot(*closed(a, pressure[order], 360.0), "k-", lw=1.4)
    axes[1].set_ylabel("pressure at φ = 0 [MPa]")
    axes[1].set_xlabel("angle from the load direction [deg] (pin: in the pin's frame)")
    axes[1].set_xlim(-180, 180)
    axes[1].set_xticks(np.arange(-180, 181, 30))
    axes[1].grid(alpha=0.3)
    return save(fig, path, dpi=120)


def history_figure(path, *, sweeps, max_pin_mm, max_pivot_mm, fit_pin, fit_pivot, target,
                   direct, thesis, title):
    """Max wear of pin and pivot against sweeps (cf. Fig. 4-9), the linear
    extrapolation to ``target`` sweeps, the direct run and the thesis values."""
    fig, ax = plt.subplots(figsize=(10, 4.2))
    s = np.concatenate([[0.0], sweeps])
    ax.plot(s / 1e3, np.concatenate([[0.0], max_pin_mm]), "-", lw=1.8, label="pin (simulated)")
    ax.plot(s / 1e3, np.concatenate([[0.0], max_pivot_mm]), "-", lw=1.8, label="pivot (simulated)")
    xs = np.array([sweeps[-1] * 0.5, target])
    for (slope, icpt), lab in ((fit_pin, "pin"), (fit_pivot, "pivot")):
        ax.plot(xs / 1e3, (icpt + slope * xs) * 1e3, ":", lw=1.2,
                label=f"{lab}: linear extrapolation")
    if direct is not None:
        ds, dpin, dpiv = direct
        ax.plot(ds / 1e3, dpin, "--", lw=1.0, label="pin (direct run)")
        ax.plot(ds / 1e3, dpiv, "--", lw=1.0, label="pivot (direct run)")
    # the thesis's values at the target, side by side (2.028 and 2.0 mm coincide)
    references.side_by_side(ax, target / 1e3, [(f"thesis {label}: {value} mm", value)
                                               for label, value in thesis.items()])
    references.room_right(ax, 0.0, target / 1e3, len(thesis))
    ax.set_xlabel("sweeps [x 1000] (one sweep = -30 -> 30 deg; a test cycle = 2 sweeps)")
    ax.set_ylabel("max wear depth [mm]")
    ax.grid(alpha=0.3)
    legend_outside(ax, fontsize=7)
    ax.set_title(title, fontsize=10)
    return save(fig, path, dpi=120)
