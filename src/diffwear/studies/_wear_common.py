"""Shared driver of the wear studies (``wear-5000``, ``rig-21400``)."""

from __future__ import annotations

import math
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

from .. import interrupt
from ..choices import WEAR_CONTACTS as CONTACTS
from ..choices import check_wear_model
from ..contact import centred_state, contact_history
from ..dynamics import consistent_state
from ..errors import InputError
from ..io import CHECKPOINT as OUT_CHECKPOINT
from ..presets import PTFE_DENSITY, WearJointDesign, with_wear_joint
from ..report import Block, Bullets, Report, Table
from ..wear import wear_cycle, worn_mechanism, worn_volume
from ..wear.cycle import cycle_integrator
from ..wear.evolution import ChunkedEvolution, Evolver, load_checkpoint, save_checkpoint
from ..wear.fem_route import FemEvolver, default_model
from ._report import COMPARISON_WORDS, comparison_table, peak_line, write_report

JOINT = "crank_rod"
N_SAVE = 401


def params_of(d: WearJointDesign):
    """(k, clearance, depth, diameter) as one array: the differentiable inputs."""
    return jnp.stack([d.k, d.clearance, d.depth, d.diameter])


def design_of(p, base: WearJointDesign) -> WearJointDesign:
    return WearJointDesign(p[0], p[1], p[2], p[3], base.wall, base.mu, base.restitution)


def mech_builder(mech0, design: WearJointDesign, n_theta: int):
    """p -> ``mech0`` with the wear joint of `design_of`(p, ``design``): the
    mechanism as a function of the differentiable inputs (`params_of`)."""
    def mech_of_p(p):
        return with_wear_joint(mech0, design_of(p, design), n_theta=n_theta)
    return mech_of_p


def initial_state(mech0, q_guess, mech):
    """y0 of ``mech`` (the wear version of the ideal ``mech0``): the ideal
    mechanism's consistent state with the pin centred."""
    return centred_state(mech0, consistent_state(mech0, q_guess), mech)


CHECKPOINT = OUT_CHECKPOINT  # the name `io.OutputDir` knows
# Free flight over more than this fraction of a simulated cycle (impacts)
# warns: the wear of one cycle, extrapolated over A cycles, then rests on
# impacts that change from cycle to cycle.
CONTACT_LOSS_WARNING = 0.25
CHUNKS = 10  # a run is cut into ~10 chunks: checkpoint and progress after each
# checkpoint keys added later, with the value that checkpoints written before meant
META_DEFAULTS = {"contact": "efm", "integrator": "tsit5"}


