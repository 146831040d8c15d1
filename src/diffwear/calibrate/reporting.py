"""What a calibration's ``report.md`` states: its blocks (`diffwear.report`),
built from the `Calibration` and its summary.  The numbers stay numbers
(`Significant`, `PlusMinus`) until the report is rendered.
"""

from __future__ import annotations

import math

from ..report import Block, Bullets, PlusMinus, Section, Significant, Table, Text
from . import learned
from .effects import LIBRARY, Library
from .identify import AMBIGUITY, GOF_SIGMAS, LR_CRITICAL, STRENGTH_SIGMAS, Calibration


def report_blocks(c: Calibration, summary: dict, structure: dict) -> list[Block]:
    """Every block of the report but its figures (`outputs.write` adds them)."""
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
    blocks.append(_answer_section(c, summary, lib))
    blocks.append(_error_section(summary))
    blocks.append(_parameter_section(c, summary))
    blocks += _life_blocks(summary)
    blocks.append(_candidate_section(summary, lib))
    if summary["suspects"]:
        blocks.append(_suspect_section(summary))
    limits = summary.get("detection_limits") or {}
    if limits:
        blocks.append(Section("Detection limits", [
            "The smallest strength of each effect not named that these data would have "
            f"detected ({STRENGTH_SIGMAS:g} sigma from zero at the final model, at the shape "
            "where the data are most sensitive to it): \"none\" reads \"none above these\".",
            Table(("effect", "detection limit (strength)", "at shape"),
                  [(name, Significant(v["strength"], 3),
                    _limit_shape(name, v["shape"], lib) if v["shape"] else "")
                   for name, v in limits.items()])]))
    mc = summary.get("model_check")
    if mc:
        blocks.append(_model_check_section(mc))
    lines = []
    for key, value in structure.items():
        if isinstance(value, dict):
            value = Text(_joined([Text((f"{k}: ", Significant(v, 3))) for k, v in value.items()],
                                 ", "))
        elif isinstance(value, list):
            value = Text(_joined([Significant(v, 3) for v in value], ", "))
        elif isinstance(value, float):
            value = Significant(value, 3)
        lines.append(Text((f"{key.replace('_', ' ')}: ", value)))
    blocks += [
        Section("Residual structure (base fit)", [Bullets(summary["residual_words"]),
                                                  Bullets(lines)]),
        Section("Error per series", [Table(
            ("series", "RMS before [sigma]", "RMS after [sigma]"),
            [(name, Significant(before, 3), Significant(after, 3))
             for name, (before, after) in summary["series_rms"].items()])]),
    ]
    return blocks


def _joined(parts: list, sep: str) -> tuple:
    """``parts`` with ``sep`` between each two (a `Text`'s ``str.join``)."""
    out: list = []
    for k, p in enumerate(parts):
        out += [sep, p] if k else [p]
    return tuple(out)


def _answer_section(c: Calibration, summary: dict, lib: Library) -> Section:
    gof = c.gof
    check = summary["selection"]["prediction_check"]
    why = [Text(("the fit points' chi2 ", Significant(gof["chi2"], 5),
                 f" on {gof['dof']} degrees of freedom "
                 f"({'within' if gof['consistent_with_noise'] else '**above**'} the noise's ",
                 Significant(gof["limit"], 5), ")"))]
    if check is not None:
        why.append(Text((f"{'it predicts' if check['predicts'] else 'it **does not predict**'}"
                         f" the inspection at {check['cycles']:,.0f} cycles from the earlier "
                         "fit points (Q ", Significant(check["statistic"], 4),
                         f" on {check['points']} points, limit ",
                         Significant(check["limit"], 4), ")")))
    verdict = ("the data are explained: " if not summary["residual_unexplained"] else
               "**the residual is unexplained** by these causes: ")
    return Section("Answer", [
        Bullets([*_effect_lines(summary, lib), *_discrepancy_lines(summary, lib),
                 Text((verdict, *_joined(why, "; ")))]),
        Bullets(_suspect_lines(summary)),
        f"How it was chosen: {summary['selection']['rule']}.",
    ])


