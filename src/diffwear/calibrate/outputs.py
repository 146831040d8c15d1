"""The files of a calibration (`write`): ``summary.json`` (effect_identified,
effect_strength, effect_strength_std, heldout_rmse_before/after,
candidates, ...), ``residuals.csv`` (every point: series, kind, x, data,
base and final model, normalised residuals, held out or not),
``fit_<series>.png`` (data against the base and the final model),
``residual_structure.png`` (residual against bushing angle, against cycle
count, and the force residual's harmonic spectrum), ``candidates.png``
(score statistics), the discrepancy, posterior, life and next-measurement
figures where there are such, and ``report.md`` linking them.

Every number first, then every file: the report's blocks
(`reporting.report_blocks`), then the figures' data, then the files in one
`OutputDir.write`.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np

from ..io import OutputDir, Outputs
from ..plots import calibration as plots_calibration
from ..report import Figure, Report, Section
from . import learned
from .frame_check import frame_warnings
from .identify import AMBIGUITY, Calibration
from .reporting import disc_words, report_blocks
from .residual_structure import locate_residual, series_rms
from .residual_words import describe_residuals

# the figures' axes: y scale and unit, x label and scale (angles, SI rad, drawn in deg)
UNIT = {"profile": (1e6, "um", "bushing angle [deg]", 180 / math.pi),
        "max_depth": (1e3, "mm", "cycles", 1.0), "volume": (1e9, "mm^3", "cycles", 1.0),
        "force": (1.0, "N", "crank angle [deg]", 180 / math.pi)}


def write(c: Calibration, out: OutputDir, log=print) -> dict:
    """Every file of the calibration ``c`` into ``out``; returns the summary."""
    data = c.dataset
    summary = c.summary()
    final = c.final or c.base
    summary["series_rms"] = series_rms(c, final)
    structure = locate_residual(c)
    summary["residual_words"] = describe_residuals(c, structure)
    summary["frame_warnings"] = frame_warnings(c)
    for w in summary["frame_warnings"]:
        log(f"warning: {w['message']}")
    summary["series"] = [s.name for s in data.series]
    blocks = report_blocks(c, summary, structure)
    files = _figures(c, structure)
    summary["plots"] = figures = files.names
    p = c.problem
    files.csv("residuals.csv", {
        "series": p.series_of_point, "x": np.concatenate([s.x for s in data.series]),
        "data": p.y, "base_model": c.base.prediction, "final_model": final.prediction,
        "base_residual": c.base.residual, "final_residual": final.residual,
        "held_out": p.holdout.astype(int)})
    files.report("report.md", Report(f"Calibration: {data.name}", [
        *blocks, Section("Plots", [*(Figure(f) for f in figures),
                                   f"Wall time {c.wall_time_s:.0f} s."])]))
    files.json("summary.json", summary)   # last: it marks the run finished
    out.write(files)
    log(f"wrote {out.path}")
    return summary


def _figures(c: Calibration, structure: dict) -> Outputs:
    """The calibration's figures (`plots.calibration`) from its numbers, each
    drawn when the files are written: every number first, then the figures."""
    p = c.problem
    which = p.series_of_point
    final = c.final or c.base
    stage1 = c.selection.stages[0] if c.selection is not None and c.selection.stages else None
    ranked = sorted(stage1.assessed.values(), key=lambda a: a.criterion) if stage1 else []
    deepest = _deepest(c.dataset)
    chosen_label = _final_label(final)
    members = _members_of(final)
    covered = _covered(final.discrepancy, c) if final.discrepancy is not None else None
    # the fits' series, the residuals and the force residual's spectrum
    band = None if c.posterior is None else c.predictive_band()
    pooled = c.pool_models()
    first = " (the first of two explanations)" if pooled else ""
    title_p = ("posterior of " + ("the first of two explanations" if pooled else "the final model")
               + " (" + _posterior_words(c.posterior) + ")" if c.posterior is not None else "")
    if pooled:   # an open answer: the line is the first model's, the band both models'
        chosen_label += first
    band_label = ("90 % predictive band, pooled over both" if pooled
                  else "90 % predictive band")
    fits = []
    for k, s in enumerate(c.dataset.series):
        m = which == k
        scale, unit, xlabel, xscale = UNIT[s.kind]
        fits.append(plots_calibration.SeriesFit(
            name=s.name, kind=s.kind, unit=unit, xlabel=xlabel, scale=scale, x=s.x * xscale,
            y=s.y, sigma=s.sigma, holdout=s.holdout, base=c.base.prediction[m],
            chosen=None if final is c.base else final.prediction[m],
            chosen_label=chosen_label, cycles=s.cycles,
            band=None if band is None else (band[0][m], band[1][m]), band_label=band_label))
    cycles = [s.cycle_counts for s in c.dataset.series]
    residuals = [c.base.residual[which == k] for k in range(len(c.dataset.series))]
    harmonics = structure.get("force_residual_harmonics")
    # the first stage's candidates, by criterion
    adopted = [learned.label(m) for m in members] if ranked else []
    labels = [learned.label(a.effect) for a in ranked]
    if final.discrepancy is not None:  # the learned discrepancy with its band
        d = final.discrepancy
        lib = c.problem.library
        span = learned.span(d, c.dataset, lib)
        b = c.summary_discrepancy().get("log_k_per_coefficient")
        x, delta, band_d = learned.curve(d, final.discrepancy_coefficients,
                                         final.discrepancy_cov, span, c.dataset.fit_cycles, b,
                                         lib)
        axis = lib.variable(d).axis
        title_d = f"learned discrepancy of k over {disc_words(d, lib)}{first}"
    if c.posterior is not None:  # the posterior's numbers in the dataset's units
        post = c.posterior
        numbers = post.layout.natural(post.z)
        columns = {c.dataset.label(n): c.dataset.in_own_unit(n, v)
                   for n, v in numbers.items() if not n.startswith("delta_")}
    f = c.forecast
    nxt = (f.next_measurement if f is not None else None) or {}
    chosen = None
    if f is not None and nxt.get("kind") in f.scores:  # the inspection to take next
        cyc, val = f.scores[nxt["kind"]]
        chosen = (nxt["cycles"], float(val[int(np.argmin(np.abs(cyc - nxt["cycles"])))]))
    ylabel = ("separation of the two explanations [sigma]" if "expected_separation_sigma" in nxt
              else "life band narrowed by [share]" if "life_band_reduction" in nxt
              else "depth band narrowed by [share]")

    files = Outputs()
    for fit in fits:
        files.figure(f"fit_{fit.name}.png", partial(plots_calibration.series_fit, f=fit))
    files.figure("residual_structure.png", lambda path: plots_calibration.residual_structure(
        path, fits, residuals, cycles, harmonics))
    if ranked:
        files.figure("candidates.png", lambda path: plots_calibration.candidates(
            path, labels, [a.criterion for a in ranked], [a.qualifies for a in ranked],
            adopted, AMBIGUITY))
    if final.discrepancy is not None:
        files.figure("discrepancy.png", lambda path: plots_calibration.discrepancy(
            path, x, delta, band_d, axis, title_d, covered))
    if c.posterior is not None:
        files.figure("posterior.png", lambda path: plots_calibration.posterior(
            path, columns, post.weights, title_p))
    if f is not None and f.trajectory:
        files.figure("life.png", lambda path: plots_calibration.life(
            path, f.trajectory, f.limit, deepest, f.horizon, (f.life["q05"], f.life["q95"]),
            [(m["name"], m["weight"]) for m in f.life.get("models", [])]))
        if f.scores:
            files.figure("next_measurement.png", lambda path: plots_calibration.next_measurement(
                path, f.scores, ylabel, chosen))
    return files


def _members_of(fit) -> list[str]:
    return [*fit.effects, *([learned.candidate(fit.discrepancy)] if fit.discrepancy else [])]


def _covered(variable: str, c: Calibration):
    """The range of ``variable`` the fit data see, in the plot's units."""
    data = c.dataset
    if variable == "angle":
        return learned.worn_arc(data)
    if variable == "cycles":
        return (0.0, float(data.fit_cycles))
    if variable == "depth":
        deepest = [float(np.max(s.y)) for s in data.series
                   if s.kind == "profile" and not s.holdout.all()]
        return (0.0, 1e3 * max(deepest)) if deepest else None
    return None


def _deepest(data) -> list[tuple]:
    """(cycles, deepest reading, held out) of each measured profile."""
    return [(float(s.cycles), float(np.max(s.y)), bool(s.holdout.all()))
            for s in data.series if s.kind == "profile"]


def _final_label(f) -> str:
    parts = [*f.effects] + ([f"discrepancy in {f.discrepancy}"] if f.discrepancy else [])
    return "with " + " + ".join(parts) if parts else "base model"


def _posterior_words(post) -> str:
    """How the posterior's draws were made and weighted, for a figure title."""
    if post.method == "nuts":
        return "NUTS"
    if post.diagnostics.get("weights") == "gaussian, unchecked":
        return "Laplace, unchecked: the importance check failed"
    return ("Laplace, importance-weighted" if "pareto_k" in post.diagnostics
            else "Laplace, linearised")


