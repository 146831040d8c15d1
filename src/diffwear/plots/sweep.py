"""Figures of the sweeps and the sensitivity analysis: heatmaps and line plots
of a grid, tornado plots of elasticities, histograms of sampled outputs."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..errors import InputError
from .files import save
from .layout import legend_outside, wrapped

# What the sweeps' and the sensitivity's code names stand for, as a reader of
# the field names them (`quantity`; `diffwear.sweep.models` defines them).
NAMES = {
    "k": "wear coefficient k", "clearance": "radial clearance c",
    "depth": "bushing depth h", "diameter": "pin diameter d", "mu": "friction coefficient μ",
    "free_length": "spring free length L0", "restitution": "restitution e_r",
    "max_depth": "max wear depth", "volume": "worn volume",
    "mean_joint_force": "mean joint force", "life": "life",
}
UNITS = {"mm": "mm", "mm3": "mm³", "N": "N", "um": "µm", "m": "m", "cycles": "cycles",
         "s": "s"}


def quantity(name: str) -> str:
    """A code name in words with its unit: "max_depth_mm" -> "max wear
    depth [mm]", "volume_mm3" -> "worn volume [mm³]", "k" -> "wear
    coefficient k"; a name it does not know stays as it is."""
    head, _, unit = name.rpartition("_")
    if head and unit in UNITS:
        return f"{NAMES.get(head, head.replace('_', ' '))} [{UNITS[unit]}]"
    return NAMES.get(name, name)


def sampled_ticks(axis, values) -> None:
    """Ticks at a short grid's sampled values (<= 10), none between: a cell's
    centre is where its value was sampled."""
    from matplotlib.ticker import FixedLocator, NullLocator

    values = np.asarray(values, dtype=float)
    if values.size > 10:
        return
    axis.set_major_locator(FixedLocator(values))
    axis.set_minor_locator(NullLocator())
    axis.set_ticklabels([f"{v:.4g}" for v in values])


def geometric(v) -> bool:
    """True for a positive grid of constant ratio (drawn on a log axis)."""
    v = np.asarray(v, dtype=float)
    if v.size < 3 or np.any(v <= 0):
        return False
    r = v[1:] / v[:-1]
    return bool(np.allclose(r, r[0], rtol=1e-6) and not np.isclose(r[0], 1.0))


def heatmap(path, x, y, z, *, xlabel: str, ylabel: str, title: str, zlabel: str = "",
            annotate: bool = True):
    """Heatmap of z[i, j] at (x[j], y[i]) (cells centred on the values; log axes
    for geometric grids; ticks at the sampled values); the colour bar labelled
    ``zlabel`` (the quantity and its unit); values written in the cells up to
    10 x 10."""
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    mesh = ax.pcolormesh(x, y, z, shading="nearest", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label=zlabel)
    if geometric(x):
        ax.set_xscale("log")
    if geometric(y):
        ax.set_yscale("log")
    sampled_ticks(ax.xaxis, x)
    sampled_ticks(ax.yaxis, y)
    if annotate and z.shape[0] <= 10 and z.shape[1] <= 10:
        for i, yi in enumerate(y):
            for j, xj in enumerate(x):
                ax.text(xj, yi, f"{z[i, j]:.3g}", ha="center", va="center", fontsize=7,
                        color="w")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(wrapped(title), fontsize=9)
    return save(fig, path, dpi=110)


def line(path, x, y, *, xlabel: str, ylabel: str, title: str) -> Path:
    """One output over a 1-D grid (log x axis for a geometric grid)."""
    fig, ax = plt.subplots(figsize=(6, 3.6))
    ax.plot(x, y, "o-")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    if geometric(x):
        ax.set_xscale("log")
    ax.set_title(wrapped(title), fontsize=9)
    return save(fig, path, dpi=110)


def tornado(path, sens, output: str, *, rel_change: float = 0.1,
            title: str | None = None) -> Path:
    """Tornado plot of a `diffwear.sweep.sensitivity.Sensitivity`: the
    linearised change of ``output`` [%] for each parameter moved by
    +-``rel_change`` (bars sorted by size; = +-elasticity x change)."""
    e = {p: sens.elasticity(output, p) for p in sens.wrt}
    order = sorted(e, key=lambda p: abs(e[p]) if math.isfinite(e[p]) else -1)
    fig, ax = plt.subplots(figsize=(6.4, 0.45 * len(order) + 1.7))
    for i, p in enumerate(order):
        d = 100 * e[p] * rel_change
        ax.barh(i, d, color="tab:red", alpha=0.8,
                label=f"p × {1 + rel_change:g}" if i == 0 else None)
        ax.barh(i, -d, color="tab:blue", alpha=0.8,
                label=f"p × {1 - rel_change:g}" if i == 0 else None)
        ax.text(abs(d), i, f"  ε = {e[p]:+.2f}", va="center", fontsize=8)
    ax.set_yticks(range(len(order)), [quantity(p) for p in order])
    ax.axvline(0, color="k", lw=0.8)
    name = quantity(output).split(" [")[0]
    ax.set_xlabel(f"change of {name} [%] (linearised)\n"
                  "ε = (p / y) ∂y/∂p: the elasticity of y to the parameter p")
    legend_outside(ax)
    ax.set_title(wrapped(title or f"sensitivity of {name} ({sens.method})"), fontsize=9)
    lim = max([abs(100 * v * rel_change) for v in e.values() if math.isfinite(v)] + [1e-12])
    ax.set_xlim(-1.35 * lim, 1.75 * lim)  # room right for the largest bar's ε
    return save(fig, path, dpi=110)


def histogram(path, prop, output: str, *, bins: int = 20, xlabel: str | None = None,
              title: str | None = None) -> Path:
    """Histogram of the sampled ``output`` (or "life_cycles") of a
    `diffwear.sweep.sensitivity.Propagation`, with the linearised normal
    estimate and the design-point value."""
    if output == "life_cycles":
        if prop.life is None:
            raise InputError("histogram of 'life_cycles': this propagation computed no life "
                             "(give propagate_scatter(..., life=(output, limit, cycles)))")
        x = prop.life["samples"]
    else:
        x = prop.result[output]
    s = prop.stats[output]
    fig, ax = plt.subplots(figsize=(8.4, 4.0))
    ax.hist(x, bins=bins, density=True, alpha=0.6, label=f"{len(x)} samples")
    grid = np.linspace(np.min(x), np.max(x), 200)
    if s["std_linear"] > 0:
        pdf = np.exp(-0.5 * ((grid - s["mean_linear"]) / s["std_linear"]) ** 2)
        ax.plot(grid, pdf / (s["std_linear"] * math.sqrt(2 * math.pi)), "k--",
                label="linearised (normal)")
    ax.axvline(s["mean"], color="tab:red", label=f"mean {s['mean']:.4g}")
    ax.axvspan(s["p5"], s["p95"], color="tab:red", alpha=0.08, label="5-95 %")
    ax.set_xlabel(xlabel or output)
    ax.set_ylabel("density")
    legend_outside(ax)
    ax.set_title(wrapped(title or (f"{output}: {prop.name} {prop.distribution}, "
                                    f"+-{100 * prop.scatter:.0f} %")),
                 fontsize=9)
    return save(fig, path, dpi=110)
