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
from functools import partial

import numpy as np  # noqa: E402

from ..calibrate import learned
from ..calibrate.dataset import Dataset  # noqa: E402
from ..calibrate.effects import LIBRARY, Library  # noqa: E402
from ..calibrate.fit import ModelSettings  # noqa: E402
from ..calibrate.forecast import DEFAULT_OUTLOOK
from ..calibrate.frame_check import frame_warnings  # noqa: E402
from ..calibrate.identify import (  # noqa: E402
    AMBIGUITY,
    GOF_SIGMAS,
    LR_CRITICAL,
    STRENGTH_SIGMAS,
    Calibration,
    calibrate,
)
from ..calibrate.residual_structure import locate_residual, series_rms
from ..calibrate.residual_words import describe_residuals  # noqa: E402
from ..io import OutputDir, Outputs  # noqa: E402
from ..plots import calibration as plots_calibration
from ..report import (
    Block,
    Bullets,
    Figure,
    Report,
    Section,
    Table,
    plus_minus,
    render,
    significant,
)

DESCRIPTION = "calibrate the rig model on measured wear data and identify a missing effect"
# the figures' axes: y scale and unit, x label and scale (angles, SI rad, drawn in deg)
UNIT = {"profile": (1e6, "um", "bushing angle [deg]", 180 / math.pi),
        "max_depth": (1e3, "mm", "cycles", 1.0), "volume": (1e9, "mm^3", "cycles", 1.0),
        "force": (1.0, "N", "crank angle [deg]", 180 / math.pi)}


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
    title_p = ("posterior of the final model (" + _posterior_words(c.posterior) + ")"
               if c.posterior is not None else "")
    members = _members_of(final)
    covered = _covered(final.discrepancy, c) if final.discrepancy is not None else None
    # the fits' series, the residuals and the force residual's spectrum
    band = None if c.posterior is None else c.predictive_band()
    fits = []
    for k, s in enumerate(c.dataset.series):
        m = which == k
        scale, unit, xlabel, xscale = UNIT[s.kind]
        fits.append(plots_calibration.SeriesFit(
            name=s.name, kind=s.kind, unit=unit, xlabel=xlabel, scale=scale, x=s.x * xscale,
            y=s.y, sigma=s.sigma, holdout=s.holdout, base=c.base.prediction[m],
            chosen=None if final is c.base else final.prediction[m],
            chosen_label=chosen_label, cycles=s.cycles,
            band=None if band is None else (band[0][m], band[1][m])))
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
        axis, title_d = lib.variable(d).axis, f"learned discrepancy of k over {disc_words(d, lib)}"
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


def disc_words(variable: str, library: Library = LIBRARY) -> str:
    return library.variable(variable).words


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


def _stage_line(k: int, st: dict) -> str:
    """One forward-selection stage in words."""
    qualified = [learned.label(e) for e, c in st["candidates"].items() if c["qualifies"]]
    text = (f"stage {k + 1}: {len(st['candidates'])} refitted, qualifying: "
            f"{', '.join(qualified) or 'none'}")
    if st.get("added"):
        text += f"; added **{learned.label(st['added'])}**"
    if st.get("branches"):
        text += (f" ({', '.join(learned.label(e) for e in st['branches'])} as close by the "
                 "criterion: grown on a branch of its own)")
    if st.get("dropped"):
        text += (f"; dropped {', '.join(learned.label(e) for e in st['dropped'])} (no longer "
                 "qualifying beside the rest)")
    if st.get("ambiguous"):
        text += f"; **{' or '.join(st['ambiguous'])}**: too close to tell apart"
    if st.get("failed"):
        text += "; refit failed: " + "; ".join(f"{e} ({why})" for e, why in st["failed"].items())
    return text


def _final_label(f) -> str:
    parts = [*f.effects] + ([f"discrepancy in {f.discrepancy}"] if f.discrepancy else [])
    return "with " + " + ".join(parts) if parts else "base model"


def _param_text(name: str, value: float, std: float, data) -> str:
    """A fitted number with its 1-sigma in the dataset's unit."""
    scale = data.in_own_unit(name, 1.0)
    unit = data.unit_of(name)
    return plus_minus(value * float(scale), std * float(scale)) + (f" {unit}" if unit else "")