def run_evolution(mech_of_p, p, y0, cycles, period, *, method, extrapolation, max_dynamic,
                  wall, n_theta, rtol=1e-2, atol=1e-6, out=None, meta=None, resume=False,
                  progress=False, chunks=CHUNKS, fem=None, joint=JOINT, integrator="tsit5"):
    """Compile (timed) and run (timed) the whole evolution of clearance joint
    ``joint``.

    ``fem``: a `FemWearModel` for the FEM wear route (`wear.fem_route`), else
    (None) the EFM route.  ``integrator``: the dynamic cycles' integrator by
    name, at its tolerance (`wear.cycle.CYCLE_INTEGRATORS`).

    Without ``out``: one jitted function.  With ``out`` (an `OutputDir`): in
    ``chunks`` chunks of scan slots (`ChunkedEvolution`, same result), saving
    ``out/checkpoint.npz`` (state, history so far, ``meta``) after each chunk;
    ``resume=True`` continues from that checkpoint, which must carry the same
    ``meta``.  ``progress``: a tqdm bar of real cycles done (with time left).
    Returns (result, compile time, run time, info for the summary).
    """
    solver, tol = cycle_integrator(integrator)
    kw = dict(period=period, method=method, extrapolation=extrapolation,
              max_dynamic=max_dynamic, wall_thickness=wall, rtol=rtol, atol=atol,
              cycle_solver=solver, cycle_rtol=tol, cycle_atol=tol)

    def make(p):
        if fem is None:
            return Evolver(mech_of_p(p), joint, cycles, **kw)
        return FemEvolver(mech_of_p(p), joint, cycles, fem=fem, **kw)

    if out is None:
        def fn(p, y0):  # as `evolve` / `evolve_fem`, for either route
            ev = make(p)
            state, hist = ev.run(ev.init(y0), ev.n_slots)
            return ev.result(state, hist)

        t0 = time.perf_counter()
        compiled = jax.jit(fn).lower(p, y0).compile()
        compile_time = time.perf_counter() - t0
        t0 = time.perf_counter()
        res = jax.block_until_ready(compiled(p, y0))
        return res, compile_time, time.perf_counter() - t0, {}

    from tqdm.auto import tqdm

    meta = {**(meta or {}), "cycles": float(cycles), "method": method,
            "extrapolation": float(extrapolation), "n_theta": int(n_theta),
            "contact": "efm" if fem is None else "fem", "integrator": integrator}
    if fem is not None:
        meta.update(fem_refresh_interval=float(fem.refresh_interval),
                    fem_samples=fem.n_samples, fem_layers=fem.n_layers, fem_force=fem.force)
    path = out.path / CHECKPOINT
    start = None
    if resume:
        if not path.is_file():
            raise InputError(f"--resume {out.path}: no {CHECKPOINT} there to resume from")
        start, saved = load_checkpoint(path)
        for key, value in meta.items():
            if saved.get(key, META_DEFAULTS.get(key)) != value:
                raise InputError(
                    f"--resume {out.path}: the checkpoint belongs to a run with {key} = "
                    f"{saved.get(key)!r}, this run has {key} = {value!r}; resume with the "
                    "options of the interrupted run")

    n_slots = make(p).n_slots
    run = ChunkedEvolution(make, p, y0, max(1, math.ceil(n_slots / chunks)))
    compile_time = run.compile()
    done0 = 0.0 if start is None else float(start.state.n)
    bar = tqdm(total=float(cycles), initial=done0, unit="cycle", disable=not progress,
               desc=meta.get("study", "wear"), dynamic_ncols=True,
               bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} cycles [{elapsed}<{remaining}]")

    def on_chunk(ck):
        save_checkpoint(path, ck, meta)
        bar.update(float(ck.state.n) - bar.n)
        interrupt.check()  # a Ctrl-C lost inside a callback ends the run here

    t0 = time.perf_counter()
    try:
        res = jax.block_until_ready(run.run(start=start, on_chunk=on_chunk))
    finally:
        bar.close()
    if path.exists():
        out.file(CHECKPOINT)  # listed in the summary; kept after the run
    info = {"finished": True, "checkpoint": CHECKPOINT if path.exists() else None,
            "resumed_from_cycles": done0 if start is not None else None}
    return res, compile_time, time.perf_counter() - t0, info


def _integrator_label(name: str) -> str:
    """E.g. "Tsit5, rtol = atol = 1e-06" for a `wear.cycle.CYCLE_INTEGRATORS` name."""
    solver, tol = cycle_integrator(name)
    return f"{type(solver).__name__}, rtol = atol = {tol:g}"


def check_contact(contact) -> str:
    if contact not in CONTACTS:
        raise InputError(f"--contact must be one of {', '.join(CONTACTS)} (the pressure "
                         f"model of the wear), got {contact!r}")
    return contact


