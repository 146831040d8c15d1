"""Shared driver of the wear studies (``wear-5000``, ``rig-21400``,
``rig-lubricated``): a `WearStudy` run on any wear model, and its one writer.

The run is `diffwear.models.execution.run_model`'s (compiled once, timed, in
chunks with checkpoints where the model keeps them; the report's words for
the model from `model_words`); the outputs are the same
for every model where they have a meaning: the profile, the history, the
joint force and the pin's locus over the first and the last cycle
(`AbstractWearModel.cycle_histories`), figures, summary and report.  What a
result holds beyond the wear is reported where it has it: the simulated
dynamic cycles and Archard's check (the dynamic models), the contact check
(the quasi-static model).
"""

from __future__ import annotations

import math
import sys
from typing import Any, Callable, NamedTuple

import jax.numpy as jnp
import numpy as np

from ..contact import MixedLubrication, centred_state
from ..dynamics import consistent_state
from ..errors import SolverError
from ..models import AbstractWearModel, Dynamic, WearSolution
from ..models.execution import Checkpoints, RunTimes, run_model
from ..presets import PTFE_DENSITY, WearJointDesign, with_wear_joint
from ..report import Block, Bullets, Report, Table
from ..wear import Constant, CycleSettings, arc_peak_depth, worn_volume
from ..wear.cycle import cycle_integrator
from ..wear.status import RESULTS, message
from ..wear.status import name as status_name
from . import model_words
from ._report import COMPARISON_WORDS, comparison_table, peak_line, write_report

JOINT = "crank_rod"
# Free flight over more than this fraction of a simulated cycle (impacts)
# warns: the wear of one cycle, extrapolated over A cycles, then rests on
# impacts that change from cycle to cycle.
CONTACT_LOSS_WARNING = 0.25


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


class WearStudy(NamedTuple):
    """What a wear study is: its ``name``, the mechanism ``mech_of(p)`` with
    its wear joint of ``design`` (``p``: its traced inputs, `params_of`), the
    state ``y0`` and ``period`` [s] of a cycle, the ``thesis``'s values (for
    ``thesis_cycles`` cycles), the report's ``description`` and what it adds
    to the summary and the report; for the figures, the thesis figures the
    profile compares with (``cf``) and what of the thesis's values the run is
    calibrated to (``calibrated``, words; `diffwear.plots.wear.Lines`)."""

    name: str
    mech_of: Callable
    p: Any
    design: WearJointDesign
    y0: Any
    period: float
    thesis: dict
    description: str
    thesis_cycles: int | None = None
    extra_summary: dict = {}
    extra_report: tuple = ()
    cf: str = ""
    calibrated: str = ""


def run_wear_study(out, study: WearStudy, *, cycles, model: AbstractWearModel, log,
                   resume: bool = False, progress: bool = False) -> dict:
    """The wear of ``study`` over ``cycles`` on ``model``: the run (kept in
    checkpoints in ``out`` where the model keeps them; ``resume`` continues),
    every output, then a run that stopped early raises `SolverError` after
    its results are written.  A model with a reference route (the FEM route:
    the same dynamics with the EFM pressure) runs that first, and the report
    compares both.  The thesis's values are compared only for the cycle
    count they are for."""
    if study.thesis_cycles is not None and study.thesis and int(cycles) != int(
            study.thesis_cycles):
        why = (f"the thesis's values are for {int(study.thesis_cycles):,} cycles and this "
               f"run has {int(cycles):,}: not compared")
        study = study._replace(thesis={}, cf="", calibrated="",
                               extra_report=(*study.extra_report, Bullets([why])),
                               extra_summary={**study.extra_summary,
                                              "thesis_not_compared": why})
    extra_summary, extra_report = dict(study.extra_summary), list(study.extra_report)
    reference = model.reference()
    if reference is not None:
        log(f"[{study.name}] {model_words.label(reference)} for the comparison ...")
        ref, ref_times = _evolve(study, reference, cycles, None)
    settings = model_words.describe(model, cycles)
    log(f"[{study.name}] {cycles} cycles, " + ", ".join(f"{k} {v}" for k, v in settings.items())
        + " ...")
    meta = {"study": study.name, "cycles": float(cycles), **settings,
            "n_theta": int(study.mech_of(study.p).element(JOINT).profile.n)}
    res, times = _evolve(study, model, cycles, Checkpoints(out, meta, resume, progress))
    extra_summary.update(times.info)
    if reference is not None:
        mine = route_numbers(res, study.design, times)
        theirs = route_numbers(ref, study.design, ref_times)
        ratio = times.wall_time / ref_times.wall_time
        tag, ref_tag = settings["contact"], model_words.describe(reference, cycles)["contact"]
        extra_summary.update({f"{tag}_route": {**model_words.route_summary(model, res), **mine},
                              f"{ref_tag}_route": theirs,
                              f"wall_time_ratio_{tag}_to_{ref_tag}": ratio})
        extra_report += route_table(mine, theirs, ratio)
    summary = write_outputs(out, study._replace(extra_summary=extra_summary,
                                                extra_report=tuple(extra_report)),
                            model=model, res=res, cycles=cycles, times=times, log=log)
    if bool(res.result != RESULTS.ok):
        raise SolverError(f"{study.name}: {message(res.result)} after "
                          f"{summary['cycles']:.0f} cycles (max depth "
                          f"{summary['max_wear_depth_mm']:.4f} mm; {model.name} model); "
                          f"stopped, results so far written to {out.path}")
    return summary


