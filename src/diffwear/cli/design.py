"""``diffwear design two-joint``: the thesis Ch. 8 design study, on the model itself.

Writes into the output folder: ``summary.json`` (the equal-life answer with
d1_mm, d2_mm, h1_mm, h2_mm, cyc1, cyc2, rel_gap, iterations,
model_evaluations, wall_time_s; plus the two further problems, the Table 8-4
check and the trend check), ``history.csv`` (every model evaluation inside the
optimiser), ``life_map_joint1.png`` / ``life_map_joint2.png`` and
``life_maps.csv`` (cyc1 over (d1, h1) and cyc2 over (d2, h2), the other joint
at the answer: the model mapped over a grid with lax.map, like thesis Figs. 8-7 and 8-8) and
``report.md``.
"""

from __future__ import annotations

import csv
import time
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

from .._checks import check_int_option
from ..design.life_maps import life_maps, map_batch, map_trend
from ..design.optimise import jacobian, jacobian_method, life_of
from ..design.problems import START, solve_problems
from ..design.two_joint import SWEEP_MODEL, TABLE_8_4, TABLE_8_5, TwoJointLife
from ..errors import InputError
from ..io import OutputDir
from ..models import Dynamic, QuasiStatic
from ..plots import design as plots_design
from ..report import Block, Report, Table, render

NAME = "two-joint"
DESCRIPTION = ("Ch. 8: bushing diameters and depths of two wearing joints for equal life "
               "(optimistix on the quasi-static model with exact gradients, corrected on "
               "the dynamic model)")

PROBLEMS = ("equal-life", "longest-common-life", "least-material", "robust")
MODELS = ("quasi-static", "dynamic")
# steps: the quasi-static model's wear steps to the limit; dynamic_steps: the
# dynamic model's (the reference of the correction, or the model itself).
FULL: dict[str, Any] = dict(model="quasi-static", steps=40, dynamic_steps=10, map_points=4,
                            n_theta=90, problems=("equal-life",))
QUICK: dict[str, Any] = dict(model="quasi-static", steps=10, dynamic_steps=3, map_points=2,
                             n_theta=90, problems=("equal-life",))
# Load samples per cycle of the quasi-static model here: 90 puts the lives
# within 1e-4 of 180 samples' on this mechanism (measured at the equal-life
# design) at half the cost.
SAMPLES = 90
# the quasi-static steps start at 5: at 2 steps to the 2 mm limit its lives
# are too crude for the dynamic correction to converge (measured: residual
# stuck at 27 %); from 10 steps it converges in 2-3 rounds
LIMITS = dict(steps=(5, 400), dynamic_steps=(1, 100), map_points=(2, 50), n_theta=(12, 720))


def settings(*, quick: bool = False, problems: str | None = None, model: str | None = None,
             **overrides) -> dict:
    """The models and map sizes: `FULL` (or `QUICK`) with any non-None override,
    each checked against `LIMITS`; ``problems``: comma-separated names from
    `PROBLEMS` or "all" (equal life is always solved: the maps are drawn
    around it); ``model``: one of `MODELS`.  `InputError` names the option."""
    chosen: dict[str, Any] = dict(QUICK if quick else FULL)
    if problems is not None:
        names = tuple(n.strip() for n in problems.split(",") if n.strip())
        if names == ("all",):
            names = PROBLEMS
        unknown = [n for n in names if n not in PROBLEMS]
        if unknown or not names:
            raise InputError(f"--problems: unknown problem(s) {unknown or [problems]}; "
                             f"choose from {', '.join(PROBLEMS)} or all")
        chosen["problems"] = tuple(n for n in PROBLEMS if n in names or n == "equal-life")
    if model is not None:
        if model not in MODELS:
            raise InputError(f"--model: unknown model {model!r}; choose from {', '.join(MODELS)}")
        chosen["model"] = model
    if chosen["model"] == "dynamic" and "robust" in chosen["problems"]:
        raise InputError("--problems robust needs --model quasi-static (its stochastic "
                         "gradients are autodiff gradients of the lives)")
    for key, value in overrides.items():
        if value is None:
            continue
        check_int_option(f"--{key.replace('_', '-')}", value, *LIMITS[key])
        chosen[key] = value
    return chosen


