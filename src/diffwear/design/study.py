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

import jax
import jax.numpy as jnp
import numpy as np

from .._checks import check_int_option
from ..errors import InputError
from ..io import OutputDir
from .optimise import (LONGEST_LIFE_CORNER, equal_life, jacobian, least_material,
                       longest_common_life)
from .two_joint import LOWER, TABLE_8_4, TABLE_8_5, UPPER, TwoJointLife

NAME = "two-joint"
DESCRIPTION = ("Ch. 8: bushing diameters and depths of two wearing joints for equal life "
               "(optimistix on the full model)")

START = np.array([45.0e-3, 45.0e-3, 30.0e-3, 30.0e-3])  # m: the centre of the Table 8-3 box
PROBLEMS = ("equal-life", "longest-common-life", "least-material")
FULL = dict(steps=10, map_points=5, n_theta=90, problems=PROBLEMS)
QUICK = dict(steps=3, map_points=2, n_theta=90, problems=PROBLEMS)
LIMITS = dict(steps=(1, 100), map_points=(1, 50), n_theta=(12, 720))


def settings(*, quick: bool = False, problems: str | None = None, **overrides) -> dict:
    """The model and map sizes: `FULL` (or `QUICK`) with any non-None override,
    each checked against `LIMITS`, and ``problems`` (comma-separated names from
    `PROBLEMS`; equal life is always solved: the maps are drawn around it).
    `InputError` names the option."""
    chosen = dict(QUICK if quick else FULL)
    if problems is not None:
        names = tuple(n.strip() for n in problems.split(",") if n.strip())
        unknown = [n for n in names if n not in PROBLEMS]
        if unknown or not names:
            raise InputError(f"--problems: unknown problem(s) {unknown or [problems]}; "
                             f"choose from {', '.join(PROBLEMS)}")
        chosen["problems"] = tuple(n for n in PROBLEMS if n in names or n == "equal-life")
    for key, value in overrides.items():
        if value is None:
            continue
        check_int_option(f"--{key.replace('_', '-')}", value, *LIMITS[key])
        chosen[key] = value
    return chosen


def life_maps(model: TwoJointLife, x, points: int) -> dict:
    """cyc_j over (d_j, h_j) on a points x points grid, the other joint at ``x``
    (the model mapped over the grid, one compiled call per joint)."""
    d = np.linspace(LOWER[0], UPPER[0], points)
    h = np.linspace(LOWER[2], UPPER[2], points)
    dd, hh = np.meshgrid(d, h, indexing="ij")
    # lax.map, not vmap: under vmap the scan's lax.cond becomes a select and
    # every point runs all 3 x steps + 4 slots (the full 5 x 5 maps ran > 17 min)
    batch = jax.jit(lambda xs: jax.lax.map(model, xs))
    maps = {"d_m": d, "h_m": h}
    for j in (0, 1):
        xs = np.repeat(np.asarray(x)[None], dd.size, axis=0)
        xs[:, j], xs[:, j + 2] = dd.ravel(), hh.ravel()
        maps[f"cyc{j + 1}"] = np.asarray(batch(jnp.asarray(xs)))[:, j].reshape(dd.shape)
    return maps


def map_trend(maps: dict) -> dict:
    """The thesis's trend check (Figs. 8-7/8-8: life "rises strongly with depth
    and falls weakly with diameter") read off the life maps, i.e. over the
    whole Table 8-3 box rather than from a local derivative: at the default
    cycle tolerance the model's life carries ~3e-4 relative noise, which
    central differences at 1e-3 relative step turn into ~400 cycles/mm, more
    than the diameter slope itself (measured on the coarse model).

    Per joint: ``depth_life_ratio`` (life at the deepest over the shallowest
    bushing, least over the diameters), ``diameter_relative_change`` (life at
    the largest minus the smallest diameter, over their mean, the extreme over
    the depths), and whether every grid line is monotone."""
    out = {"rises_with_depth": [], "falls_with_diameter": [], "depth_life_ratio": [],
           "diameter_relative_change": []}
    for j in (1, 2):
        c = maps[f"cyc{j}"]  # [d, h]
        out["rises_with_depth"].append(bool(np.all(np.diff(c, axis=1) > 0)))
        out["falls_with_diameter"].append(bool(np.all(np.diff(c, axis=0) < 0)))
        out["depth_life_ratio"].append(float(np.min(c[:, -1] / c[:, 0])))
        change = (c[-1] - c[0]) / (0.5 * (c[-1] + c[0]))
        out["diameter_relative_change"].append(float(change[np.argmax(np.abs(change))]))
    out["life_rises_with_depth"] = all(out["rises_with_depth"])
    out["life_falls_with_diameter"] = all(out["falls_with_diameter"])
    return out