def dynamic_model(cycles, target_dynamic: int, integrator: str) -> Dynamic:
    """A study's dynamic model: constant A = ceil(cycles / ``target_dynamic``)
    (about that many dynamic cycles) on the cycle integrator ``integrator``
    (`wear.cycle.CYCLE_INTEGRATORS`, at its tolerance)."""
    solver, tol = cycle_integrator(integrator)
    return Dynamic(extrapolation=Constant(max(1.0, float(math.ceil(cycles / target_dynamic)))),
                   cycle=CycleSettings(rtol=tol, atol=tol, solver=solver),
                   dynamic_cycles=int(target_dynamic))


def _evolve(study: WearStudy, model: AbstractWearModel, cycles, checkpoints):
    return run_model(model, study.mech_of, study.p, (JOINT,), study.y0, period=study.period,
                     cycles=cycles, wall_thickness=study.design.wall, checkpoints=checkpoints)


def route_numbers(res: WearSolution, design: WearJointDesign, times: RunTimes) -> dict:
    """Max depth (on the grid and as the largest +-4 deg mean, `arc_peak_depth`),
    volume, Archard volume (where the model sums the load), times of one
    route's result."""
    depth = res.depth[0]
    out: dict = {"max_wear_depth_mm": float(np.max(np.asarray(depth))) * 1e3,
                 "arc_peak_depth_mm": float(arc_peak_depth(depth)) * 1e3,
                 "wear_volume_mm3": float(worn_volume(depth, design.bushing_radius,
                                                      design.depth)) * 1e9}
    if res.state is not None:  # simulated cycles: their normal load x sliding
        out["archard_k_times_load_sliding_mm3"] = float(
            design.k * res.state.load_sliding[0]) * 1e9
    out.update(dynamic_cycles_simulated=simulated_cycles(res), status=status_name(res.result),
               wall_time_s=times.wall_time, compile_time_s=times.compile_time)
    return out


def simulated_cycles(res: WearSolution) -> int:
    """Dynamic cycles the run simulated (0: none, the quasi-static model)."""
    return int(res.stats.get("dynamic_cycles", 0))


def route_table(mine: dict, reference: dict, ratio: float) -> list[Block]:
    """Report blocks: the FEM route next to the EFM route (both run here)."""
    return [
        "FEM route next to the EFM route (both run here, same dynamics):",
        Table(("route", "max depth [mm]", "max depth, +-4 deg mean [mm]", "volume [mm^3]",
               "k x sum(N ds) [mm^3]", "run time [s]", "compile time [s]"),
              [(tag, f"{d['max_wear_depth_mm']:.4f}", f"{d['arc_peak_depth_mm']:.4f}",
                f"{d['wear_volume_mm3']:.2f}",
                f"{d['archard_k_times_load_sliding_mm3']:.2f}", f"{d['wall_time_s']:.1f}",
                f"{d['compile_time_s']:.1f}") for tag, d in (("FEM", mine), ("EFM", reference))]),
        Bullets([f"run time FEM / EFM route: {ratio:.2f} (thesis: 11 h / 7 h = 1.6 on the "
                 "rig, 162 / 92 min = 1.8 on wear-5000)"])]