def _candidate_section(summary: dict, lib: Library) -> Section:
    candidates = []
    for cand in summary["candidates"]:
        refitted = "refit_chi2_fit" in cand
        candidates.append((
            learned.label(cand["name"]), Significant(cand["score"], 3),
            Significant(cand["p_value"], 2),
            PlusMinus(cand["refit_strength"], cand["refit_strength_std"])
            if "refit_strength" in cand else "",
            Significant(cand.get("refit_shape"), 3) if cand.get("refit_shape") else "",
            Significant(cand["refit_chi2_fit"], 5) if refitted else "",
            ("yes" if cand.get("qualifies") else "no") if refitted else ""))
    return Section("Candidates", [
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
        "and predict the fit window's last inspection.  Models within "
        f"{AMBIGUITY:g} of the best criterion, and two discrepancies over different variables "
        f"whose chi2 + prior lie within {AMBIGUITY:g}, are an open answer.",
        Bullets([_stage_line(k, st) for k, st in enumerate(summary.get("stages", []))]),
        Table(("candidate", "score", "p", "refit strength", "refit shape", "refit chi2",
               "qualifies"), candidates),
        "Library: " + "; ".join(f"`{e.name}`: {e.description}"
                                + (f" ({e.source})" if e.source else "")
                                for e in lib.effects)
        + "".join(f"; not a candidate here: `{r['name']}` ({r['reason']})"
                  for r in summary.get("effects_refused", []))])


def _suspect_section(summary: dict) -> Section:
    return Section("Mechanism suspects", [
        "No cause in the library explains the data, so the rig parameters the dataset "
        "neither fits nor excludes (`suspect = false`) were scored the same way "
        "(derivative in the logarithm of the parameter); when the residual is "
        "unexplained the best is refitted and named, if its score passes p = 0.001 "
        "corrected for the number of suspects and its refitted value stays within the "
        "parameter's plausible range.",
        Table(("parameter", "score", "p", "stated [SI]", "factor asked for"),
              [(sp["name"], Significant(sp["score"], 3), Significant(sp["p_value"], 2),
                Significant(sp["value"]), _factor_words(sp))
               for sp in summary["suspects"][:6]]),
        _suspects_verdict(summary)])


def _model_check_section(mc: dict) -> Section:
    return Section("Check on the dynamic model", [
        f"The final fit evaluated, not refitted, on the {mc['description']}:",
        Table(("", "fitted model", "dynamic model"), [
            (f"chi2, {mc['n_fit']} fit points", Significant(mc["chi2_fit_model"], 5),
             Significant(mc["chi2_fit"], 5)),
            (f"chi2, {mc['n_holdout']} held-out points",
             Significant(mc["chi2_holdout_model"], 5), Significant(mc["chi2_holdout"], 5))]),
        *([] if mc.get("carries_over", True) else [Text((
            "**Warning:** the fit does not carry over to the dynamic model (chi2 ",
            Significant(mc["chi2_fit"], 5), " against ", Significant(mc["chi2_fit_model"], 5),
            "): the quasi-static model's own error may have chosen the effects; refit with "
            "`--model dynamic` before trusting them."))])])


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


def _param_text(name: str, value: float, std: float, data) -> Text:
    """A fitted number with its 1-sigma in the dataset's unit."""
    scale = float(data.in_own_unit(name, 1.0))
    unit = data.unit_of(name)
    return Text((PlusMinus(value * scale, std * scale), f" {unit}" if unit else ""))


def _factor_words(sp: dict) -> Text:
    """The factor a suspect's score (or refit) asks for, or that it lies
    beyond the parameter's plausible range."""
    bounds = sp.get("plausible_range")
    if bounds and not bounds[0] <= sp["factor"] <= bounds[1]:
        return Text(("beyond ", Significant(bounds[0], 2), "x-", Significant(bounds[1], 2),
                     "x"))
    return Text((Significant(sp["factor"], 3), "x"))


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


def _limit_shape(effect: str, value: float, library: Library = LIBRARY) -> Text:
    shape = library.effect(effect).shape
    return Text((Significant(value, 3), f" {shape.unit}" if shape else ""))


def _error_section(summary: dict) -> Section:
    """The error before and after on the held-out points, which the choice did
    not see, and the predictive bands' coverage."""
    rows = [("held-out RMSE [sigma]", Significant(summary["heldout_rmse_before"], 3),
             Significant(summary["heldout_rmse_after"], 3)),
            ("fit RMSE [sigma]", Significant(summary["fit_rmse_before"], 3),
             Significant(summary["fit_rmse_after"], 3))]
    text = ("The held-out measurements were read once, after the choice: the error on "
            "them is the error on data the answer did not see.")
    models = summary.get("coverage_models")
    cov = summary.get("heldout_coverage")
    if cov is not None and cov == cov:
        whose = ("The final model's 90 % predictive band (model and noise)" if not models else
                 "The 90 % predictive band (model and noise) over both explanations, pooled "
                 f"by their weights ({_weights_words(models)}),")
        text += (f"  {whose} holds {100 * cov:.0f} % of the held-out points"
                 f" ({100 * summary['fit_coverage']:.0f} % of the fit points).")
    # an open answer's errors are its first explanation's; its band is pooled
    after = f"first explanation: {models[0]['name']}" if models else "final model"
    return Section("Before and after, on data the choice did not see",
                   [text, Table(("", "base model", after), rows)])