def _plot_map(path, maps, j, answer):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    d, h = maps["d_m"] * 1e3, maps["h_m"] * 1e3
    c = ax.contourf(d, h, maps[f"cyc{j}"].T / 1e3, levels=12, cmap="viridis")
    fig.colorbar(c, ax=ax, label=f"cyc{j} [thousand cycles]")
    ax.plot(answer[j - 1] * 1e3, answer[j + 1] * 1e3, "r*", ms=12, label="equal-life answer")
    ax.plot(TABLE_8_4[j - 1] * 1e3, TABLE_8_4[j + 1] * 1e3, "wo", label="thesis Table 8-4")
    ax.set_xlabel(f"bushing diameter d{j} [mm]")
    ax.set_ylabel(f"bushing depth h{j} [mm]")
    ax.set_title(f"Joint {j}: cycles to 2 mm wear")
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def run(out: OutputDir, *, settings: dict | None = None, log=print) -> dict:
    """Solve the chosen problems, check Table 8-4, map the lives; ``settings``
    from `settings()` (default `FULL`)."""
    settings = FULL if settings is None else settings
    model = TwoJointLife(steps=settings["steps"], n_theta=settings["n_theta"])
    t0 = time.perf_counter()
    log(f"[{NAME}] model: steps {model.steps}, n_theta {model.n_theta}; Table 8-4 check ...")
    thesis_cycles = model.life(TABLE_8_4)
    thesis_gap = float(abs(thesis_cycles[0] - thesis_cycles[1]) / thesis_cycles.mean())

    log(f"[{NAME}] equal life from {np.round(START * 1e3, 2).tolist()} mm ...")
    eq = equal_life(model, START)
    jac = jacobian(model, eq.x) * 1e-3  # cycles per mm

    solved = {}
    if "longest-common-life" in settings["problems"]:
        log(f"[{NAME}] longest common life ...")
        solved["longest_common_life"] = longest_common_life(model)
    if "least-material" in settings["problems"]:
        # the thesis's life if our model can reach it with d = 20 mm, else the
        # equal-life answer's (reachable: life hardly depends on d)
        corner = (solved["longest_common_life"].notes["corner_cycles"]
                  if "longest_common_life" in solved else model.life(LONGEST_LIFE_CORNER))
        target = float(TABLE_8_5["surrogate_cycles"])
        why = "thesis Table 8-5"
        if min(corner) < target:
            why = (f"the equal-life answer's life; the thesis's {target:,.0f} cycles is out of "
                   f"reach: {min(corner):,.0f} at d = 20 mm, h = 50 mm")
            target = float(np.mean(eq.cycles))
        log(f"[{NAME}] least material at {target:,.0f} cycles ({why}) ...")
        solved["least_material"] = least_material(model, target, corner_cycles=corner)
        solved["least_material"].notes["target_source"] = why

    log(f"[{NAME}] life maps ({settings['map_points']}^2 points per joint) ...")
    maps = life_maps(model, eq.x, settings["map_points"])
    total = time.perf_counter() - t0
    trend = map_trend(maps)
    trend["jacobian_cycles_per_mm"] = jac.tolist()

    for j in (1, 2):
        _plot_map(out.file(f"life_map_joint{j}.png"), maps, j, eq.x)
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

    summary = {
        **eq.summary(),
        "start_mm": (START * 1e3).tolist(),
        "model": {"steps": model.steps, "scheme": model.scheme, "n_theta": model.n_theta,
                  "cycle_rtol": model.cycle_rtol, "wear_limit_mm": model.limit * 1e3,
                  "jacobian": "central differences, 1e-3 relative (8 runs in one lax.map)"},
        "trend": trend,
        "thesis_optimum_table_8_4": {
            "x_mm": (TABLE_8_4 * 1e3).tolist(), "cyc1": float(thesis_cycles[0]),
            "cyc2": float(thesis_cycles[1]), "rel_gap": thesis_gap,
            "thesis_full_model": TABLE_8_5},
        **{key: res.summary() for key, res in solved.items()},
        "total_wall_time_s": total,
        "settings": {**settings, "problems": list(settings["problems"])},
        "quick": settings["steps"] < FULL["steps"] or settings["n_theta"] < FULL["n_theta"],
    }
    out.json("summary.json", summary)
    out.text("report.md", _report(summary))
    log(f"[{NAME}] equal life: d = {eq.x[:2] * 1e3} mm, h = {eq.x[2:] * 1e3} mm, "
        f"cyc = {eq.cycles}, gap {eq.rel_gap:.2e}; {total:.0f} s")
    return summary


