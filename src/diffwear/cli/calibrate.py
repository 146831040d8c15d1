"""``diffwear calibrate DATA_DIR --out DIR``: the measured-data loop and its report.

Writes ``summary.json`` (effect_identified, effect_strength,
effect_strength_std, heldout_rmse_before/after, candidates, ...),
``residuals.csv`` (every point: series, kind, x, data, base and final model,
normalised residuals, held out or not), ``fit_<series>.png`` (data against the
base and the final model), ``residual_structure.png`` (residual against bushing
angle, against cycle count, and the force residual's harmonic spectrum),
``candidates.png`` (score statistics) and ``report.md`` linking them.
"""

from __future__ import annotations

import math

import numpy as np  # noqa: E402

from ..calibrate import learned
from ..calibrate.dataset import PARAMETERS, Dataset  # noqa: E402
from ..calibrate.discrepancy import VARIABLES
from ..calibrate.effects import EFFECTS  # noqa: E402
from ..calibrate.fit import ModelSettings  # noqa: E402
from ..calibrate.frame_check import frame_warnings  # noqa: E402
from ..calibrate.identify import (  # noqa: E402
    GOF_SIGMAS,
    LR_CRITICAL,
    STRENGTH_SIGMAS,
    Calibration,
    calibrate,
)
from ..calibrate.residual_structure import residual_structure, series_rms
from ..calibrate.residual_words import describe_residuals  # noqa: E402
from ..io import OutputDir  # noqa: E402
from ..plots import calibration as plots_calibration
from ..report import Block, Bullets, Figure, Report, Section, Table, render

# SI units of the fitted parameters in the report (the dataset's own units are
# converted on loading: k in mm^3/(N m) is 1e-9 1/Pa)
REPORT_UNITS = {"wear coefficient": "1/Pa = m^3/(N m)", "length": "m", None: "-",
                "mass": "kg", "inertia": "kg m^2", "stiffness": "N/m"}

DESCRIPTION = "calibrate the rig model on measured wear data and identify a missing effect"
# the figures' axes: y scale and unit, x label and scale (angles, SI rad, drawn in deg)
UNIT = {"profile": (1e6, "um", "bushing angle [deg]", 180 / math.pi),
        "max_depth": (1e3, "mm", "cycles", 1.0), "volume": (1e9, "mm^3", "cycles", 1.0),
        "force": (1.0, "N", "crank angle [deg]", 180 / math.pi)}


def _plots(out: OutputDir, c: Calibration) -> list[str]:
    """The calibration's figures (`plots.calibration`) from its numbers."""
    p = c.problem
    which = p.series_of_point
    final = c.final or c.base
    fits = []
    for k, s in enumerate(c.dataset.series):
        m = which == k
        scale, unit, xlabel, xscale = UNIT[s.kind]
        fits.append(plots_calibration.SeriesFit(
            name=s.name, kind=s.kind, unit=unit, xlabel=xlabel, scale=scale, x=s.x * xscale,
            y=s.y, sigma=s.sigma, holdout=s.holdout, base=c.base.prediction[m],
            chosen=None if final is c.base else final.prediction[m],
            chosen_label=_final_label(final), cycles=s.cycles))
    files = [plots_calibration.series_fit(out.file(f"fit_{f.name}.png"), f).name for f in fits]
    cycles = [s.cycle_counts for s in c.dataset.series]
    residuals = [c.base.residual[which == k] for k in range(len(c.dataset.series))]
    harmonics = residual_structure(c).get("force_residual_harmonics")
    files.append(plots_calibration.residual_structure(
        out.file("residual_structure.png"), fits, residuals, cycles, harmonics).name)
    files.append(plots_calibration.candidates(
        out.file("candidates.png"), [s.effect for s in c.scores],
        [s.statistic for s in c.scores], LR_CRITICAL[1]).name)
    d = c.discrepancy.chosen if c.discrepancy is not None else None
    if d is not None:
        f = d.model
        span = learned.span(d.variable, c.dataset)
        x, delta, band = learned.curve(d.variable, f.discrepancy_coefficients,
                                       f.discrepancy_cov, span)
        label = {"angle": "bushing angle [deg]", "pressure": "contact pressure [MPa]",
                 "sliding_speed": "sliding speed [mm/s]", "cycles": "cycles",
                 "depth": "wear depth [mm]"}[d.variable]
        files.append(plots_calibration.discrepancy(
            out.file("discrepancy.png"), x, delta, band, label,
            f"learned discrepancy of k over {d.variable.replace('_', ' ')}").name)
    return files