def write_outputs(out, study: WearStudy, *, model: AbstractWearModel, res: WearSolution,
                  cycles, times: RunTimes, log) -> dict:
    """Every output of a wear study's run into ``out``: the profile, the
    history, the first and last cycles' joint force and pin locus (CSV),
    figures, summary.json and report.md.  Returns the summary."""
    from ..plots import wear as plots_wear

    mech = study.mech_of(study.p)
    design = study.design
    el = mech.element(JOINT)
    theta = np.asarray(el.profile.theta)
    depth = np.asarray(res.depth[0])
    hist = res.history[0]
    valid = np.asarray(hist.valid).astype(bool)
    steps_n = np.asarray(hist.cycles)[valid]
    steps_depth = np.asarray(hist.depth)[valid]
    volumes = np.asarray(worn_volume(steps_depth, el.bushing_radius, el.law.depth)) * 1e9
    numbers = route_numbers(res, design, times)
    first, last, crank = model.cycle_histories(mech, JOINT, study.y0, period=study.period,
                                               evolution=res)
    crank = np.asarray(crank)

    out.csv("wear_profile.csv", {"theta_rad": theta, "depth_mm": depth * 1e3})
    out.csv("wear_history.csv", {"cycles": steps_n,
                                 "max_depth_mm": steps_depth.max(axis=1) * 1e3,
                                 "volume_mm3": volumes, **_simulated_columns(res)})
    for tag, h in (("first", first), ("last", last)):
        f = np.asarray(h.force)
        out.csv(f"joint_force_{tag}_cycle.csv", {
            "crank_angle_rad": crank, "fx_N": f[:, 0], "fy_N": f[:, 1],
            "force_N": np.hypot(f[:, 0], f[:, 1]), "normal_load_N": np.asarray(h.normal_load)})
        off = np.asarray(h.offset)
        out.csv(f"contact_locus_{tag}_cycle.csv", {
            "crank_angle_rad": crank, "offset_x_mm": off[:, 0] * 1e3,
            "offset_y_mm": off[:, 1] * 1e3, "contact_angle_rad": np.asarray(h.contact_angle),
            "penetration_um": np.asarray(h.penetration) * 1e6})
    figs = plots_wear.wear_figures(out, name=study.name, theta=theta, depth_mm=depth * 1e3,
                                   history=(steps_n[1:], steps_depth.max(axis=1)[1:] * 1e3,
                                            volumes[1:]),
                                   crank=crank, first=first, last=last, thesis=study.thesis,
                                   lines=plots_wear.Lines(
                                       clearance_mm=float(design.clearance) * 1e3,
                                       wall_mm=float(design.wall) * 1e3,
                                       label=model_words.label(model),
                                       markers=model_words.step_words(model), status=res.result,
                                       cf=study.cf, calibrated=study.calibrated))
    settings = model_words.describe(model, cycles)
    summary = {
        "study": study.name, "cycles": float(res.cycles), "cycles_requested": float(cycles),
        **{k: v for k, v in numbers.items()
           if k not in ("wall_time_s", "compile_time_s", "arc_peak_depth_mm")},
        "status_text": message(res.result),
        "wall_time_s": times.wall_time, "compile_time_s": times.compile_time,
        "max_wear_angle_rad": float(theta[np.argmax(depth)]),
        "worn_mass_g": numbers["wear_volume_mm3"] * 1e-9 * PTFE_DENSITY * 1e3,
        **settings,
        "mean_joint_force_first_cycle_N": float(np.mean(np.asarray(first.force_magnitude))),
        "mean_normal_load_first_cycle_N": float(np.mean(np.asarray(first.normal_load))),
        "n_theta": int(depth.size), "thesis": study.thesis, **study.extra_summary}
    margins = (float(res.contact_margin[0]), float(res.contact_margin_worn[0]))
    checked = bool(np.isfinite(margins[0]))
    if checked:
        summary.update(contact_margin=margins[0], contact_margin_worn=margins[1],
                       wear_steps=int(valid.sum()) - 1)
    warnings = []
    if res.slots is not None:
        warnings += contact_loss_warnings({"first": first, "last": last},
                                          settings.get("extrapolation", 1.0))
    if checked and margins[1] < 1.0:
        warnings.append(f"at the final profile the load may not hold the pin on the wall "
                        f"where it turns fastest (contact margin {margins[1]:.2f} < 1); "
                        "check with the dynamic model (--model dynamic)")
    if warnings:
        summary["warnings"] = warnings
    summary["files"] = sorted(set(out.files)) + ["report.md", "summary.json"]
    report = Report(study.name, [
        study.description,
        *_result_words(res, el),
        comparison_table(model_words.label(model), summary, study.thesis),
        COMPARISON_WORDS,
        Bullets([*_run_words(summary, res, times), peak_line(summary),
                 *_contact_words(summary, res, checked)]),
        *study.extra_report,
        Bullets([f"warning: {w}" for w in warnings])])
    write_report(out, report, figs, summary)
    for w in warnings:
        print(f"diffwear: warning: {study.name}: {w}", file=sys.stderr)
    log(f"[{study.name}] {model.name}: max depth {summary['max_wear_depth_mm']:.4f} mm, "
        f"volume {summary['wear_volume_mm3']:.2f} mm^3, "
        f"{summary['dynamic_cycles_simulated']} dynamic cycles, {times.wall_time:.2f} s "
        f"(+{times.compile_time:.1f} s compile)")
    return summary


