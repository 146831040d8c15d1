"""Figures of the calibration against measured wear data (``diffwear calibrate``)."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import FuncFormatter

from .files import save
from .layout import legend_outside, wrapped


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
    band: tuple | None = None  # (lower, upper) of the final model's 90 % predictive band
    band_label: str = "90 % predictive band"  # says when the band pools two models


def series_fit(path: Path, f: SeriesFit) -> Path:
    """The data with error bars against the base fit and the final model, with
    the final model's 90 % predictive band (model and noise) where known."""
    fig, ax = plt.subplots(figsize=(8.4, 3.6))
    order = np.argsort(f.x)
    few = f.x.size < 3  # a line through one or two points shows nothing: markers
    if f.band is not None:
        lo, hi = (np.asarray(b)[order] * f.scale for b in f.band)
        if few:
            ax.errorbar(f.x[order], 0.5 * (lo + hi), yerr=0.5 * (hi - lo), fmt="none",
                        ecolor="C1", alpha=0.35, lw=6, label=f.band_label)
        else:
            ax.fill_between(f.x[order], lo, hi, color="C1", alpha=0.25, lw=0,
                            label=f.band_label)
    ax.errorbar(f.x, f.y * f.scale, yerr=f.sigma * f.scale, fmt=".", ms=3, color="k",
                label="data (1 sigma)", alpha=0.7)
    ax.plot(f.x[order], f.base[order] * f.scale, "s" if few else "-", mfc="none",
            label="base fit")
    if f.chosen is not None:
        ax.plot(f.x[order], f.chosen[order] * f.scale, "D" if few else "--", mfc="none",
                label=f.chosen_label)
    if f.holdout.any():
        ax.plot(f.x[f.holdout], f.y[f.holdout] * f.scale, "o", mfc="none", color="r", ms=6,
                label="held out")
    what = {"profile": "wear depth", "volume": "worn volume", "max_depth": "maximum depth",
            "force": "joint force"}.get(f.kind, f.kind)
    title = {"profile": "worn profile", "volume": "worn volume (weighed)",
             "max_depth": "maximum wear depth", "force": "joint force"}.get(f.kind, f.name)
    if f.cycles is not None and f.kind in ("profile", "force"):
        title += f" at {f.cycles:,.0f} cycles"
    ax.set(xlabel=f.xlabel, ylabel=f"{what} [{f.unit}]", title=title)
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
        # few points (a weighing, a depth history) as large open markers drawn
        # last, so that a profile's hundreds of points do not hide them
        few = np.size(r) < 30
        axes[1].plot(n, r, "D" if few else ".", ms=7 if few else 3,
                     mfc="none" if few else None, zorder=3 if few else 2,
                     label=f.name.replace("_", " "))
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


def candidates(path: Path, names: Sequence[str], criteria: Sequence[float],
               qualifies: Sequence[bool], adopted: Sequence[str], window: float) -> Path:
    """Each candidate refitted on the base model: its penalised criterion
    (BIC, on the fit points) above the best candidate's, qualifying ones
    filled, the adopted ones named; the comparable window shaded (within it
    the simplest wins).  Each bar's end is a dot (the best candidate's bar
    has no length); bars beyond the axis are cut at its end."""
    from matplotlib.patches import Patch

    fig, ax = plt.subplots(figsize=(8.4, 0.9 + 0.32 * max(len(names), 1)))
    c = np.asarray(criteria, dtype=float)
    gap = c - np.min(c[np.asarray(qualifies, bool)]) if any(qualifies) else c - np.min(c)
    top = max(10 * window, 1.0)
    y = np.arange(len(names))[::-1]
    colors = ["C0" if q else "0.75" for q in qualifies]
    ax.barh(y, np.clip(gap, 0.0, top), color=colors, left=0.0)
    # each bar's end marked, so that the best candidate's (length zero) shows
    ax.scatter(np.clip(gap, 0.0, top), y, s=18, c=colors, edgecolors="k", linewidths=0.6,
               zorder=3, clip_on=False)
    ax.axvspan(0, window, color="C2", alpha=0.12, lw=0)
    for yi, g in zip(y, gap):
        if g > top:
            ax.text(top, yi, f" {g:,.0f} ", ha="right", va="center", fontsize=7, color="w")
        elif g == 0.0:
            ax.text(0.02 * top, yi, "best", ha="left", va="center", fontsize=7)
    ax.set_yticks(y, [n + ("  (adopted)" if n in adopted else "") for n in names])
    handles = [Patch(color="C0", label="qualifies (p < 0.001)"),
               Patch(color="0.75", label="does not qualify"),
               Patch(color="C2", alpha=0.12, label=f"comparable (within {window:g})")]
    ax.set(xlim=(0, top), xlabel="criterion (BIC on the fit points) above the best candidate's",
           title="candidate causes refitted on the base model")
    ax.legend(handles=handles, fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0),
              borderaxespad=0.0)
    return _save(fig, path)


def discrepancy(path: Path, x, delta, band, xlabel: str, title: str,
                covered: tuple | None = None) -> Path:
    """The learned discrepancy delta(x) of the wear coefficient, in per cent,
    with its 1-sigma band; ``covered``: the range of x the data see (shaded;
    outside it the band is the prior's)."""
    fig, ax = plt.subplots(figsize=(6.4, 3.4))
    x, d, b = np.asarray(x), 100 * np.asarray(delta), 100 * np.asarray(band)
    if covered is not None:
        lo, hi = covered
        spans = [(lo, hi)] if hi >= lo else [(lo, x.max()), (x.min(), hi)]
        for k, (a, c) in enumerate(spans):
            ax.axvspan(a, c, color="0.9", zorder=0,
                       label=None if k else "range the data see")
    ax.fill_between(x, d - b, d + b, alpha=0.3, label="1 sigma")
    ax.plot(x, d, label="delta")
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set(xlabel=xlabel, ylabel="k (1 + delta): delta [%]", title=wrapped(title, 55))
    if xlabel.endswith("[MPa]") or xlabel.endswith("[mm/s]"):
        ax.set_xscale("log")
    if xlabel.startswith("bushing angle"):
        ax.set_xticks(np.arange(0, 361, 45))
        ax.set_xlim(0, 360)
    legend_outside(ax)
    return _save(fig, path)