def _report(c: Calibration, summary: dict, files: list[str], structure: dict) -> Report:
    d = c.dataset
    lib = c.problem.library
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
    gof = c.gof
    check = summary["selection"]["prediction_check"]
    why = [f"the fit points' chi2 {significant(gof['chi2'], 5)} on {gof['dof']} degrees of "
           f"freedom ({'within' if gof['consistent_with_noise'] else '**above**'} the "
           f"noise's {significant(gof['limit'], 5)})"]
    if check is not None:
        why.append(f"{'it predicts' if check['predicts'] else 'it **does not predict**'} the "
                   f"inspection at {check['cycles']:,.0f} cycles from the earlier fit points "
                   f"(Q {significant(check['statistic'], 4)} on {check['points']} points, "
                   f"limit {significant(check['limit'], 4)})")
    blocks.append(Section("Answer", [
        Bullets([*_effect_lines(summary, lib), *_discrepancy_lines(summary, lib),
                 ("the data are explained: " if not summary["residual_unexplained"] else
                  "**the residual is unexplained** by these causes: ") + "; ".join(why)]),
        Bullets(_suspect_lines(summary)),
        f"How it was chosen: {summary['selection']['rule']}.",
    ]))
    blocks.append(_error_section(summary))
    blocks.append(_parameter_section(c, summary, final))
    blocks += _life_blocks(summary)
    candidates = []
    for cand in summary["candidates"]:
        refitted = "refit_chi2_fit" in cand
        candidates.append((
            learned.label(cand["name"]), significant(cand["score"], 3),
            significant(cand["p_value"], 2),
            plus_minus(cand["refit_strength"], cand["refit_strength_std"])
            if "refit_strength" in cand else "",
            significant(cand.get("refit_shape"), 3) if cand.get("refit_shape") else "",
            significant(cand["refit_chi2_fit"], 5) if refitted else "",
            ("yes" if cand.get("qualifies") else "no") if refitted else ""))
    blocks.append(Section("Candidates", [
        "Every candidate cause is scored at zero strength from the base fit (a score test; "
        "an effect with a shape over its prior, its p-value corrected for that; a learned "
        "discrepancy over all its coefficients at once) and refitted when the score asks "
        "for it.  A library effect qualifies with a chi-square drop above the critical value "
        f"at p = 0.001 ({LR_CRITICAL[1]} for a strength, {LR_CRITICAL[2]} with a shape the "
        f"data determine) and what is reported (the strength, or the extra worn volume when "
        f"the shape is not determined) >= {STRENGTH_SIGMAS:g} sigma from zero; a discrepancy "
        "with a drop above the critical value for its effective number of coefficients.  BIC "
        "(ln n per determined number) ranks them; forward selection adds one at a time; the "
        f"result must leave noise-sized residuals (chi2 <= dof + {GOF_SIGMAS:g} sqrt(2 dof)) "
        "and predict the fit window's last inspection.",
        Bullets([_stage_line(k, st) for k, st in enumerate(summary.get("stages", []))]),
        Table(("candidate", "score", "p", "refit strength", "refit shape", "refit chi2",
               "qualifies"), candidates),
        "Library: " + "; ".join(f"`{e.name}`: {e.description}"
                                + (f" ({e.source})" if e.source else "")
                                for e in lib.effects)
        + "".join(f"; not a candidate here: `{r['name']}` ({r['reason']})"
                  for r in summary.get("effects_refused", []))]))
    if summary["suspects"]:
        blocks.append(Section("Mechanism suspects", [
            "No cause in the library explains the data, so the rig parameters the dataset "
            "neither fits nor excludes (`suspect = false`) were scored the same way "
            "(derivative in the logarithm of the parameter); when the residual is "
            "unexplained the best is refitted and named, if its score passes p = 0.001 "
            "corrected for the number of suspects and its refitted value stays within the "
            "parameter's plausible range.",
            Table(("parameter", "score", "p", "stated [SI]", "factor asked for"),
                  [(sp["name"], significant(sp["score"], 3), significant(sp["p_value"], 2),
                    significant(sp["value"]), _factor_words(sp))
                   for sp in summary["suspects"][:6]]),
            _suspects_verdict(summary)]))
    limits = summary.get("detection_limits") or {}
    if limits:
        blocks.append(Section("Detection limits", [
            "The smallest strength of each effect not named that these data would have "
            f"detected ({STRENGTH_SIGMAS:g} sigma from zero at the final model, at the shape "
            "where the data are most sensitive to it): \"none\" reads \"none above these\".",
            Table(("effect", "detection limit (strength)", "at shape"),
                  [(name, significant(v["strength"], 3),
                    _limit_shape(name, v["shape"], lib) if v["shape"] else "")
                   for name, v in limits.items()])]))
    mc = summary.get("model_check")
    if mc:
        blocks.append(Section("Check on the dynamic model", [
            f"The final fit evaluated, not refitted, on the {mc['description']}:",
            Table(("", "fitted model", "dynamic model"), [
                (f"chi2, {mc['n_fit']} fit points", significant(mc["chi2_fit_model"], 5),
                 significant(mc["chi2_fit"], 5)),
                (f"chi2, {mc['n_holdout']} held-out points",
                 significant(mc["chi2_holdout_model"], 5), significant(mc["chi2_holdout"], 5))]),
            *([] if mc.get("carries_over", True) else [
                f"**Warning:** the fit does not carry over to the dynamic model (chi2 "
                f"{significant(mc['chi2_fit'], 5)} against "
                f"{significant(mc['chi2_fit_model'], 5)}): the quasi-static model's own error "
                "may have chosen the effects; refit with `--model dynamic` before trusting "
                "them."])]))
    lines = []
    for key, value in structure.items():
        if isinstance(value, dict):
            value = ", ".join(f"{k}: {significant(v, 3)}" for k, v in value.items())
        elif isinstance(value, list):
            value = ", ".join(significant(v, 3) for v in value)
        elif isinstance(value, float):
            value = significant(value, 3)
        lines.append(f"{key.replace('_', ' ')}: {value}")
    blocks += [
        Section("Residual structure (base fit)", [Bullets(summary["residual_words"]),
                                                  Bullets(lines)]),
        Section("Error per series", [Table(
            ("series", "RMS before [sigma]", "RMS after [sigma]"),
            [(name, significant(before, 3), significant(after, 3))
             for name, (before, after) in summary["series_rms"].items()])]),
        Section("Plots", [*(Figure(f) for f in files),
                          f"Wall time {c.wall_time_s:.0f} s."]),
    ]
    return Report(f"Calibration: {d.name}", blocks)


