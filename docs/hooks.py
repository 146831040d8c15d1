"""mkdocs hooks: pages filled from the code and the benchmark records, so that
every figure in them comes from the repository.

* ``CLI_REFERENCE``: the ``--help`` of every ``diffwear`` command;
* ``QUASI_STATIC_TABLE``: ``benchmarks/records/quasi_static.json``;
* ``AGREEMENT_TABLE``: ``benchmarks/records/agreement.json`` (and the
  kinematic-feedback bound, ``feedback.json``);
* ``RESULTS_TABLE``: the stored calibration runs,
  ``design_studies/calibration/results/*/summary.json``, against the truth the
  generator ``design_studies/calibration/make_datasets.py`` recorded;
* ``HEADLINE_TABLE``: the README's headline results, its links made relative
  to the docs;
* the figures under ``figures/``: drawn by ``docs/figures.py`` from the stored
  runs and records when the site builds.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RECORDS = ROOT / "benchmarks" / "records"


def _cli_reference() -> str:
    sys.path.insert(0, str(ROOT / "src"))
    from diffwear.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    parts = ["Every command exits 0 on success, 2 on bad input (the message names the "
             "file, key or value) and 3 on a solver failure (results so far are written).",
             "", "```text", parser.format_help().rstrip(), "```"]
    for name, p in sub.choices.items():
        parts += ["", f"## diffwear {name}", "", "```text", p.format_help().rstrip(), "```"]
    return "\n".join(parts)


def _quasi_static_table() -> str:
    cases = json.loads((RECORDS / "quasi_static.json").read_text())["cases"]
    rig = cases["rig-21400 quasi-static"]
    grad = cases["quasi-static life gradient (4 parameters)"]
    sweep = cases["quasi-static life sweep, 1000 designs"]
    dyn = json.loads((RECORDS / "full_2d4674c_quiet.json").read_text())["cases"]
    rig_dyn = dyn["rig-21400 (constant A)"]
    grad_dyn = dyn["rig-21400 gradient (4 parameters)"]
    rows = [
        "| task | quasi-static | dynamic | goal |", "|---|---:|---:|---|",
        f"| `rig-21400`, 21,400 cycles, after compile | {rig['run_s']:.2f} s "
        f"(compile {rig['compile_s']:.1f} s) | {rig_dyn['run_s']:.1f} s | <= 0.5 s |",
        f"| Ch. 8 lives: Jacobian w.r.t. 4 parameters / forward run | "
        f"{grad['ratio_gradient_to_forward']:.2f}x (forward {grad['forward_s']:.2f} s) | "
        f"8x (central differences; the rig's autodiff gradient "
        f"{grad_dyn['ratio_gradient_to_forward']:.1f}x) | <= 3x |",
        f"| lives of {sweep['designs']:,} designs over the Table 8-3 box (vmap) | "
        f"{sweep['run_s']:.1f} s ({1e3 * sweep['s_per_design']:.0f} ms each) | "
        + (f"~{sweep['dynamic_estimate_s'] / 60:.0f} min ({sweep['dynamic_one_life_s']:.1f} s "
           "per life)" if "dynamic_estimate_s" in sweep else "") + " | <= 20 s |",
    ]
    design = cases.get("ch8-optimisation")
    design_dyn = dyn.get("ch8-optimisation")
    if design and design_dyn:
        rows.append(f"| Ch. 8 equal-life design, whole run incl. compiles | "
                    f"{design['run_s']:.0f} s ({design['dynamic_runs']} dynamic runs, gap "
                    f"{design['rel_gap']:.1e}) | {design_dyn['run_s']:.0f} s (dynamic model "
                    f"alone, {design_dyn.get('model_evaluations', 82)} runs) | < 60 s |")
    calibration = RECORDS / "calibration.json"
    if calibration.exists():
        cal = json.loads(calibration.read_text())["cases"]["calibration loop"]
        rows.append(f"| `diffwear calibrate`, 21,400-cycle campaign ({cal['dataset']}), whole "
                    f"loop incl. compiles and the dynamic check | {cal['run_s']:.0f} s "
                    f"(check {cal['dynamic_check_s']:.0f} s, beside the refits) | "
                    "`--model dynamic`: every fit step a forward-mode pass through 86 dynamic "
                    "cycles | "
                    "<= 120 s |")
    error = sweep.get("sweep_settings_max_rel_error_32_designs",
                      sweep["sweep_settings_rel_error"])
    note = (f"\nThe sweep runs at the sweep settings (`diffwear.design.SWEEP_MODEL`): lives "
            f"within {100 * error:.2f} % of the default settings'.  Machine: "
            + json.loads((RECORDS / "quasi_static.json").read_text())["meta"]["device"]
            + ", 2 CPUs.")
    return "\n".join(rows) + "\n" + note


def _agreement_table() -> str:
    data = json.loads((RECORDS / "agreement.json").read_text())
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from agreement import markdown  # the script that wrote the record renders it

    ch8 = data["ch8"]
    coarse, fine = ch8["steps"]
    text = markdown(data)
    text += (f"\n\nCh. 8 dynamic lives: extrapolated from {coarse} and {fine} wear steps "
             f"(Richardson, first order: 2 L{fine} - L{coarse}); the quasi-static lives at "
             f"the default settings ({ch8['quasi_static_settings']['steps']} steps, "
             f"{ch8['quasi_static_settings']['samples']} load samples).")
    feedback = RECORDS / "feedback.json"
    if feedback.exists():
        fb = json.loads(feedback.read_text())
        ch8_fb = max(abs(v) for k, vals in fb["ch8"].items() if k != "base" for v in vals)
        rig_fb = max(abs(v) for k, vals in fb["rig"].items() if not k.startswith("base")
                     for v in vals)
        text += ("\n\n**Kinematic feedback left out.**  The quasi-static loads come from the "
                 "ideal mechanism.  Changing the connecting rod's length by the whole "
                 "clearance + wear depth for the whole cycle (an upper bound: the real "
                 "offset turns with the load) changes the Ch. 8 lives by at most "
                 f"{100 * ch8_fb:.2f} % (2 mm) and the rig's depth and volume by at most "
                 f"{100 * rig_fb:.2f} % (`benchmarks/feedback.py`).")
    return text


def _truth_words(effects, truth_params, distort, stated) -> str:
    """A campaign's truth as the generator records it, in words."""
    from diffwear.calibrate import discrepancy as disc
    from diffwear.calibrate.effects import EFFECTS, NAMES

    parts = []
    if effects is not None:
        for k, name in enumerate(NAMES):
            strength = float(effects.strength[k])
            if strength == 0.0:
                continue
            text = f"{name} {strength:g}"
            if EFFECTS[k].shape is not None:
                text += f" ({float(effects.shape(name)):g} {EFFECTS[k].shape.unit})"
            parts.append(text)
        angle = np.asarray(effects.discrepancy)[disc.SLICES["angle"]]
        if np.any(angle != 0.0):
            amp = np.hypot(angle[0::2], angle[1::2])
            m = int(np.argmax(amp)) + 1
            peak = np.degrees(np.arctan2(angle[2 * m - 1], angle[2 * m - 2]) / m) % (360 / m)
            parts.append(f"k x (1 + {amp[m - 1]:g} cos {m}(theta - {peak:.0f} deg)), outside "
                         "the library")
        outside = getattr(effects, "outside", None)
        if outside is not None:
            parts.append(getattr(outside, "words", "a rate factor") + ", outside the library")
    odd = [p for p in truth_params if p not in ("k", "free_length")
           and truth_params[p] != stated[p]]
    parts += [f"{p} x{truth_params[p] / stated[p]:g}" for p in odd]
    if distort is not None:
        parts.append(f"{distort.__name__.replace('_', ' ')}, outside the library")
    return "; ".join(parts) or "none"