def _stage_line(k: int, st: dict) -> str:
    """One forward-selection stage in words."""
    qualified = [e for e, c in st["candidates"].items() if c["qualifies"]]
    text = (f"stage {k + 1}: {len(st['candidates'])} refitted, qualifying: "
            f"{', '.join(qualified) or 'none'}")
    if st.get("added"):
        text += f"; added **{st['added']}**"
    if st.get("dropped"):
        text += f"; dropped {', '.join(st['dropped'])} (no longer qualifying beside the rest)"
    if st.get("ambiguous"):
        text += f"; **{' or '.join(st['ambiguous'])}**: too close to tell apart"
    if st.get("failed"):
        text += "; refit failed: " + "; ".join(f"{e} ({why})" for e, why in st["failed"].items())
    return text


def _final_label(f) -> str:
    parts = [*f.effects] + ([f"discrepancy in {f.discrepancy}"] if f.discrepancy else [])
    return "with " + " + ".join(parts) if parts else "base model"


def _fmt(v, digits=4):
    return "n/a" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.{digits}g}"


def _report(c: Calibration, summary: dict, files: list[str]) -> Report:
    d = c.dataset
    blocks: list[Block] = [
        d.description or "",
        f"Dataset `{d.path}`: {len(d.series)} series, "
        f"{c.base.n_fit} fit points, {c.base.n_holdout} held-out points; fitted: "
        f"{', '.join(d.fit_names)}.  Model: {summary['model_settings']['description']}.  "
        "Residuals are in units of each series' stated 1-sigma noise.",
        *(f"> {note}" for note in d.notes),
        *(f"> **Warning:** {w['message']}." for w in summary.get("frame_warnings", [])),
        *(f"> **Warning:** {w['message']}." for w in summary.get("unit_warnings", [])),
    ]
    if c.base.n_fit <= len(d.fit_names) + 2:
        blocks.append(f"**What these data can support:** {c.base.n_fit} numbers for "
                      f"{len(d.fit_names)} fitted parameters leave {c.base.dof} degree(s) of "
                      "freedom: enough to calibrate, not to tell candidate effects apart (a "
                      "score test needs residual structure: profiles at several cycle counts, "
                      "a mass history or a force trace).")
    final = c.final or c.base
    blocks.append(Section("Result", [
        Bullets([*_effect_lines(summary),
                 f"residual unexplained by the library: "
                 f"{'**yes**' if summary['residual_unexplained'] else 'no'}"
                 f" (chi2 {c.gof['chi2']:.1f} on {c.gof['dof']} dof; noise allows "
                 f"{c.gof['limit']:.1f})",
                 *_discrepancy_lines(summary)]),
        Bullets([f"mechanism suspect: **{summary['suspect']}**"
                 + _suspect_verdict(summary["suspects"][0])] if summary.get("suspect") else []),
        Table(("", "base model", "final model"), [
            ("held-out RMSE [sigma]", _fmt(summary["heldout_rmse_before"]),
             _fmt(summary["heldout_rmse_after"])),
            ("fit RMSE [sigma]", _fmt(summary["fit_rmse_before"]),
             _fmt(summary["fit_rmse_after"])),
            *((f"{n} [{REPORT_UNITS[PARAMETERS[n]]}]",
               f"{_fmt(c.base.params[n])} +- {_fmt(c.base.params_std[n], 2)}",
               f"{_fmt(final.params[n])} +- {_fmt(final.params_std[n], 2)}")
              for n in d.fit_names)]),
    ]))
    candidates = []
    for cand in summary["candidates"]:
        refitted = "refit_strength" in cand
        candidates.append((
            cand["name"], _fmt(cand["score"]), _fmt(cand["p_value"], 2),
            f"{_fmt(cand['refit_strength'])} +- {_fmt(cand['refit_strength_std'], 2)}"
            if refitted else "",
            _fmt(cand.get("refit_shape"), 3) if cand.get("refit_shape") else "",
            _fmt(cand.get("refit_heldout_rmse")) if refitted else "",
            ("yes" if cand.get("qualifies") else "no") if refitted else ""))
    blocks.append(Section("Candidates", [
        "Score test at zero strength from the base fit (module "
        "`diffwear.calibrate.scores`; an effect with a shape is scored over its "
        "prior and its p-value corrected for that); every candidate with a positive score "
        "refitted with its shape.  A candidate qualifies with a likelihood-ratio drop above "
        f"the chi-square critical value at p = 0.001 ({LR_CRITICAL[1]} for a strength, "
        f"{LR_CRITICAL[2]} with a shape the data determine), what is reported (the "
        f"strength, or the extra worn volume when the shape is not determined) >= "
        f"{STRENGTH_SIGMAS:g} sigma from zero on the allowed side, and a lower held-out "
        "chi2; the penalised criterion (BIC: ln n per determined number) ranks them, "
        "forward selection adds one at a time (module `diffwear.calibrate.identify`), "
        f"and the result must leave noise-sized residuals (chi2 <= dof + {GOF_SIGMAS} "
        "sqrt(2 dof)).",
        Bullets([_stage_line(k, st) for k, st in enumerate(summary.get("stages", []))]),
        Table(("effect", "score", "p", "refit strength", "refit shape", "held-out RMSE",
               "qualifies"), candidates),
        "Library: " + "; ".join(f"`{e.name}`: {e.description}"
                                + (f" ({e.source})" if e.source else "") for e in EFFECTS)]))
    if summary["suspects"]:
        blocks.append(Section("Mechanism suspects", [
            "No wear effect explains the data, so the rig parameters the dataset neither "
            "fits nor excludes (`suspect = false`) were scored the same way (derivative "
            "in the logarithm of the parameter); when the residual is unexplained the "
            "best is refitted and named, if its score passes p = 0.001 corrected for the "
            "number of suspects.",
            Table(("parameter", "score", "p", "stated", "first-step factor"),
                  [(sp["name"], _fmt(sp["score"]), _fmt(sp["p_value"], 2), _fmt(sp["value"]),
                    _fmt(sp["factor"], 3)) for sp in summary["suspects"][:6]])]))
    limits = summary.get("detection_limits") or {}
    if limits:
        blocks.append(Section("Detection limits", [
            "The smallest strength of each effect not named that these data would have "
            f"detected ({STRENGTH_SIGMAS:g} sigma from zero at the final model, at the shape "
            "where the data are most sensitive to it): \"none\" reads \"none above these\".",
            Table(("effect", "detection limit (strength)", "at shape"),
                  [(name, _fmt(v["strength"], 3), _fmt(v["shape"], 3) if v["shape"] else "")
                   for name, v in limits.items()])]))
    check = summary.get("model_check")
    if check:
        blocks.append(Section("Check on the dynamic model", [
            f"The final fit evaluated, not refitted, on the {check['description']}:",
            Table(("", "fitted model", "dynamic model"), [
                (f"chi2, {check['n_fit']} fit points", _fmt(check["chi2_fit_model"]),
                 _fmt(check["chi2_fit"])),
                (f"chi2, {check['n_holdout']} held-out points",
                 _fmt(check["chi2_holdout_model"]), _fmt(check["chi2_holdout"]))]),
            *([] if check.get("carries_over", True) else [
                f"**Warning:** the fit does not carry over to the dynamic model (chi2 "
                f"{_fmt(check['chi2_fit'])} against {_fmt(check['chi2_fit_model'])}): the "
                "quasi-static model's own error may have chosen the effects; refit with "
                "`--model dynamic` before trusting them."])]))
    structure = []
    for key, value in residual_structure(c).items():
        if isinstance(value, dict):
            value = ", ".join(f"{k}: {_fmt(v, 3)}" for k, v in value.items())
        elif isinstance(value, list):
            value = ", ".join(_fmt(v, 3) for v in value)
        structure.append(f"{key.replace('_', ' ')}: {value}")
    blocks += [
        Section("Residual structure (base fit)", [Bullets(summary["residual_words"]),
                                                  Bullets(structure)]),
        Section("Error per series", [Table(
            ("series", "RMS before [sigma]", "RMS after [sigma]"),
            [(name, _fmt(before, 3), _fmt(after, 3))
             for name, (before, after) in summary["series_rms"].items()])]),
        Section("Plots", [*(Figure(f) for f in files), f"Wall time {c.wall_time_s:.0f} s."]),
    ]
    return Report(f"Calibration: {d.name}", blocks)