def _factor_words(sp: dict) -> str:
    """The factor a suspect's score (or refit) asks for, or that it lies
    beyond the parameter's plausible range."""
    bounds = sp.get("plausible_range")
    if bounds and not bounds[0] <= sp["factor"] <= bounds[1]:
        return f"beyond {significant(bounds[0], 2)}x-{significant(bounds[1], 2)}x"
    return f"{significant(sp['factor'], 3)}x"


def _suspects_verdict(summary: dict) -> str:
    """Why the suspects table names a suspect or none."""
    if summary.get("suspect"):
        return f"Named: {summary['suspect']}."
    lead = summary["suspects"][0]
    if "implausible" in lead:
        return f"None named: {lead['implausible']}."
    if not summary["residual_unexplained"]:
        return ("None named: the chosen model explains the data, so no parameter is asked to "
                "explain a residual (the scores are listed for reference).")
    return ("None named: no score passes p = 0.001 corrected for the number of suspects.")


def _limit_shape(effect: str, value: float, library: Library = LIBRARY) -> str:
    shape = library.effect(effect).shape
    return f"{significant(value, 3)} {shape.unit}" if shape else significant(value, 3)


def _error_section(summary: dict) -> Section:
    """The error before and after on the held-out points, which the choice did
    not see, and the predictive bands' coverage."""
    rows = [("held-out RMSE [sigma]", significant(summary["heldout_rmse_before"], 3),
             significant(summary["heldout_rmse_after"], 3)),
            ("fit RMSE [sigma]", significant(summary["fit_rmse_before"], 3),
             significant(summary["fit_rmse_after"], 3))]
    text = ("The held-out measurements were read once, after the choice: the error on "
            "them is the error on data the answer did not see.")
    cov = summary.get("heldout_coverage")
    if cov is not None and cov == cov:
        whose = ("final model's" if not summary.get("coverage_models") else
                 "two explanations' (pooled by their weights: "
                 + ", ".join(f"{m['name']} {100 * m['weight']:.0f} %"
                             for m in summary["coverage_models"]) + ")")
        text += (f"  The {whose} 90 % predictive band (model and noise) holds "
                 f"{100 * cov:.0f} % of the held-out points"
                 f" ({100 * summary['fit_coverage']:.0f} % of the fit points).")
    return Section("Before and after, on data the choice did not see",
                   [text, Table(("", "base model", "final model"), rows)])