def run_wear_study(out, *, name, mech0, design: WearJointDesign, y0, cycles, period, method,
                   extrapolation, target_dynamic, n_theta, thesis: dict, description: str, log,
                   resume=False, progress=False, extra_summary=None, extra_report=(),
                   contact="efm", fem=None, model="dynamic", thesis_cycles=None,
                   integrator=None, study_integrator="tsit5") -> dict:
    """The body of a wear study: ``design``'s wear joint swapped into ``mech0``
    (differentiable in k, clearance, depth, diameter), the evolution over
    ``cycles`` (constant A = cycles / ``target_dynamic`` unless ``extrapolation``
    is given; checkpointed into ``out``), all outputs, then `EvolutionResult.check`
    (a run that stopped early raises after its results are written).

    ``contact="fem"``: the wear pressure from the FE ring (`wear.fem_route`;
    ``fem`` a `FemWearModel`, default `default_model(design)`); the EFM route is
    run first (one jit, not checkpointed) so that the report compares both.
    ``integrator``: the dynamic cycles' integrator ("tsit5" or "rodas4",
    `wear.cycle.CYCLE_INTEGRATORS`) of both routes; None: ``study_integrator``,
    the one the study chose.  Given to the quasi-static model, an integrator is
    an error: it has no dynamic cycles.

    ``thesis_cycles``: the cycle count the ``thesis`` values are for; a run of
    another length is not compared with them (report, plots and summary say
    so instead)."""
    check_contact(contact)
    if thesis_cycles is not None and thesis and int(cycles) != int(thesis_cycles):
        why = (f"the thesis's values are for {int(thesis_cycles):,} cycles and this run has "
               f"{int(cycles):,}: not compared")
        extra_report = [*extra_report, Bullets([why])]
        extra_summary = {**(extra_summary or {}), "thesis_not_compared": why}
        thesis = {}
    check_wear_model(model, ((method != "constant", f"--method {method}"),
                             (contact != "efm", f"--contact {contact}"),
                             (integrator is not None, f"--integrator {integrator}"),
                             (resume, "--resume")))
    if integrator is None:
        integrator = study_integrator
    cycle_integrator(integrator)  # a bad name fails before any work
    if model == "quasi-static":
        from . import _quasi_static_study

        mech = mech_builder(mech0, design, n_theta)(params_of(design))
        return _quasi_static_study.run(
            out, name=name, mech=mech, design=design, y0=y0, cycles=cycles, period=period,
            thesis=thesis, description=description, log=log, extra_summary=extra_summary,
            extra_report=extra_report)
    if contact == "fem" and method != "constant":
        raise InputError(f"--contact fem runs with --method constant only (constant A, as "
                         f"the thesis's FEM route), got --method {method}")

    mech_of_p = mech_builder(mech0, design, n_theta)
    params = params_of(design)
    a = extrapolation or default_constant_a(cycles, target_dynamic)
    common_kw = dict(method=method, extrapolation=a, max_dynamic=4 * target_dynamic,
                     wall=design.wall, n_theta=n_theta, integrator=integrator)
    extra_summary, extra_report = dict(extra_summary or {}), list(extra_report)
    label = "diffwear"
    if contact == "fem":
        fem = default_model(design) if fem is None else fem
        log(f"[{name}] EFM route for the comparison: {cycles} cycles, A {a} ...")
        efm, efm_ct, efm_wt, _ = run_evolution(mech_of_p, params, y0, cycles, period, **common_kw)
        efm_summary = route_numbers(efm, design, efm_wt, efm_ct)
        log(f"[{name}] EFM route: max depth {efm_summary['max_wear_depth_mm']:.4f} mm, volume "
            f"{efm_summary['wear_volume_mm3']:.2f} mm^3, {efm_wt:.1f} s (+{efm_ct:.1f} s compile)")
        label = "diffwear (FEM route)"
        description = (description + f" Wear pressure: FEM route (thesis Ch. 5): the EFM "
                       f"dynamics' joint force ({fem.force}) at {fem.n_samples + 1} times per "
                       f"cycle on a plane-strain Q9 ring ({n_theta} x {fem.n_layers}, E "
                       f"{float(fem.youngs_modulus) / 1e9:g} GPa, nu "
                       f"{float(fem.poisson_ratio):g}, outer R "
                       f"{float(fem.outer_radius) * 1e3:.3f} mm), compliance rebuilt every "
                       f"{float(fem.refresh_interval):g} wear cycle(s).")
    log(f"[{name}] {cycles} cycles, method {method}, A {a}, contact {contact} ...")
    res, ct, wt, info = run_evolution(
        mech_of_p, params, y0, cycles, period, **common_kw, out=out,
        meta={"study": name}, resume=resume, progress=progress,
        fem=fem if contact == "fem" else None)
    extra_summary["contact"] = contact
    extra_summary["integrator"] = integrator
    if contact == "fem":
        fallback = res.state.memory["fem_explicit"]
        fem_summary = {"explicit_fallback_cycles": int(np.asarray(fallback)),
                       **route_numbers(res, design, wt, ct)}
        ratio = wt / efm_wt
        extra_summary.update(
            fem_route={**fem_summary, "refresh_interval": float(fem.refresh_interval),
                       "samples_per_cycle": fem.n_samples + 1, "layers": fem.n_layers,
                       "force": fem.force, "youngs_modulus_Pa": float(fem.youngs_modulus),
                       "poisson_ratio": float(fem.poisson_ratio),
                       "outer_radius_m": float(fem.outer_radius)},
            efm_route=efm_summary, wall_time_ratio_fem_to_efm=ratio)
        extra_report += route_table(fem_summary, efm_summary, ratio)
    summary = write_outputs(
        out, name=name, mech=mech_of_p(params), design=design, res=res, y0=y0, period=period,
        cycles=cycles, compile_time=ct, wall_time=wt, thesis=thesis, method=method,
        extrapolation=a, description=description, log=log,
        extra_summary={**extra_summary, **info}, extra_report=extra_report, label=label)
    res.check(name)
    return summary