def _weights_words(models: list[dict]) -> str:
    """The models an open answer pools, with their weights ("A 77 %, B 23 %")."""
    return ", ".join(f"{m['name']} {100 * m['weight']:.0f} %" for m in models)


def _parameter_section(c: Calibration, summary: dict) -> Section:
    d = c.dataset
    final = c.final or c.base
    post = summary.get("posterior")
    numbers = (post or {}).get("numbers", {})
    rows: list[tuple] = []
    for n in d.fit_names:
        q = numbers.get(n)
        scale = float(d.in_own_unit(n, 1.0))
        rows.append((f"{n} [{d.unit_of(n) or '-'}]",
                     PlusMinus(c.base.params[n] * scale, c.base.params_std[n] * scale),
                     PlusMinus(final.params[n] * scale, final.params_std[n] * scale),
                     "" if q is None else _interval(q["q05"] * scale, q["q95"] * scale),
                     "" if q is None or "r_hat" not in q else Significant(q["r_hat"], 4),
                     "" if q is None else f"{q['ess']:.0f}"))
    for n, q in numbers.items():
        if n in d.fit_names or n.startswith("delta_"):
            continue
        rows.append((n.replace("_", " "), "", PlusMinus(q["mean"], q["std"]),
                     _interval(q["q05"], q["q95"]),
                     Significant(q["r_hat"], 4) if "r_hat" in q else "", f"{q['ess']:.0f}"))
    blocks: list[Block] = [Table(("number", "base fit", "final fit (1 sigma)",
                                  "posterior 5-95 %", "R-hat", "ESS"), rows)]
    disc = summary.get("discrepancy") or {}
    k = disc.get("k_with")
    if k and disc.get("k_without"):
        name = next((n for n in d.fit_names if n == "k" or n.endswith("wear.coefficient")), "k")
        without = disc["k_without"]
        blocks.append(Text((
            "The wear coefficient with the learned discrepancy (the discrepancy orthogonal to "
            "it over the data) is ", _param_text(name, k["value"], k["std"], d), "; without "
            "it, ", _param_text(name, without["value"], without["std"], d), ".")))
    if post:
        blocks.append(Text(("Posterior: ", _posterior_how(post), ".")))
    return Section("Parameters", blocks)


def _interval(lo: float, hi: float) -> Text:
    return Text((Significant(lo, 4), " .. ", Significant(hi, 4)))


def _posterior_how(post: dict) -> Text | str:
    """How the posterior was sampled, and the check it passed or failed."""
    diag = post["diagnostics"]
    if post["method"] == "nuts":
        how = Text((f"NUTS, {post['chains']} chains, {diag['draws_sampled']} draws; largest "
                    "R-hat ", Significant(diag["max_r_hat"], 4), ", smallest bulk ESS "
                    f"{diag['min_ess']:.0f}, {diag['divergences']} divergent transitions"))
        target = diag.get("r_hat_target")
        if target is None:
            return how
        if diag.get("converged", True):
            return Text((how, f" (the chains ran until every R-hat was at most {target}: "
                              f"{diag['draws_per_chain']} draws a chain)"))
        return Text((how, f"; **R-hat stayed above {target}** after "
                          f"{diag['draws_per_chain']} draws a chain: the chains disagree, "
                          "and the bands below rest on an unconverged sample"))
    if "pareto_k" in diag:
        k_text = ("n/a" if diag["pareto_k"] is None or not math.isfinite(diag["pareto_k"])
                  else Significant(diag["pareto_k"], 2))
        if diag["gaussian_adequate"]:
            verdict = Text(("Pareto k ", k_text, f": near enough; effective draws "
                                                 f"{diag['ess']:.0f}"))
        else:
            verdict = Text(("Pareto k ", k_text, ": **not** confirmed, so the bands below are "
                            "the Gaussian's, unchecked (its draws unweighted); a checked "
                            "posterior needs `--posterior nuts`"))
        return Text(("the Laplace (Gaussian) approximation at the fit, scaled along each "
                     "principal direction to the exact posterior's fall-off, "
                     f"{post['draws']} draws evaluated on the exact model and weighted by "
                     "Pareto-smoothed importance ratios; ", verdict))
    return ("the Laplace (Gaussian) approximation at the fit, linearised (the dynamic "
            "model is too costly to evaluate at every draw)")