def _parameter_section(c: Calibration, summary: dict, final) -> Section:
    d = c.dataset
    post = summary.get("posterior")
    numbers = (post or {}).get("numbers", {})
    rows = []
    for n in d.fit_names:
        q = numbers.get(n)
        scale = float(d.in_own_unit(n, 1.0))
        rows.append((f"{n} [{d.unit_of(n) or '-'}]",
                     plus_minus(c.base.params[n] * scale, c.base.params_std[n] * scale),
                     plus_minus(final.params[n] * scale, final.params_std[n] * scale),
                     "" if q is None else f"{significant(q['q05'] * scale, 4)} .. "
                                          f"{significant(q['q95'] * scale, 4)}",
                     "" if q is None or "r_hat" not in q else significant(q["r_hat"], 4),
                     "" if q is None else f"{q['ess']:.0f}"))
    for n, q in numbers.items():
        if n in d.fit_names or n.startswith("delta_"):
            continue
        rows.append((n.replace("_", " "), "", plus_minus(q["mean"], q["std"]),
                     f"{significant(q['q05'], 4)} .. {significant(q['q95'], 4)}",
                     significant(q["r_hat"], 4) if "r_hat" in q else "", f"{q['ess']:.0f}"))
    blocks: list[Block] = [Table(("number", "base fit", "final fit (1 sigma)",
                                  "posterior 5-95 %", "R-hat", "ESS"), rows)]
    disc = summary.get("discrepancy") or {}
    k = disc.get("k_with")
    if k and disc.get("k_without"):
        name = next((n for n in d.fit_names if n == "k" or n.endswith("wear.coefficient")), "k")
        without = disc["k_without"]
        blocks.append(
            f"The wear coefficient with the learned discrepancy (the discrepancy "
            f"orthogonal to it over the data) is {_param_text(name, k['value'], k['std'], d)}; "
            f"without it, {_param_text(name, without['value'], without['std'], d)}.")
    if post:
        diag = post["diagnostics"]
        if post["method"] == "nuts":
            how = (f"NUTS, {post['chains']} chains, {diag['draws_sampled']} draws; largest "
                   f"R-hat {significant(diag['max_r_hat'], 4)}, smallest bulk ESS "
                   f"{diag['min_ess']:.0f}, {diag['divergences']} divergent transitions")
        elif "pareto_k" in diag:
            k_text = ("n/a" if diag["pareto_k"] is None or not math.isfinite(diag["pareto_k"])
                      else significant(diag["pareto_k"], 2))
            if diag["gaussian_adequate"]:
                verdict = (f"Pareto k {k_text}: near enough; effective draws "
                           f"{diag['ess']:.0f}")
            else:
                verdict = (f"Pareto k {k_text}: **not** confirmed, so the bands below are the "
                           "Gaussian's, unchecked (its draws unweighted); a checked posterior "
                           "needs `--posterior nuts`")
            how = (f"the Laplace (Gaussian) approximation at the fit, scaled along each "
                   f"principal direction to the exact posterior's fall-off, {post['draws']} "
                   f"draws evaluated on the exact model and weighted by Pareto-smoothed "
                   f"importance ratios; {verdict}")
        else:
            how = ("the Laplace (Gaussian) approximation at the fit, linearised (the dynamic "
                   "model is too costly to evaluate at every draw)")
        blocks.append(f"Posterior: {how}.")
    return Section("Parameters", blocks)


def _posterior_words(post) -> str:
    """How the posterior's draws were made and weighted, for a figure title."""
    if post.method == "nuts":
        return "NUTS"
    if post.diagnostics.get("weights") == "gaussian, unchecked":
        return "Laplace, unchecked: the importance check failed"
    return ("Laplace, importance-weighted" if "pareto_k" in post.diagnostics
            else "Laplace, linearised")


def _life_blocks(summary: dict) -> list[Block]:
    life = summary.get("life")
    if not life:
        return []
    beyond = life["beyond_run"]
    band = (f"{life['q05']:,.0f} to {life['q95']:,.0f}" +
            (f" (or beyond: {100 * beyond:.0f} % of the draws do not reach it by "
             f"{life['run_to_cycles']:,.0f})" if beyond > 0 else ""))
    depth = life["depth_at_horizon"]
    lines = [f"cycles until the maximum wear depth reaches {significant(life['limit_mm'], 4)} "
             f"mm: **{life['median']:,.0f}** (90 % band {band})",
             f"maximum wear depth at {life['horizon_cycles']:,.0f} cycles: "
             f"**{significant(depth['median'], 3)} mm** (90 % band "
             f"{significant(depth['q05'], 3)} to {significant(depth['q95'], 3)} mm)"]
    nxt = summary.get("next_measurement")
    if nxt:
        lines.append(f"the next measurement: {nxt['sentence']}")
    models = life.get("models")
    where = ("Under the chosen model (its effects and discrepancy included), over the "
             "posterior's draws." if not models else
             "Over both explanations the data leave open, each on its own posterior's draws, "
             "pooled by the models' weights exp(-criterion / 2): "
             + ", ".join(f"{m['name']} {100 * m['weight']:.0f} %" for m in models) + ".")
    return [Section("Life and the next measurement", [where, Bullets(lines)])]