def route_numbers(res, design: WearJointDesign, wall_time, compile_time) -> dict:
    """Max depth, volume, Archard volume, times of one route's result."""
    volume = float(worn_volume(res.depth, design.bushing_radius, design.depth)) * 1e9
    return {"max_wear_depth_mm": float(np.max(np.asarray(res.depth))) * 1e3,
            "wear_volume_mm3": volume,
            "archard_k_times_load_sliding_mm3": float(design.k * res.load_sliding) * 1e9,
            "dynamic_cycles_simulated": int(res.dynamic_cycles), "status": int(res.status),
            "wall_time_s": wall_time, "compile_time_s": compile_time}


def route_table(fem: dict, efm: dict, ratio: float) -> list[Block]:
    """Report blocks: the FEM route next to the EFM route (both run here)."""
    return [
        "FEM route next to the EFM route (both run here, same dynamics):",
        Table(("route", "max depth [mm]", "volume [mm^3]", "k x sum(N ds) [mm^3]",
               "run time [s]", "compile time [s]"),
              [(tag, f"{d['max_wear_depth_mm']:.4f}", f"{d['wear_volume_mm3']:.2f}",
                f"{d['archard_k_times_load_sliding_mm3']:.2f}", f"{d['wall_time_s']:.1f}",
                f"{d['compile_time_s']:.1f}") for tag, d in (("FEM", fem), ("EFM", efm))]),
        Bullets([f"run time FEM / EFM route: {ratio:.2f} (thesis: 11 h / 7 h = 1.6 on the "
                 "rig, 162 / 92 min = 1.8 on wear-5000)"])]