def _found_words(s: dict) -> str:
    """What the loop named, in words."""
    def effect(e):
        if "identified_form" in e:
            f = e["identified_form"]
            return (f"{e['name']}: {f['value_mm3']:+.3g} +- {f['std_mm3']:.2g} mm^3 by "
                    f"{f['cycles']:g} cycles (shape not determined)")
        text = f"{e['name']}: {e['strength']:.3g} +- {e['strength_std']:.2g}"
        if e.get("shape") is not None:
            lo, hi = e["shape_interval"]
            text += f" ({e['shape']:.3g}; 1 sigma {lo:.3g}..{hi:.3g})"
        return text

    words = []
    for e in s.get("effects_identified", []):
        if e.get("ambiguous"):
            words.append(f"{e['name']} (ambiguous)")
        else:
            words.append(effect(e))
    d = s.get("discrepancy") or {}
    if d.get("variable"):
        words.append(f"discrepancy in {d['variable']}: {d['shape']}")
    if not words:
        words.append("none" + (", residual unexplained" if s["residual_unexplained"] else ""))
    return "; ".join(words)


def _calibration_table() -> str:
    import importlib.util

    sys.path.insert(0, str(ROOT / "src"))
    calibration = ROOT / "design_studies" / "calibration"
    spec = importlib.util.spec_from_file_location("make", calibration / "make_datasets.py")
    make = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(make)
    from diffwear.calibrate.model import rig_defaults

    stated = rig_defaults()
    rows = ["| campaign | truth | named (fit data only) | held-out RMSE before -> after "
            "[sigma] | held-out points in the 90 % band | life to the wall [cycles] | suspect "
            "named | chi2 fit points: fitted / dynamic check | wall |",
            "|---|---|---|---|---|---|---|---|---|"]
    for name, (effects, *_rest) in make.DATASETS.items():
        truth_params, distort = _rest[2], _rest[3]
        path = calibration / "results" / name / "summary.json"
        if not path.exists():
            continue
        s = json.loads(path.read_text())
        truth = _truth_words(effects, truth_params, distort, stated)
        suspect = ""
        if s.get("suspect"):
            lead = s["suspects"][0]
            suspect = (f"{lead['name']} x{lead['factor']:.3g}"
                       + (" (explains the data)" if lead.get("explains") else " (in part)"))
        check = s.get("model_check") or {}
        chi2 = (f"{s['chi2_fit']:.0f} / {check['chi2_fit']:.0f} on {check['n_fit']}"
                if check.get("chi2_fit") is not None else "")
        cover = s.get("heldout_coverage")
        cover = f"{100 * cover:.0f} %" if cover is not None and cover == cover else ""
        life = s.get("life") or {}
        life = (f"{life['median']:,.0f} ({life['q05']:,.0f}-{life['q95']:,.0f})"
                if life else "")
        rows.append(f"| `{name}` | {truth} | {_found_words(s)} | {s['heldout_rmse_before']:.3g} "
                    f"-> {s['heldout_rmse_after']:.3g} | {cover} | {life} | {suspect} | "
                    f"{chi2} | {s['wall_time_s']:.0f} s |")
    return "\n".join(rows) + (
        "\n\nLife: the median and the 90 % band of the cycles until the maximum depth "
        "reaches the bushing wall, under the chosen model (under both, their draws pooled "
        "by their weights, where the answer is open; so is the band's coverage).  Wall "
        "times: the whole loop incl. compilation, the posterior, the life and the dynamic "
        "check, measured with other jobs sharing the 2 CPUs; the benchmark cases "
        "`calibration loop` time a campaign alone.")