def _simulated_columns(res: WearSolution) -> dict:
    """The history's extrapolation and dynamic cycles per step, where the
    model simulates cycles (the first row: the warm-up)."""
    if res.slots is None:
        return {}
    h = {k: np.asarray(v) for k, v in res.slots.items()}
    valid = h["valid"].astype(bool)
    return {"extrapolation": np.concatenate([[0.0], h["extrapolation"][valid]]),
            "dynamic_cycles": np.concatenate([[1], h["dynamic_cycles"][valid]])}


def _result_words(res: WearSolution, el) -> list[str]:
    if res.slots is not None:
        return []
    return ["Model: quasi-static joint (the pin at the equilibrium of "
            + ("the oil film and the asperities (the EFM springs at the summit height)"
               if isinstance(el.law, MixedLubrication) else "the EFM springs")
            + " under the ideal mechanism's joint load; wear integrated in the cycle count)."]


def _integrator_label(name: str) -> str:
    """E.g. "Tsit5, rtol = atol = 1e-06" for a `wear.cycle.CYCLE_INTEGRATORS` name."""
    solver, tol = cycle_integrator(name)
    return f"{type(solver).__name__}, rtol = atol = {tol:g}"


def _run_words(s: dict, res: WearSolution, times: RunTimes) -> list[str]:
    if res.slots is None:
        return [f"cycles: {s['cycles']:.0f} in {s['wear_steps']} steps of the wear ODE (the "
                "profile's growth integrated over the cycle count by an adaptive solver); "
                f"status: {s['status_text']}",
                f"run time {times.wall_time:.2f} s (the compiled wear evolution), compile "
                f"time {times.compile_time:.1f} s (compiling it)"]
    return [
        f"cycles: {s['cycles']:.0f}; dynamic cycles simulated: "
        f"{s['dynamic_cycles_simulated']} (incl. 1 warm-up cycle whose wear is "
        f"discarded); method {s['method']}, extrapolation A = {s['extrapolation']:g} (the "
        "wear of one simulated cycle stands for A cycles; with --method adaptive or error, "
        "the first A, which the method then changes)",
        f"Archard check: k x sum(N ds) = {s['archard_k_times_load_sliding_mm3']:.3f} "
        "mm^3 (the wear coefficient times the normal load integrated over the sliding "
        "distance, summed over the cycles, each simulated one counted A times: Archard's "
        "law for the whole volume, to compare with the wear volume above)",
        f"mean |joint force| first cycle {s['mean_joint_force_first_cycle_N']:.1f} N "
        "(the magnitude of the joint's contact force averaged over the first cycle after "
        f"the warm-up), mean total normal load {s['mean_normal_load_first_cycle_N']:.1f}"
        " N (the bushing's pressure integrated over the contact arc, averaged the same way: "
        "above the joint force because the pressure spreads over an arc)",
        f"run time {times.wall_time:.1f} s (the compiled wear evolution), compile time "
        f"{times.compile_time:.1f} s (compiling it); dynamic cycles on "
        f"{_integrator_label(s.get('integrator', 'tsit5'))}"]


def _contact_words(s: dict, res: WearSolution, checked: bool) -> list[str]:
    if not checked:
        return []
    return [
        f"contact margin: unworn {s['contact_margin']:.3g}, final profile "
        f"{s['contact_margin_worn']:.3g}.  The smallest over the cycle of the joint load "
        "divided by m c omega^2, the inward force the pin (effective mass m) needs to follow "
        "the load around a wall of clearance c as the load turns at omega: above 1 the load "
        "holds the pin on the wall, below 1 the pin may fly across the clearance and this "
        "model does not hold; a huge value means the load's direction hardly turns",
        f"mean |joint force| {s['mean_joint_force_first_cycle_N']:.1f} N (the magnitude of "
        "the joint's load averaged over a cycle); mean total normal load (unworn) "
        f"{s['mean_normal_load_first_cycle_N']:.1f} N (the bushing's pressure integrated "
        "over the contact arc, averaged over a cycle: above the joint force because the "
        "pressure spreads over an arc)",
        "the first- and last-cycle joint force curves (joint_force_first/last_cycle.csv, "
        "contact_locus_and_force.png) are the same: this model takes the joint load from "
        "the ideal mechanism, which the wear does not change; the normal load and the "
        "pin's locus do change with the worn profile"]


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