def _shape_text(entry: dict, library: Library = LIBRARY) -> str:
    shape = library.effect(entry["name"]).shape
    assert shape is not None  # called for effects with a fitted shape only
    lo, hi = entry["shape_interval"] or (math.nan, math.nan)
    return (f"{shape.name.replace('_', ' ')} {significant(entry['shape'], 3)} {shape.unit} "
            f"(1 sigma: {significant(lo, 3)} to {significant(hi, 3)})")


def _effect_text(entry: dict, library: Library = LIBRARY) -> str:
    if "identified_form" in entry:
        return entry["identified_form"]["sentence"]
    text = (f"**{entry['name']}**, strength "
            f"{plus_minus(entry['strength'], entry['strength_std'])} (1 sigma)")
    if entry.get("shape") is not None:
        text += f", {_shape_text(entry, library)}"
    return text


def _effect_lines(summary: dict, library: Library = LIBRARY) -> list[str]:
    """The named effects (or the ambiguity) in words."""
    effects = summary["effects_identified"]
    lines = [f"effect identified: **{summary['effect_identified']}**"]
    for e in effects:
        if e.get("ambiguous"):
            beside = f" beside {' + '.join(e['beside'])}" if e.get("beside") else ""
            lines.append(f"**{e['name']}**{beside}: these data cannot tell them apart; "
                         + "; ".join(f"{a['name']}: "
                                     + ", ".join(_effect_text(x, library)
                                                 for x in a["effects"])
                                     for a in e["alternatives"]))
        else:
            lines.append(_effect_text(e, library))
    for e in summary.get("effects_partial", []):
        lines.append(f"partial candidate (leaves the residual unexplained): "
                     f"{_effect_text(e, library)}")
    return lines


def _discrepancy_lines(summary: dict, library: Library = LIBRARY) -> list[str]:
    d = summary.get("discrepancy")
    if not d:
        return []
    if d.get("variable") is None:
        return [f"learned discrepancy: {d['shape']}"]
    return [f"learned discrepancy of k over **{disc_words(d['variable'], library)}**: {d['shape']}"
            " (`discrepancy.png`)"]


def _suspect_verdict(s: dict) -> str:
    if "explains" not in s:
        return ""
    return (f"; refitted, {s['name']} = {plus_minus(s['refit_value'], s['refit_std'])} SI "
            + ("explains the data (residuals at the noise)" if s["explains"] else
               f"leaves chi2 {significant(s['refit_chi2_fit'], 5)}: part of the residual "
               "only"))


def _suspect_lines(summary: dict) -> list[str]:
    if not summary["suspects"]:
        return []
    lead = summary["suspects"][0]
    if summary.get("suspect"):
        return [f"mechanism suspect: **{summary['suspect']}**" + _suspect_verdict(lead)]
    if "implausible" in lead:
        return [f"no mechanism suspect: {lead['implausible']}"]
    return []


def run(data: Dataset, out: OutputDir, *, settings: ModelSettings | None = None,
        top: int = 3, check: bool = True, discrepancy=None, outlook=DEFAULT_OUTLOOK,
        log=print) -> dict:
    """The loop on a loaded dataset (`load_dataset`: bad input is found before
    ``out`` exists), writing the outputs listed in the module notes."""
    c = calibrate(data, settings, top=top, check=check, discrepancy=discrepancy,
                  outlook=outlook, log=log)
    summary = c.summary()
    final = c.final or c.base
    summary["series_rms"] = series_rms(c, final)
    structure = locate_residual(c)
    summary["residual_words"] = describe_residuals(c, structure)
    summary["frame_warnings"] = frame_warnings(c)
    for w in summary["frame_warnings"]:
        log(f"warning: {w['message']}")
    # every number first, then every file (`Outputs`)
    files = _figures(c, structure)
    figures = files.names
    p = c.problem
    files.csv("residuals.csv", {
        "series": p.series_of_point, "x": np.concatenate([s.x for s in data.series]),
        "data": p.y, "base_model": c.base.prediction, "final_model": final.prediction,
        "base_residual": c.base.residual, "final_residual": final.residual,
        "held_out": p.holdout.astype(int)})
    summary["series"] = [s.name for s in data.series]
    summary["plots"] = figures
    report = _report(c, summary, figures, structure)
    files.text("report.md", lambda: render(report))
    out.write(files)
    out.json("summary.json", summary)
    log(f"wrote {out.path}")
    return summary
