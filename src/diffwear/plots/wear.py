"""Figures of the wear studies (cf. thesis Figs. 5-5, 6-9, 7-4, 7-5)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np


def wear_figures(out, *, name, theta, depth_mm, history, crank, first, last, clearance_mm,
                 thesis, label="diffwear (EFM)", markers="simulated dynamic cycles"):
    figs = []
    # wear profile with the thesis maxima drawn in
    fig, ax = plt.subplots(figsize=(7, 3.6))
    ax.plot(theta, depth_mm, lw=1.6, label=label)
    for (label, ref), style in zip(thesis.items(), ("--", ":", "-.")):
        if "max_wear_depth_mm" in ref:
            ax.axhline(ref["max_wear_depth_mm"], ls=style, color="k", lw=0.9,
                       label=f"thesis {label}: max {ref['max_wear_depth_mm']} mm")
    ax.set_xlabel("bushing angle θ [rad]")
    ax.set_ylabel("wear depth [mm]")
    ax.set_xlim(0, 2 * np.pi)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"{name}: bushing wear profile (cf. Figs. 5-5/6-9/7-4/7-5)")
    fig.tight_layout()
    fig.savefig(out.file("wear_profile.png"), dpi=120)
    plt.close(fig)
    figs.append("wear_profile.png")

    cycles, dmax, vol = history
    fig, axes = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    axes[0].plot(np.concatenate([[0], cycles]), np.concatenate([[0], dmax]), "o-", ms=3)
    axes[1].plot(np.concatenate([[0], cycles]), np.concatenate([[0], vol]), "o-", ms=3)
    for (label, ref), mk in zip(thesis.items(), ("s", "^", "D")):
        if "max_wear_depth_mm" in ref:
            axes[0].plot(cycles[-1] if len(cycles) else 0, ref["max_wear_depth_mm"], mk,
                         label=f"thesis {label}")
        if "wear_volume_mm3" in ref:
            axes[1].plot(cycles[-1] if len(cycles) else 0, ref["wear_volume_mm3"], mk,
                         label=f"thesis {label}")
    axes[0].set_ylabel("max depth [mm]")
    axes[1].set_ylabel("volume [mm³]")
    axes[1].set_xlabel("cycles")
    for ax in axes:
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:  # thesis markers only when compared
            ax.legend(fontsize=8)
    axes[0].set_title(f"{name}: wear vs cycles (markers: {markers})")
    fig.tight_layout()
    fig.savefig(out.file("wear_history.png"), dpi=120)
    plt.close(fig)
    figs.append("wear_history.png")

    fig, axes = plt.subplots(1, 2, figsize=(9, 4))
    for hist, label in ((first, "first cycle"), (last, "last cycle")):
        off = np.asarray(hist.offset) * 1e3
        axes[0].plot(off[:, 0], off[:, 1], lw=1, label=label)
        axes[1].plot(np.degrees(crank), np.asarray(hist.force_magnitude), lw=1,
                     label=f"|F| {label}")
    t = np.linspace(0, 2 * np.pi, 200)
    axes[0].plot(clearance_mm * np.cos(t), clearance_mm * np.sin(t), "k:", lw=0.8,
                 label="initial clearance")
    axes[0].set_aspect("equal")
    axes[0].set_xlabel("pin offset x (rod frame) [mm]")
    axes[0].set_ylabel("y [mm]")
    axes[0].set_title("pin centre locus in the bushing")
    axes[1].set_xlabel("crank angle [deg]")
    axes[1].set_ylabel("joint force [N]")
    axes[1].set_title("crank-rod joint force")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out.file("contact_locus_and_force.png"), dpi=120)
    plt.close(fig)
    figs.append("contact_locus_and_force.png")
    return figs