def write_outputs(out, *, name, mech, design: WearJointDesign, res, y0, period, cycles,
                  compile_time, wall_time, thesis: dict, method: str, extrapolation,
                  description: str, log, extra_summary=None, extra_report=(),
                  label: str = "diffwear"):
    from ..plots import wear as plots_wear

    el = mech.element(JOINT)
    n = el.profile.n
    theta = np.asarray(el.profile.theta)
    depth = np.asarray(res.depth)
    numbers = route_numbers(res, design, wall_time, compile_time)

    # first (after the warm-up) and last dynamic cycles, saved densely
    cyc = jax.jit(lambda m, y, t: wear_cycle(m, JOINT, y, t, period, n_save=N_SAVE))
    warm = cyc(mech, y0, 0.0)
    first = cyc(mech, warm.y_end, period)
    # the last cycle runs on the final profile after one settling cycle: the
    # evolution's end state belongs to the profile before its last wear step,
    # and on the deeper final profile the pin would first drop into the
    # groove (an impact the gradually worn joint never sees)
    mech_last = worn_mechanism(mech, JOINT, res.depth)
    settle = cyc(mech_last, res.y, res.t)
    last = cyc(mech_last, settle.y_end, res.t + period)
    hist_first = contact_history(mech, JOINT, first.ys)
    hist_last = contact_history(mech_last, JOINT, last.ys)
    tt = np.asarray(first.ts) - float(first.ts[0])
    crank = 2 * np.pi * tt / period

    out.csv("wear_profile.csv", {"theta_rad": theta, "depth_mm": depth * 1e3})
    h = {k: np.asarray(v) for k, v in res.history.items()}
    valid = h["valid"].astype(bool)
    out.csv("wear_history.csv", {
        "cycles": np.concatenate([[0.0], h["cycles"][valid]]),
        "max_depth_mm": np.concatenate([[0.0], h["max_depth"][valid] * 1e3]),
        "volume_mm3": np.concatenate([[0.0], h["volume"][valid] * 1e9]),
        "extrapolation": np.concatenate([[0.0], h["extrapolation"][valid]]),
        "dynamic_cycles": np.concatenate([[h["dynamic_cycles"][0] * 0 + 1],
                                          h["dynamic_cycles"][valid]]),
    })
    for tag, hist in (("first", hist_first), ("last", hist_last)):
        f = np.asarray(hist.force)
        out.csv(f"joint_force_{tag}_cycle.csv", {
            "crank_angle_rad": crank, "fx_N": f[:, 0], "fy_N": f[:, 1],
            "force_N": np.hypot(f[:, 0], f[:, 1]), "normal_load_N": np.asarray(hist.normal_load),
        })
        off = np.asarray(hist.offset)
        out.csv(f"contact_locus_{tag}_cycle.csv", {
            "crank_angle_rad": crank, "offset_x_mm": off[:, 0] * 1e3,
            "offset_y_mm": off[:, 1] * 1e3, "contact_angle_rad": np.asarray(hist.contact_angle),
            "penetration_um": np.asarray(hist.penetration) * 1e6,
        })

    figs = plots_wear.wear_figures(out, name=name, theta=theta, depth_mm=depth * 1e3,
                                   history=(h["cycles"][valid], h["max_depth"][valid] * 1e3,
                                            h["volume"][valid] * 1e9),
                                   crank=crank, first=hist_first, last=hist_last,
                                   clearance_mm=float(design.clearance) * 1e3, thesis=thesis,
                                   wall_mm=float(design.wall) * 1e3, status=int(res.status))

    summary = {
        "study": name,
        "cycles": float(res.cycles),
        "cycles_requested": float(cycles),
        **numbers,
        "max_wear_angle_rad": float(theta[np.argmax(depth)]),
        "worn_mass_g": numbers["wear_volume_mm3"] * 1e-9 * PTFE_DENSITY * 1e3,
        "method": method,
        "extrapolation": extrapolation,
        "mean_joint_force_first_cycle_N": float(np.mean(np.asarray(hist_first.force_magnitude))),
        "mean_normal_load_first_cycle_N": float(np.mean(np.asarray(hist_first.normal_load))),
        "n_theta": n,
        "thesis": thesis,
        **(extra_summary or {}),
    }
    warnings = contact_loss_warnings({"first": hist_first, "last": hist_last}, extrapolation)
    if warnings:
        summary["warnings"] = warnings
    summary["files"] = sorted(set(out.files)) + ["report.md", "summary.json"]
    report = Report(name, [
        description,
        comparison_table(label, summary, thesis),
        COMPARISON_WORDS,
        Bullets([
            f"cycles: {summary['cycles']:.0f}; dynamic cycles simulated: "
            f"{summary['dynamic_cycles_simulated']} (incl. 1 warm-up cycle whose wear is "
            f"discarded); method {method}, extrapolation A = {extrapolation} (the wear of one "
            "simulated cycle stands for A cycles; with --method adaptive or error, the first "
            "A, which the method then changes)",
            f"Archard check: k x sum(N ds) = {summary['archard_k_times_load_sliding_mm3']:.3f} "
            "mm^3 (the wear coefficient times the normal load integrated over the sliding "
            "distance, summed over the cycles, each simulated one counted A times: Archard's "
            "law for the whole volume, to compare with the wear volume above)",
            peak_line(summary),
            f"mean |joint force| first cycle {summary['mean_joint_force_first_cycle_N']:.1f} N "
            "(the magnitude of the joint's contact force averaged over the first cycle after "
            f"the warm-up), mean total normal load {summary['mean_normal_load_first_cycle_N']:.1f}"
            " N (the bushing's pressure integrated over the contact arc, averaged the same way: "
            "above the joint force because the pressure spreads over an arc)",
            f"run time {wall_time:.1f} s (the compiled wear evolution), compile time "
            f"{compile_time:.1f} s (compiling it); dynamic cycles on "
            f"{_integrator_label(summary.get('integrator', 'tsit5'))}"]),
        *extra_report,
        Bullets([f"warning: {w}" for w in warnings])])
    write_report(out, report, figs, summary)
    for w in warnings:
        print(f"diffwear: warning: {name}: {w}", file=sys.stderr)
    log(f"[{name}] max depth {summary['max_wear_depth_mm']:.4f} mm, volume "
        f"{summary['wear_volume_mm3']:.2f} mm^3, {summary['dynamic_cycles_simulated']} dynamic "
        f"cycles, {wall_time:.1f} s (+{compile_time:.1f} s compile)")
    return summary


def contact_loss_warnings(cycles: dict, extrapolation) -> list[str]:
    """A warning for each simulated cycle (``{"first": history, ...}``, from
    `contact_history`) whose pin is out of contact over more than
    `CONTACT_LOSS_WARNING` of it."""
    out = []
    for tag, hist in cycles.items():
        lost = float(np.mean(np.asarray(hist.penetration) <= 0.0))
        if lost > CONTACT_LOSS_WARNING:
            out.append(f"the pin lost contact over {lost:.0%} of the {tag} dynamic cycle "
                       f"(impacts): the wear of one cycle extrapolated over A = "
                       f"{float(extrapolation):g} cycles rests on impacts that change from "
                       "cycle to cycle; check with --method error or a smaller A")
    return out


def default_constant_a(cycles, target_dynamic):
    return max(1.0, float(math.ceil(cycles / target_dynamic)))