def _shape_text(entry: dict) -> str:
    shape = next(e.shape for e in EFFECTS if e.name == entry["name"])
    assert shape is not None  # called for effects with a fitted shape only
    lo, hi = entry["shape_interval"] or (math.nan, math.nan)
    return (f"{shape.name.replace('_', ' ')} {_fmt(entry['shape'], 3)} {shape.unit} "
            f"(1 sigma: {_fmt(lo, 3)}..{_fmt(hi, 3)})")


def _effect_text(entry: dict) -> str:
    if "identified_form" in entry:
        return entry["identified_form"]["sentence"]
    text = (f"**{entry['name']}**, strength {_fmt(entry['strength'])} +- "
            f"{_fmt(entry['strength_std'], 2)} (1 sigma)")
    if entry.get("shape") is not None:
        text += f", {_shape_text(entry)}"
    return text


def _effect_lines(summary: dict) -> list[str]:
    """The named effects (or the ambiguity) in words."""
    effects = summary["effects_identified"]
    lines = [f"effect identified: **{summary['effect_identified']}**"]
    for e in effects:
        if e.get("ambiguous"):
            lines.append(f"**{e['name']}**: these data cannot tell them apart; "
                         + "; ".join(f"{a['name']}: "
                                     + ", ".join(_effect_text(x) for x in a["effects"])
                                     for a in e["alternatives"])
                         + (f"; {e['separating_measurement']['sentence']}"
                            if e.get("separating_measurement") else ""))
        else:
            lines.append(_effect_text(e))
    for e in summary.get("effects_partial", []):
        lines.append(f"partial candidate (leaves the residual above the noise): "
                     f"{_effect_text(e)}")
    return lines


