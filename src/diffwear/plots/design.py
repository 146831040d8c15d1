"""Figures of the bushing design (thesis Ch. 8)."""

from __future__ import annotations

import matplotlib.pyplot as plt

from .files import save
from .layout import legend_outside


def life_map(path, maps: dict, j: int, answer, thesis) -> None:
    """Cycles to the wear limit of joint ``j`` over its (diameter, depth) map,
    with the design ``answer`` and the ``thesis``'s (both (d1, d2, h1, h2) [m])."""
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    d, h = maps["d_m"] * 1e3, maps["h_m"] * 1e3
    c = ax.contourf(d, h, maps[f"cyc{j}"].T / 1e3, levels=12, cmap="viridis")
    fig.colorbar(c, ax=ax, label=f"joint {j} life [thousand cycles to 2 mm wear]")
    ax.plot(answer[j - 1] * 1e3, answer[j + 1] * 1e3, "r*", ms=12, label="equal-life answer")
    ax.plot(thesis[j - 1] * 1e3, thesis[j + 1] * 1e3, "wo", mec="k", label="thesis Table 8-4")
    ax.set_xlabel(f"bushing diameter d{j} [mm]")
    ax.set_ylabel(f"bushing depth h{j} [mm]")
    ax.set_title(f"Joint {j}: cycles to 2 mm wear")
    legend_outside(ax, below=True, ncol=2)  # the colour bar is on the right
    save(fig, path, dpi=120)