def _life_blocks(summary: dict) -> list[Block]:
    life = summary.get("life")
    if not life:
        return []
    beyond = life["beyond_run"]
    band = (f"{life['q05']:,.0f} to {life['q95']:,.0f}" +
            (f" (or beyond: {100 * beyond:.0f} % of the draws do not reach it by "
             f"{life['run_to_cycles']:,.0f})" if beyond > 0 else ""))
    depth = life["depth_at_horizon"]
    lines: list = [
        Text(("cycles until the maximum wear depth reaches ", Significant(life["limit_mm"], 4),
              f" mm: **{life['median']:,.0f}** (90 % band {band})")),
        Text((f"maximum wear depth at {life['horizon_cycles']:,.0f} cycles: **",
              Significant(depth["median"], 3), " mm** (90 % band ",
              Significant(depth["q05"], 3), " to ", Significant(depth["q95"], 3), " mm)"))]
    nxt = summary.get("next_measurement")
    if nxt:
        lines.append(f"the next measurement: {nxt['sentence']}")
    models = life.get("models")
    rule = (models or [{}])[0].get("weighted_by", "exp(-criterion / 2)")
    where = ("Under the chosen model (its effects and discrepancy included), over the "
             "posterior's draws." if not models else
             "Over both explanations the data leave open, each on its own posterior's draws, "
             f"pooled by the models' weights {rule}: " + _weights_words(models) + ".")
    return [Section("Life and the next measurement", [where, Bullets(lines)])]


def _shape_text(entry: dict, library: Library = LIBRARY) -> Text:
    shape = library.effect(entry["name"]).shape
    assert shape is not None  # called for effects with a fitted shape only
    lo, hi = entry["shape_interval"] or (math.nan, math.nan)
    return Text((f"{shape.name.replace('_', ' ')} ", Significant(entry["shape"], 3),
                 f" {shape.unit} (1 sigma: ", Significant(lo, 3), " to ", Significant(hi, 3),
                 ")"))


def _effect_text(entry: dict, library: Library = LIBRARY) -> Text | str:
    if "identified_form" in entry:
        return entry["identified_form"]["sentence"]
    parts: tuple = (f"**{entry['name']}**, strength ",
                    PlusMinus(entry["strength"], entry["strength_std"]), " (1 sigma)")
    if entry.get("shape") is not None:
        parts += (", ", _shape_text(entry, library))
    return Text(parts)


def _effect_lines(summary: dict, library: Library = LIBRARY) -> list:
    """The named effects (or the ambiguity) in words."""
    effects = summary["effects_identified"]
    lines: list = [f"effect identified: **{summary['effect_identified']}**"]
    for e in effects:
        if e.get("ambiguous"):
            beside = f" beside {' + '.join(e['beside'])}" if e.get("beside") else ""
            each = [Text((f"{a['name']}: ", *_joined([
                *(_effect_text(x, library) for x in a["effects"]),
                *([f"k over {disc_words(a['discrepancy'], library)} {a['discrepancy_shape']}"]
                  if a.get("discrepancy_shape") else [])], ", ")))
                for a in e["alternatives"]]
            lines.append(Text((f"**{e['name']}**{beside}: these data cannot tell them apart; ",
                               *_joined(each, "; "))))
        else:
            lines.append(_effect_text(e, library))
    for e in summary.get("effects_partial", []):
        lines.append(Text(("partial candidate (leaves the residual unexplained): ",
                           _effect_text(e, library))))
    return lines


def disc_words(variable: str, library: Library = LIBRARY) -> str:
    return library.variable(variable).words


def _discrepancy_lines(summary: dict, library: Library = LIBRARY) -> list[str]:
    d = summary.get("discrepancy")
    if not d:
        return []
    if d.get("variable") is None:
        return [f"learned discrepancy: {d['shape']}"]
    return [f"learned discrepancy of k over **{disc_words(d['variable'], library)}**: {d['shape']}"
            " (`discrepancy.png`)"]


def _suspect_verdict(s: dict) -> Text | str:
    if "explains" not in s:
        return ""
    return Text(("; refitted, ", s["name"], " = ", PlusMinus(s["refit_value"], s["refit_std"]),
                 " SI ", "explains the data (residuals at the noise)" if s["explains"] else
                 Text(("leaves chi2 ", Significant(s["refit_chi2_fit"], 5),
                       ": part of the residual only"))))


def _suspect_lines(summary: dict) -> list:
    if not summary["suspects"]:
        return []
    lead = summary["suspects"][0]
    if summary.get("suspect"):
        return [Text((f"mechanism suspect: **{summary['suspect']}**", _suspect_verdict(lead)))]
    if "implausible" in lead:
        return [f"no mechanism suspect: {lead['implausible']}"]
    return []