def posterior(path: Path, columns: dict, weights, title: str) -> Path:
    """Each number's posterior: a weighted histogram of the draws, with its
    5-95 % interval.  ``columns``: {label: values}."""
    n = max(len(columns), 1)
    cols = min(n, 4)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.5 * rows), squeeze=False)
    w = np.asarray(weights, dtype=float)
    for ax, (label, values) in zip(axes.flat, columns.items()):
        v = np.asarray(values, dtype=float)
        ax.hist(v, bins=24, weights=w, color="C0", alpha=0.7)
        order = np.argsort(v)
        cw = np.cumsum(w[order]) / np.sum(w)
        lo, hi = np.interp([0.05, 0.95], cw, v[order])
        ax.axvline(lo, color="k", ls=":", lw=1)
        ax.axvline(hi, color="k", ls=":", lw=1)
        ax.set(xlabel=label, yticks=[])
        ax.ticklabel_format(axis="x", style="sci", scilimits=(-3, 4))
    for ax in list(axes.flat)[n:]:
        ax.set_axis_off()
    # about 13 characters of a 10-point title to the inch
    fig.suptitle(wrapped(title + " (dotted: 5 % and 95 %)", int(13 * 3.2 * cols)), fontsize=10)
    return _save(fig, path)


def life(path: Path, trajectory: tuple, limit: float, measured: Sequence[tuple],
         horizon: float, life_band: tuple, models: Sequence[tuple[str, float]] = ()) -> Path:
    """The maximum wear depth with its 90 % band: over the campaign and its
    horizon beside the measured maxima (held-out ones open), and over the
    whole life to the limit, with the life's band.  ``models``: (name,
    weight) of each explanation whose draws were pooled, when more than one."""
    n, lo, mid, hi = (np.asarray(a, dtype=float) for a in trajectory)
    fig, (near, far) = plt.subplots(1, 2, figsize=(11.0, 3.8),
                                    gridspec_kw={"width_ratios": [1, 1.3]})
    for ax in (near, far):
        ax.fill_between(n, lo * 1e3, hi * 1e3, color="C0", alpha=0.25, lw=0,
                        label="90 % band")
        ax.plot(n, mid * 1e3, color="C0", label="median")
    for k, (cycles, depth, held) in enumerate(measured):
        near.plot(cycles, depth * 1e3, "D", ms=6, color="k", mfc="none" if held else "k",
                  label=("deepest measured (open: held out)" if k == 0 else None))
    near.axvline(horizon, color="0.5", ls=":", lw=1, label="horizon")
    upto = 1.1 * horizon
    inside = (n <= upto) & np.isfinite(hi)
    top = max(float(np.max(hi[inside], initial=0.0)), max((d for _, d, _ in measured),
                                                          default=0.0))
    near.set(xlim=(0, upto), ylim=(0, 1.15e3 * top if top > 0 else 1.0),
             xlabel="cycles", ylabel="maximum wear depth [mm]",
             title="the campaign and its horizon")
    far.axhline(limit * 1e3, color="r", ls="--", lw=1, label=f"limit {limit * 1e3:.3g} mm")
    q05, q95 = life_band
    if np.isfinite(q05) and np.isfinite(q95):
        far.axvspan(q05, min(q95, n[-1]), color="r", alpha=0.08, label="life, 90 % band")
    far.set(xlabel="cycles", xlim=(0, n[-1]), ylim=(0, None), title="to the limit")
    for ax in (near, far):  # 300000 reads 300k: the ticks never run together
        ax.xaxis.set_major_formatter(FuncFormatter(_cycles_tick))
    handles, labels = [], []
    for ax in (near, far):
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    far.legend(handles, labels, fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0),
               borderaxespad=0.0)
    over = ("the posterior's draws" if len(models) < 2 else
            "both explanations' draws, pooled: "
            + ", ".join(f"{name} {100 * w:.0f} %" for name, w in models))
    # a long pair of model names goes on a second line rather than off the figure
    fig.suptitle("\n".join(textwrap.wrap(f"Wear life: maximum depth over {over}", 100)),
                 fontsize=11)
    return _save(fig, path)


def _cycles_tick(value: float, _pos=None) -> str:
    """A cycle count as a tick label: 5000, 40k, 1.2M."""
    if abs(value) >= 1e6:
        return f"{value / 1e6:g}M"
    return f"{value / 1e3:g}k" if abs(value) >= 1e4 else f"{value:g}"


def next_measurement(path: Path, scores: dict, ylabel: str, chosen: tuple | None) -> Path:
    """What each candidate inspection (kind, cycle count) would teach."""
    fig, ax = plt.subplots(figsize=(8.4, 3.2))
    words = {"profile": "worn profile", "weighing": "weighing"}
    for kind, (cycles, values) in scores.items():
        ax.plot(cycles, values, "o-", ms=3, label=words.get(kind, kind))
    if chosen is not None:
        ax.plot(*chosen, "*", ms=14, color="r", label="the next measurement")
    ax.set(xlabel="cycles at the inspection", ylabel=ylabel, title="the next measurement")
    legend_outside(ax)
    return _save(fig, path)


def _save(fig, path: Path) -> Path:
    return save(fig, path, dpi=110)