def models(settings: dict) -> tuple:
    """(fast, reference): the model the optimiser works on and the model that
    checks it (the same object for --model dynamic)."""
    reference = TwoJointLife(wear_model=Dynamic(steps=settings["dynamic_steps"]),
                             n_theta=settings["n_theta"])
    if settings["model"] == "dynamic":
        return reference, reference
    fast = TwoJointLife(wear_model=QuasiStatic(steps=settings["steps"], samples=SAMPLES),
                        n_theta=settings["n_theta"]).prepared()
    return fast, reference


def _describe(model) -> str:
    """One line naming a life model and its resolution."""
    m = model.wear_model
    return (f"{m.name} model, {m.steps} wear steps, {getattr(m, 'samples', '-')} load samples, "
            f"{model.n_theta} profile nodes")


def run(out: OutputDir, *, settings: dict | None = None, log=print) -> dict:
    """Solve the chosen problems, check Table 8-4, map the lives; ``settings``
    from `settings()` (default `FULL`)."""
    settings = FULL if settings is None else settings
    t0 = time.perf_counter()
    fast, reference = models(settings)
    corrected = fast is not reference
    steps = settings["steps"] if corrected else settings["dynamic_steps"]
    log(f"[{NAME}] model: {fast.wear_model.name} (steps {steps}, "
        f"n_theta {fast.n_theta}), Jacobians by {jacobian_method(fast)}"
        + (f"; corrected on the dynamic model (steps {settings['dynamic_steps']})"
           if corrected else ""))
    # In a second thread while the problems are solved (2 cores; XLA compiles
    # and runs outside the GIL): the Table 8-4 check on the reference model,
    # which also compiles it for the space-mapping rounds, and the compiled
    # life maps (what it saves: docs/notes/design-solver.md).
    def map_setup():
        model = SWEEP_MODEL.prepared() if corrected else fast
        return model, map_batch(model, settings["map_points"])

    with ThreadPoolExecutor(max_workers=1) as pool:
        thesis_job = pool.submit(life_of, reference, TABLE_8_4)
        maps_job = pool.submit(map_setup)
        chosen = settings["problems"]
        solved = solve_problems(fast, reference,
                                with_longest_common_life="longest-common-life" in chosen,
                                with_least_material="least-material" in chosen,
                                with_robust="robust" in chosen, log=log, prefix=f"[{NAME}] ")
        log(f"[{NAME}] Table 8-4 check ...")
        thesis_cycles = thesis_job.result()
        map_model, batch = maps_job.result()
    eq = solved.pop("equal_life")
    dynamic_runs = sum(r.notes.get("reference_runs", 0) for r in (eq, *solved.values()))
    if not corrected:
        dynamic_runs = eq.model_evaluations + sum(r.model_evaluations for r in solved.values())

    dynamic_runs += 1
    thesis_fast = life_of(fast, TABLE_8_4)
    thesis_gap = float(abs(thesis_cycles[0] - thesis_cycles[1]) / thesis_cycles.mean())
    jac = jacobian(fast, eq.x) * 1e-3  # cycles per mm

    # the maps (a picture and the trend check over the whole box) on the sweep
    # settings when the fast model has them: within 0.3 % of the design model
    # at ~1/25 of its cost per point
    log(f"[{NAME}] life maps ({settings['map_points']}^2 points per joint) ...")
    maps = life_maps(map_model, eq.x, settings["map_points"], batch)
    total = time.perf_counter() - t0
    trend = map_trend(maps)
    trend["map_model"] = _describe(map_model)
    trend["jacobian_cycles_per_mm"] = jac.tolist()
    trend["jacobian_method"] = jacobian_method(fast)

    for j in (1, 2):
        plots_design.life_map(out.file(f"life_map_joint{j}.png"), maps, j, eq.x, TABLE_8_4)
    with open(out.file("life_maps.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["joint", "d_mm", "h_mm", "cycles"])
        for j in (1, 2):
            for a, dv in enumerate(maps["d_m"]):
                for b, hv in enumerate(maps["h_m"]):
                    w.writerow([j, dv * 1e3, hv * 1e3, maps[f"cyc{j}"][a, b]])
    with open(out.file("history.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["problem", "evaluation", "d1_mm", "d2_mm", "h1_mm", "h2_mm", "cyc1", "cyc2"])
        for res in (eq, *solved.values()):
            for i, h in enumerate(res.history):
                w.writerow([res.problem, i, *h["x_mm"], *h["cycles"]])

    model_info = {"wear_limit_mm": fast.limit * 1e3, "n_theta": fast.n_theta,
                  "steps": settings["steps"], "dynamic_steps": settings["dynamic_steps"]}
    summary = {
        **eq.summary(),
        "model": fast.wear_model.name,
        "jacobian_method": jacobian_method(fast),
        "dynamic_runs": int(dynamic_runs),
        "corrected_on": reference.wear_model.name if corrected else None,
        "start_mm": (START * 1e3).tolist(),
        "model_settings": model_info,
        "trend": trend,
        "thesis_optimum_table_8_4": {
            "x_mm": (TABLE_8_4 * 1e3).tolist(), "cyc1": float(thesis_cycles[0]),
            "cyc2": float(thesis_cycles[1]), "rel_gap": thesis_gap,
            "model": reference.wear_model.name,
            f"{fast.wear_model.name}_cycles": thesis_fast.tolist(),
            "thesis_full_model": TABLE_8_5},
        **{key: res.summary() for key, res in solved.items()},
        "total_wall_time_s": total,
        "settings": {**settings, "problems": list(settings["problems"])},
        "quick": settings == {**QUICK, "problems": settings["problems"]},
    }
    out.json("summary.json", summary)
    out.text("report.md", render(_report(summary)))
    log(f"[{NAME}] equal life: d = {np.round(eq.x[:2] * 1e3, 3).tolist()} mm, h = "
        f"{np.round(eq.x[2:] * 1e3, 3).tolist()} mm, cyc = {np.round(eq.cycles).tolist()} "
        f"({reference.wear_model.name}), gap {eq.rel_gap:.2e}; {dynamic_runs} dynamic runs; "
        f"{total:.0f} s")
    return summary


def _row(name, s) -> tuple:
    return (name, f"{s['d1_mm']:.2f}", f"{s['d2_mm']:.2f}", f"{s['h1_mm']:.2f}",
            f"{s['h2_mm']:.2f}", f"{s['cyc1']:,.0f}", f"{s['cyc2']:,.0f}",
            f"{100 * s['rel_gap']:.2f} %", f"{s['bushing_volume_mm3'] / 1e3:.1f}",
            s["model_evaluations"])


def _report(s: dict) -> Report:
    t = s["thesis_optimum_table_8_4"]
    corrected = s["corrected_on"] is not None
    how = (f"optimistix Levenberg-Marquardt on the {s['model']} model with {s['jacobian_method']} "
           "Jacobians, bounds by sigmoid reparametrisation")
    if corrected:
        how += (f"; each answer corrected on the {s['corrected_on']} model (output space "
                f"mapping) until its residual there is below 0.5 %: lives below are the "
                f"{s['corrected_on']} model's; {s['dynamic_runs']} {s['corrected_on']} runs in all")
    blocks: list[Block] = [
        "Table 2-1 slider-crank, PTFE bushings in the rod at crank-rod (1) and rod-slider (2), "
        "k 5.05e-4 mm^3/(N m), mu 0.13, limit 2 mm, Table 8-3 box. Optimiser: " + how + ".",
        "Lives in cycles to the 2 mm limit: joint 1 (crank-rod) and joint 2 (rod-slider); "
        "gap: their difference over their mean.",
        Table(("problem", "d1 mm", "d2 mm", "h1 mm", "h2 mm", "life 1", "life 2", "gap",
               "PTFE cm^3", "model runs"), [
            _row("equal life (from box centre)", s),
            *[_row(title, s[key]) for key, title in (
                ("longest_common_life", "equal life, longest common life"),
                ("least_material", "equal life, least material at "
                 f"{s.get('least_material', {}).get('target_cycles', 0):,.0f} cycles"))
              if key in s]]),
    ]
    if "robust" in s:
        r = s["robust"]
        det = r["deterministic"]
        check = r["percentile_check"]
        blocks += [
            f"Robust design ({s['model']} model, lives at the median k): the weaker joint's "
            f"life must reach {r['target_cycles']:,.0f} cycles in "
            f"{100 * r['reliability']:.0f} % of the mechanisms, each bushing's k log-normal "
            f"with 95 % within +-{100 * r['k_scatter']:.0f} %"
            + (f" ({r['asked_cycles']:,.0f} cycles asked: out of reach, the best 10th "
               f"percentile in the box is {r['best_percentile_in_box']:,.0f})"
               if r["asked_cycles"] > r["target_cycles"] else "") + ":",
            Table(("design", "h1 mm", "h2 mm", "life 1 (median k)", "life 2 (median k)",
                   "P10 of weaker life", "PTFE cm^3"), [
                ("deterministic least material", f"{det['h1_mm']:.2f}", f"{det['h2_mm']:.2f}",
                 f"{det['cyc1']:,.0f}", f"{det['cyc2']:,.0f}", f"{det['percentile']:,.0f}",
                 f"{det['bushing_volume_mm3'] / 1e3:.1f}"),
                ("robust", f"{r['h1_mm']:.2f}", f"{r['h2_mm']:.2f}", f"{r['cyc1']:,.0f}",
                 f"{r['cyc2']:,.0f}",
                 f"{check['percentile']:,.0f} ({check['interval'][0]:,.0f}-"
                 f"{check['interval'][1]:,.0f}, {check['samples']:,} samples)",
                 f"{r['bushing_volume_mm3'] / 1e3:.1f}")]),
            "Reliability costs "
            f"{100 * (r['bushing_volume_mm3'] / det['bushing_volume_mm3'] - 1):.0f} "
            "% more PTFE."]
        mc = r.get("monte_carlo_check")
        if mc is not None:
            blocks.append(
                f"Monte-Carlo check: the {s['model']} model itself at {mc['samples']:,} sampled "
                f"k pairs gives a P10 of {mc['percentile']:,.0f} cycles (95 % interval "
                f"{mc['interval'][0]:,.0f}-{mc['interval'][1]:,.0f}): "
                + ("it confirms the reported percentile." if mc["confirms"] else
                   "**the reported percentile lies outside it**."))
    blocks += [
        f"Thesis optimum (Table 8-4) in our {t['model']} model: lives {t['cyc1']:,.0f} "
        f"(joint 1) and {t['cyc2']:,.0f} (joint 2) cycles, gap {100 * t['rel_gap']:.1f} % "
        "(thesis full model: 121,600 / 117,600, 3.3 %).",
        f"Trend over the Table 8-3 box (from the life maps, {s['trend']['map_model']}; "
        "thesis: life rises strongly with "
        "depth and falls weakly with diameter): life rises with depth: "
        f"{s['trend']['life_rises_with_depth']} (deepest / shallowest bushing: "
        f"{', '.join(f'{r:.2f}x' for r in s['trend']['depth_life_ratio'])} for joints 1, 2); "
        f"falls with diameter: {s['trend']['life_falls_with_diameter']} (largest vs smallest "
        "diameter: "
        f"{', '.join(f'{100 * r:+.2f} %' for r in s['trend']['diameter_relative_change'])}).",
        "![joint 1](life_map_joint1.png) ![joint 2](life_map_joint2.png)",
        "Data: `summary.json`, `history.csv`, `life_maps.csv`.",
    ]
    return Report("Two-joint bushing design (thesis Ch. 8)", blocks)


def benchmark_case(quick: bool) -> dict:
    """benchmarks/run.py case ``ch8-optimisation``: the whole default design
    run (equal life on the quasi-static model, corrected on the dynamic model)
    timed, compiles included, with its dynamic runs and final gap.  Quick
    (CI): the same on the coarse settings, without maps."""
    import tempfile

    chosen = settings(quick=quick)
    if quick:
        chosen["map_points"] = 2  # the smallest map a contour plot can draw
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        s = run(OutputDir(tmp, overwrite=True), settings=chosen, log=lambda *a, **k: None)
    wall = time.perf_counter() - t0
    return {"wall_time_s": wall, "run_s": wall, "dynamic_runs": s["dynamic_runs"],
            "rel_gap": s["rel_gap"], "iterations": s["iterations"],
            "model_evaluations": s["model_evaluations"], "model": s["model"],
            "jacobian_method": s["jacobian_method"],
            "note": (f"whole design run incl. compiles: {s['model']} model with "
                     f"{s['jacobian_method']} Jacobians, {s['dynamic_runs']} dynamic runs "
                     f"(incl. the Table 8-4 check), dynamic gap {s['rel_gap']:.1e}")}