def _discrepancy_lines(summary: dict) -> list[str]:
    d = summary.get("discrepancy")
    if not d:
        return []
    if d.get("variable") is None:
        return [f"discrepancy: {d['shape']}"]
    return [f"learned discrepancy of k over **{d['variable'].replace('_', ' ')}**: {d['shape']}"
            f"; held-out RMSE {_fmt(d['heldout_rmse_before'], 3)} -> "
            f"{_fmt(d['heldout_rmse_after'], 3)} sigma (`discrepancy.png`)"]


def _suspect_verdict(s: dict) -> str:
    if "explains" not in s:
        return ""
    return (f"; refitted, {s['name']} = {_fmt(s['refit_value'])} +- {_fmt(s['refit_std'], 2)} "
            + ("explains the data (residuals at the noise)" if s["explains"] else
               f"leaves chi2 {s['refit_chi2_fit']:.1f}: part of the residual only"))


def run(data: Dataset, out: OutputDir, *, settings: ModelSettings = ModelSettings(),
        top: int = 3, check: bool = True, discrepancy=VARIABLES, log=print) -> dict:
    """The loop on a loaded dataset (`load_dataset`: bad input is found before
    ``out`` exists), writing the outputs listed in the module notes."""
    c = calibrate(data, settings, top=top, check=check, discrepancy=discrepancy, log=log)
    summary = c.summary()
    final = c.final or c.base
    summary["series_rms"] = series_rms(c, final)
    summary["residual_words"] = describe_residuals(c, residual_structure(c))
    summary["frame_warnings"] = frame_warnings(c)
    for w in summary["frame_warnings"]:
        log(f"warning: {w['message']}")
    files = _plots(out, c)
    p = c.problem
    names = [s.name for s in data.series]
    out.csv("residuals.csv", {
        "series": p.series_of_point, "x": np.concatenate([s.x for s in data.series]),
        "data": p.y, "base_model": c.base.prediction, "final_model": final.prediction,
        "base_residual": c.base.residual, "final_residual": final.residual,
        "held_out": p.holdout.astype(int)})
    summary["series"] = names
    summary["plots"] = files
    out.text("report.md", render(_report(c, summary, files)))
    out.json("summary.json", summary)
    log(f"wrote {out.path}")
    return summary