# Stored calibration runs whose figures the calibration guide shows (served
# under calibration/<run>/ from design_studies/calibration/results/<run>/)
CALIBRATION_FIGURES = {
    "campaign_three_lobe_k": ("discrepancy.png",),
    "campaign_run_in_and_creep": ("fit_worn_volume.png",),
    "campaign_pressure_exponent": ("candidates.png", "next_measurement.png"),
    "campaign_two_lobe_k": ("fit_profile_21400.png", "posterior.png", "life.png"),
    "campaign_humidity_k": ("discrepancy.png",),
}


def _coverage_record() -> str:
    """The calibration bands' coverage over synthetic campaigns
    (``benchmarks/records/calibration_coverage.json``) in words."""
    path = RECORDS / "calibration_coverage.json"
    if not path.exists():
        return "(no record yet: run `python benchmarks/coverage.py`)"
    r = json.loads(path.read_text())
    lo, hi = r["campaign_coverage_5_95"]
    return (f"{100 * r['pooled_heldout_coverage']:.1f} % of the held-out points over "
            f"{r['campaigns']} campaigns (goal 85-95 %; per campaign a median of "
            f"{100 * r['median_campaign_coverage']:.0f} %, 5-95 % of campaigns "
            f"{100 * lo:.0f}-{100 * hi:.0f} %)")


def _headline_table() -> str:
    """The README's "Headline results" section (table and note), its links
    into docs/ rewritten relative to the docs folder."""
    readme = (ROOT / "README.md").read_text()
    section = readme.split("## Headline results", 1)[1].split("\n## ", 1)[0]
    return section.strip().replace("](docs/", "](")


def _figures() -> dict[str, bytes]:
    """Every figure of ``docs/figures.py``, drawn now: site path -> PNG."""
    import importlib.util
    import tempfile

    spec = importlib.util.spec_from_file_location("diffwear_docs_figures",
                                                  Path(__file__).with_name("figures.py"))
    figures = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(figures)
    with tempfile.TemporaryDirectory() as tmp:
        return {site: path.read_bytes() for site, path in figures.draw_all(Path(tmp)).items()}


def on_files(files, config):
    """Add the stored runs' figures (`CALIBRATION_FIGURES`) and the figures
    drawn from the stored runs (``docs/figures.py``) to the site."""
    from mkdocs.structure.files import File

    results = ROOT / "design_studies" / "calibration" / "results"
    for run, names in CALIBRATION_FIGURES.items():
        for name in names:
            if (results / run / name).is_file():
                files.append(File.generated(config, f"calibration/{run}/{name}",
                                            abs_src_path=str(results / run / name)))
    for site_path, png in _figures().items():
        files.append(File.generated(config, site_path, content=png))
    return files


def on_page_markdown(markdown: str, page, config, files) -> str:
    for key, make in (("CLI_REFERENCE", _cli_reference),
                      ("QUASI_STATIC_TABLE", _quasi_static_table),
                      ("AGREEMENT_TABLE", _agreement_table),
                      ("RESULTS_TABLE", _calibration_table),
                      ("COVERAGE_RECORD", _coverage_record),
                      ("HEADLINE_TABLE", _headline_table)):
        if key in markdown:
            markdown = markdown.replace(key, make())
    return markdown