def _row(name, s):
    return (f"| {name} | {s['d1_mm']:.2f} | {s['d2_mm']:.2f} | {s['h1_mm']:.2f} | "
            f"{s['h2_mm']:.2f} | {s['cyc1']:,.0f} | {s['cyc2']:,.0f} | {100 * s['rel_gap']:.2f} % | "
            f"{s['bushing_volume_mm3'] / 1e3:.1f} | {s['model_evaluations']} |")


def _report(s: dict) -> str:
    t = s["thesis_optimum_table_8_4"]
    lines = [
        "# Two-joint bushing design (thesis Ch. 8)", "",
        "Table 2-1 slider-crank, PTFE bushings in the rod at crank-rod (1) and rod-slider (2), "
        "k 5.05e-4 mm^3/(N m), mu 0.13, limit 2 mm, Table 8-3 box. Optimiser: optimistix "
        "Levenberg-Marquardt, bounds by sigmoid reparametrisation, Jacobian by central differences.", "",
        "| problem | d1 mm | d2 mm | h1 mm | h2 mm | cyc1 | cyc2 | gap | PTFE cm^3 | model runs |",
        "|---|---|---|---|---|---|---|---|---|---|",
        _row("equal life (from box centre)", s),
        *[_row(title, s[key]) for key, title in (
            ("longest_common_life", "equal life, longest common life"),
            ("least_material", "equal life, least material at "
             f"{s.get('least_material', {}).get('target_cycles', 0):,.0f} cycles")) if key in s],
        "",
        f"Thesis optimum (Table 8-4) in our model: cyc1 = {t['cyc1']:,.0f}, cyc2 = "
        f"{t['cyc2']:,.0f}, gap {100 * t['rel_gap']:.1f} % (thesis full model: 121,600 / "
        "117,600, 3.3 %).", "",
        "Trend over the Table 8-3 box (from the life maps; thesis: life rises strongly with "
        "depth and falls weakly with diameter): life rises with depth: "
        f"{s['trend']['life_rises_with_depth']} (deepest / shallowest bushing: "
        f"{', '.join(f'{r:.2f}x' for r in s['trend']['depth_life_ratio'])} for joints 1, 2); "
        f"falls with diameter: {s['trend']['life_falls_with_diameter']} (largest vs smallest "
        "diameter: "
        f"{', '.join(f'{100 * r:+.2f} %' for r in s['trend']['diameter_relative_change'])}).", "",
        "![joint 1](life_map_joint1.png) ![joint 2](life_map_joint2.png)", "",
        "Data: `summary.json`, `history.csv`, `life_maps.csv`.",
    ]
    return "\n".join(lines) + "\n"


def benchmark_case(quick: bool) -> dict:
    """benchmarks/run.py case ``ch8-optimisation``.  Full: the equal-life
    optimisation timed, with its iterations and model runs.  Quick (CI): the
    cost of one optimiser iteration on the coarse model: one run and one
    central-difference Jacobian (8 runs)."""
    if not quick:
        model = TwoJointLife(steps=FULL["steps"])
        t0 = time.perf_counter()
        res = equal_life(model, START)
        wall = time.perf_counter() - t0
        return {"wall_time_s": wall, "run_s": wall, "iterations": res.iterations,
                "model_evaluations": res.model_evaluations, "rel_gap": res.rel_gap,
                "steps": model.steps,
                "note": (f"whole equal-life solve incl. compiles: {res.iterations} iterations, "
                         f"{res.model_evaluations} model runs, gap {res.rel_gap:.1e}")}
    model = TwoJointLife(steps=QUICK["steps"])
    x = jnp.asarray(START)
    model.life(START)  # compile
    t0 = time.perf_counter()
    cycles = model.life(START)
    run_s = time.perf_counter() - t0
    jacobian(model, x)  # compile
    t0 = time.perf_counter()
    jac = jacobian(model, x)
    jac_s = time.perf_counter() - t0
    return {"model_run_s": run_s, "jacobian_s": jac_s, "jacobian_over_run": jac_s / run_s,
            "cyc1": float(cycles[0]), "cyc2": float(cycles[1]),
            "dcyc1_dh1_per_mm": float(jac[0, 2]) * 1e-3, "steps": model.steps}
