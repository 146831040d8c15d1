"""``diffwear run FILE.toml``: simulate a loaded `MechanismFile` and write its outputs.

The motion and the wear come from `diffwear.mechanism_file`; this module checks
the options, writes the files and the report.  Outputs in the results folder:

    summary.json          key numbers (written last: marks a finished run)
    report.md             what was run and what came out, linking the rest
    trajectory.csv        t_s, then <body>_x_m, <body>_y_m, <body>_phi_rad for every body,
                          then <body>_vx_m_s, <body>_vy_m_s, <body>_omega_rad_s
    reaction_<joint>.csv  t_s, fx_N, fy_N, m_Nm: the wrench the joint exerts ON the
                          output's body (global axes; moment about that body's COM)
    contact_<joint>.csv   clearance joints: t_s, force_N (|force| on the bushing body),
                          normal_load_N, theta_rad (contact angle, bushing frame),
                          penetration_m (> 0: in contact)
    trajectory.png, reactions.png
    input.toml            copy of the mechanism file
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from .. import plots
from ..choices import WEAR_METHODS
from ..config import MechanismFile
from ..errors import InputError, SolverError
from ..io import OutputDir, Outputs
from ..mechanism import Mechanism
from ..mechanism_file import (
    Results,
    Settling,
    check_motion,
    check_size,
    check_step_budget,
    contact_warnings,
    initial_state,
    integrate_timed,
    motion_integrator,
    postprocess,
    settled_part,
    size,
    start_up_transient,
)
from ..mechanism_file import wear as mechanism_wear
from ..models.execution import Checkpoints
from ..progress import progress_line
from ..report import Block, Bullets, Figure, Report, Section, Table
from ..wear.status import RESULTS, message
from ..wear.status import name as status_name
from . import objects

# Dynamic cycles simulated by a file's dynamic wear run with constant
# extrapolation (A = cycles / this), as the Ch. 7 rig study; the adaptive and
# error-controlled methods get 4x as many scan slots.
FILE_DYNAMIC_CYCLES = 50

# per-joint numbers passed from a model's result into summary.json
_REPORTED = ("contact_margin", "method", "dynamic_cycles", "wall_time_s", "compile_time_s",
             "checkpoint", "resumed_from_cycles")


def _trajectory_columns(mech: Mechanism, r: Results) -> dict:
    cols = {"t_s": r.ts}
    for i, b in enumerate(mech.body_names):
        cols |= {f"{b}_x_m": r.q[:, 3 * i], f"{b}_y_m": r.q[:, 3 * i + 1],
                 f"{b}_phi_rad": r.q[:, 3 * i + 2]}
    for i, b in enumerate(mech.body_names):
        cols |= {f"{b}_vx_m_s": r.qd[:, 3 * i], f"{b}_vy_m_s": r.qd[:, 3 * i + 1],
                 f"{b}_omega_rad_s": r.qd[:, 3 * i + 2]}
    return cols


def write(mfile: MechanismFile, r: Results, out: OutputDir, *, steps: int, simulate_time: float,
          input_text: str | None = None, started: float | None = None,
          wear: dict | None = None, compile_time: float = 0.0,
          stopped: str | None = None) -> dict:
    """Write every output file; returns the summary (also ``summary.json``).
    ``simulate_time``: the motion's integration [s], ``compile_time`` [s]
    included.  ``stopped``: why the integration ended before the duration
    (``r`` then holds the states reached); everything is written, then the run
    fails with `SolverError`."""
    mech, sim = mfile.mechanism, mfile.simulation
    transient = start_up_transient(mfile, r)
    settled = settled_part(r.ts, transient)
    # every number first, then every file (`Outputs`); the wear's files first
    files = Outputs()
    if wear is not None:
        files.extend(wear["outputs"])
    if input_text is not None:
        files.text("input.toml", input_text)
    files.csv("trajectory.csv", _trajectory_columns(mech, r))
    by_joint = {c.name: float(np.max(np.abs(r.violation[:, mech.constraint_rows(c.name)])))
                for c in mech.constraints}
    reactions = {}
    for o in mfile.reactions:
        w = r.reactions[o.joint]
        name = files.csv(f"reaction_{o.joint}.csv",
                         {"t_s": r.ts, "fx_N": w[:, 0], "fy_N": w[:, 1], "m_Nm": w[:, 2]})
        reactions[o.joint] = {
            "on_body": o.on,
            "max_force_N": float(np.max(np.hypot(w[:, 0], w[:, 1]))),
            "max_abs_moment_Nm": float(np.max(np.abs(w[:, 2]))),
            "settled_max_force_N": _settled(np.hypot(w[:, 0], w[:, 1]), settled, transient),
            "settled_max_abs_moment_Nm": _settled(np.abs(w[:, 2]), settled, transient),
            "file": name,
        }
    contacts = {}
    warnings = []
    for co in mfile.contacts:
        h = r.contacts[co.joint]
        name = files.csv(f"contact_{co.joint}.csv",
                         {"t_s": r.ts, "force_N": h[:, 0], "normal_load_N": h[:, 1],
                          "theta_rad": h[:, 2], "penetration_m": h[:, 3]})
        contacts[co.joint] = {
            "max_force_N": float(np.max(h[:, 0])),
            "max_penetration_m": float(np.max(h[:, 3])),
            "settled_max_force_N": _settled(h[:, 0], settled, transient),
            "settled_max_penetration_m": _settled(h[:, 3], settled, transient),
            "fraction_in_contact": float(np.mean(h[:, 3] > 0)),
            "file": name,
        }
        warnings += contact_warnings(mech.element(co.joint), contacts[co.joint])

    # angles drawn in degrees; a body's coordinate that stays zero (a slider's
    # y and phi) is left out by the figure and named in its title
    panels = [(f"{c} [{u}]", {b: r.q[:, 3 * i + k] * scale
                               for i, b in enumerate(mech.body_names)})
              for k, (c, u, scale) in enumerate((("x", "m", 1.0), ("y", "m", 1.0),
                                                 ("φ", "deg", 180 / math.pi)))]
    if r.violation.shape[1]:
        panels.append(("max |Φ| [m, rad]", {"all constraints": np.max(np.abs(r.violation),
                                                                      axis=1)}))
    title = mfile.title or mfile.file
    figures = [files.figure("trajectory.png", lambda path: plots.stacked(
        path, r.ts, panels, xlabel="time [s]", logy=[False, False, False, True][: len(panels)],
        title=f"{title}: body coordinates"))]
    if mfile.reactions:
        forces = [("|F| [N]", {f"{o.joint} on {o.on}": np.hypot(r.reactions[o.joint][:, 0],
                                                                r.reactions[o.joint][:, 1])
                               for o in mfile.reactions}),
                  ("M about COM [N m]", {f"{o.joint} on {o.on}": r.reactions[o.joint][:, 2]
                                         for o in mfile.reactions})]
        figures.append(files.figure("reactions.png", lambda path: plots.stacked(
            path, r.ts, forces, xlabel="time [s]", title=f"{title}: joint reactions")))

    wall = time.perf_counter() - started if started is not None else simulate_time
    summary = {
        "file": mfile.file,
        "title": mfile.title,
        "duration_s": sim.duration,
        "n_save": sim.n_save,
        "max_constraint_violation": max(by_joint.values(), default=0.0),
        "max_constraint_violation_by_joint": by_joint,
        "reactions": reactions,
        "contacts": contacts,
        "start_up_transient": {
            "settled": transient.settled, "length_s": transient.time_s,
            **({"why_not_settled": transient.why} if not transient.settled else {})},
        "integrator": motion_integrator(mech),
        "integrator_steps": steps,
        "simulate_time_s": simulate_time,
        "wall_time_s": wall,
        "files": sorted(set(out.files) | set(files.names)) + ["report.md", "summary.json"],
        "warnings": [w for w, _ in warnings] + (wear["warnings"] if wear else []),
    }
    if wear is not None:
        summary["joints"] = wear["joints"]
        # the dynamic wear model compiles its own program (the quasi-static one's
        # compilation is within its run)
        compile_time += max((w.get("compile_time_s", 0.0) for w in wear["joints"].values()),
                            default=0.0)
        if wear["stopped"]:
            summary["wear_stopped"] = wear["stopped"]
        figures.append(wear["figure"])
        figures += [f"film_{j}.png" for j, w in wear["joints"].items() if "lubricant" in w]
    if stopped is not None:
        summary["stopped"] = {"at_time_s": float(r.ts[-1]), "reason": stopped}
        warnings.append((f"the integration stopped at t = {r.ts[-1]:.6g} s of "
                         f"{sim.duration:g} s: {stopped}", True))
    summary["compile_time_s"] = compile_time
    summary["run_time_s"] = wall - compile_time
    report = _report(mfile, summary, figures)
    files.report("report.md", report)
    out.write(files)
    out.json("summary.json", summary)
    fatal = [w for w, is_fatal in warnings if is_fatal]
    if fatal:  # the outputs are written; the run is reported as failed
        raise SolverError(f"{mfile.file}: {fatal[0]} (results written to {out.path})")
    return summary


def _settled(values: np.ndarray, settled: np.ndarray, transient: Settling) -> float | None:
    """The maximum after the start-up transient; None for a run that did not
    settle (its maxima are the whole run's)."""
    return float(np.max(values[settled])) if transient.settled else None


def _transient_text(s: dict, duration: float) -> str:
    """What the run's start-up transient was, and so which maxima the tables give."""
    t = s["start_up_transient"]
    if not t["settled"]:
        return (f"**Start-up transient: the run did not settle** ({t['why_not_settled']}); every "
                "maximum below is over the whole run, incl. the start-up transient.")
    head = (f"Start-up transient: {t['length_s']:.4g} s of the {duration:g} s run.  A run starts "
            "from its assembly state, not from the motion the drivers force (a clearance "
            "joint's pin starts centred and falls across the clearance); the forces reported "
            "below ring and then settle onto the forced motion.  The transient ends when every "
            "reported force stays in a band about its smoothed course: 1 % of the force's "
            "largest value, or twice its roughness over the run's last quarter if that is "
            "larger (`diffwear.mechanism_file.transient`). ")
    return head + ("The maxima are over the settled part (from "
                   f"t = {t['length_s']:.4g} s on); the columns marked \"whole run\" include "
                   "the start-up transient." if t["length_s"] > 0 else
                   "No transient: the maxima are over the whole run.")


def _max_cells(settled: float | None, whole: float, fmt: str, has_transient: bool) -> tuple:
    """A maximum's table cells: settled, then whole run where they differ in meaning."""
    if not has_transient:
        return (format(whole, fmt),)
    return (format(settled, fmt), format(whole, fmt))


def _run_time_meaning(s: dict) -> str:
    """What the report's run time covers (the quasi-static wear model's
    compilation is not timed apart: it falls in the run time)."""
    joints = s.get("joints") or {}
    if not joints:
        return "the rest of the run: the motion, files and figures"
    untimed = any("compile_time_s" not in w for w in joints.values())
    return ("the rest of the run: the motion, the wear"
            + (" (its model's compilation included)" if untimed else "")
            + ", files and figures")


def _compiled_wear(s: dict) -> str:
    """" and the quasi-static wear model": the wear models whose compilation
    the compile time holds (those that ran and were timed)."""
    timed = sorted({w["model"] for w in (s.get("joints") or {}).values()
                    if "compile_time_s" in w})
    return f" and the {'/'.join(timed)} wear model" if timed else ""


def _report(mfile: MechanismFile, s: dict, figures: list[str]) -> Report:
    mech, sim = mfile.mechanism, mfile.simulation
    t = s["start_up_transient"]
    split = bool(t["settled"] and t["length_s"] > 0)  # a settled part shorter than the run
    settled_word = " after the transient" if split else (
        " (whole run)" if not t["settled"] else "")
    whole = " whole run, incl. the start-up transient"
    blocks: list[Block] = [
        f"Mechanism file: `{mfile.file}` (copy: [input.toml](input.toml))."
        + (f"  Source of the numbers: {mfile.source}." if mfile.source else ""),
        f"{len(mech.bodies)} bodies ({', '.join(mech.body_names)}), "
        f"{len(mech.constraints)} joints ({', '.join(c.name for c in mech.constraints) or '-'}), "
        f"{len(mech.forces)} force elements ({', '.join(f.name for f in mech.forces) or '-'}); "
        f"{mech.n_coords} coordinates, {mech.n_constraints} constraint rows.",
        f"Simulated 0 .. {sim.duration:g} s ({sim.n_save} saved states) with "
        f"{s['integrator']}, PID step "
        f"control (rtol {sim.rtol:g}, atol {sim.atol:g}), Baumgarte alpha = "
        f"{sim.baumgarte_alpha:g} 1/s, beta = {sim.baumgarte_beta:g} 1/s."
        + (" Rodas4 (linearly implicit, L-stable) because of the lubricated joint: its oil "
           "film's squeeze damping would hold an explicit integrator at sub-microsecond "
           "steps; each saved state is the end of a step." if s["integrator"] == "Rodas4"
           else ""),
        Table(("quantity", "value", "meaning"), [
            ("max constraint violation",
             f"{s['max_constraint_violation']:.3e} (m; rad for angle rows)",
             "largest residual of the joint equations over the whole run: how far the "
             "integrated bodies drift from where the joints hold them"),
            ("integrator steps", s["integrator_steps"],
             f"steps of the {s['integrator']} integrator over the run"),
            ("start-up transient",
             f"{t['length_s']:.4g} s" if t["settled"] else "did not settle",
             "time the reported forces take to settle onto the forced motion (below)"),
            ("compile time", f"{s['compile_time_s']:.2f} s",
             "compiling the motion's integrator" + _compiled_wear(s)),
            ("run time", f"{s['run_time_s']:.2f} s", _run_time_meaning(s))]),
        _transient_text(s, sim.duration),
    ]
    if s.get("stopped"):
        stop = s["stopped"]
        blocks.insert(0, Section("Stopped early", [
            f"**The integration stopped at t = {stop['at_time_s']:.6g} s of the "
            f"{sim.duration:g} s asked for**: {stop['reason']}  The tables, files and "
            "figures below hold the states up to there (a wear run needs the whole motion: "
            "its wear was not computed)."]))
    if s["reactions"]:
        blocks.append(Section("Joint reactions", [
            "Wrench the joint exerts **on** the named body: force in global axes, moment about "
            "that body's centre of mass (for a driver: the driving torque).  max abs(F): the "
            "largest magnitude of the force; max abs(M): the largest magnitude of the moment.",
            Table(("joint", "on body", f"max abs(F) [N]{settled_word}",
                   *((f"max abs(F) [N],{whole}",) if split else ()),
                   f"max abs(M) [N m]{settled_word}",
                   *((f"max abs(M) [N m],{whole}",) if split else ()), "file"),
                  [(j, r["on_body"],
                    *_max_cells(r["settled_max_force_N"], r["max_force_N"], ".4g", split),
                    *_max_cells(r["settled_max_abs_moment_Nm"], r["max_abs_moment_Nm"], ".4g",
                                split),
                    f"[{r['file']}]({r['file']})") for j, r in s["reactions"].items()])]))
    if s["contacts"]:
        blocks.append(Section("Clearance joints", [
            "Contact force on the bushing body.  Penetration: how far the pin's surface "
            "overlaps the bushing's (the contact's elastic deformation; > 0 means contact).  "
            "In contact: the share of the saved states with penetration > 0, over the whole run.",
            Table(("joint", f"max abs(F) [N]{settled_word}",
                   *((f"max abs(F) [N],{whole}",) if split else ()),
                   f"max penetration [m]{settled_word}",
                   *((f"max penetration [m],{whole}",) if split else ()), "in contact", "file"),
                  [(j, *_max_cells(c["settled_max_force_N"], c["max_force_N"], ".4g", split),
                    *_max_cells(c["settled_max_penetration_m"], c["max_penetration_m"], ".3e",
                                split),
                    f"{100 * c['fraction_in_contact']:.1f} %", f"[{c['file']}]({c['file']})")
                   for j, c in s["contacts"].items()])]))
    if s.get("joints"):
        models = "/".join(sorted({w["model"] for w in s["joints"].values()}))
        blocks.append(Section(f"Wear ({models} model)", [
            "Every clearance joint with a wear law, over the cycles given (one cycle: one "
            "revolution of the first driver).  Max depth: the deepest point of the worn "
            "bushing profile; volume: the material worn off the bushing; cycles to limit: the "
            "cycles until the max depth reaches the given limit.",
            Table(("joint", "cycles", "max depth [mm]", "volume [mm^3]", "cycles to limit",
                   "files"),
                  [(j, f"{w['cycles']:,.0f}", f"{w['max_wear_depth_mm']:.4g}",
                    f"{w['wear_volume_mm3']:.4g}", _to_limit(w),
                    f"[profile](wear_profile_{j}.csv), [history](wear_history_{j}.csv)")
                   for j, w in s["joints"].items()]),
            Bullets([f"stopped: {why}" for why in s.get("wear_stopped", [])], strong=True)]))
    lubricated = {j: w for j, w in (s.get("joints") or {}).items() if "lubricant" in w}
    if lubricated:
        blocks.append(_lubrication_section(lubricated))
    if s.get("warnings"):
        blocks.append(Section("Warnings", [Bullets(s["warnings"], strong=True)]))
    blocks.append(Section("Files", [Bullets([
        "[summary.json](summary.json): the numbers above",
        "[trajectory.csv](trajectory.csv): t_s; every body's x_m, y_m, phi_rad (centre of "
        "mass), then vx_m_s, vy_m_s, omega_rad_s"]), *(Figure(f) for f in figures)]))
    return Report(mfile.title or str(mfile.file), blocks)


def regime(ratio: float) -> str:
    """The lubrication regime of a minimum film parameter lambda = h_min / sigma
    (Hamrock, Schmid & Jacobson: > 3 full film, 1-3 mixed, < 1 boundary)."""
    if ratio > 3.0:
        return ("full film: the oil carries the whole load and the surfaces never touch, "
                "so the bushing does not wear")
    if ratio >= 1.0:
        return ("mixed: film and asperities share the load; the bushing wears where the "
                "asperities touch, less than dry")
    return ("boundary: the film is thinner than the roughness where it is thinnest; there the "
            "asperities carry most of the load and the bushing wears")


def _lubrication_section(joints: dict) -> Section:
    rows = []
    for j, w in joints.items():
        lube = w["lubricant"]
        worst = min(w["film_ratio_min"], w["film_ratio_min_worn"])
        rows.append((j, f"{lube['viscosity_Pa_s']:.4g}", f"{lube['roughness_um']:.3g}",
                     f"{w['min_film_thickness_um']:.3g} / {w['min_film_thickness_um_worn']:.3g}",
                     f"{w['film_ratio_min']:.3g} / {w['film_ratio_min_worn']:.3g}",
                     f"{w['max_interference_um']:.3g} / {w['max_interference_um_worn']:.3g}",
                     f"{100 * w['asperity_load_share']:.3g} % / "
                     f"{100 * w['asperity_load_share_worn']:.3g} %",
                     f"{regime(worst).capitalize()}.", f"[film]({w['film_file']})"))
    return Section("Lubrication", [
        "Lubricated clearance joints: the oil film (the Reynolds film of the joint's "
        "lubricant.bearing: short, long or finite-length) and the "
        "surfaces' asperities share the load.  h min: the thinnest film over the cycle; "
        "lambda = h min / sigma (sigma: the combined RMS roughness); asperity share: the "
        "asperities' part of the load, averaged over the cycle; each on the unworn / the worn "
        "bushing.  lambda > 3: full film, no wear; 1-3: mixed lubrication, wear where the "
        "asperities touch; < 1: boundary lubrication, the asperities carry most of the load "
        "where the film is thinnest.  interference: how far the pin presses the asperities "
        "past the mean surfaces where no gap is left (h min is then 0).  These numbers are "
        "the journal's quasi-static orbit under the cycle's loads (the film with its wedge "
        "and its squeeze as the pin moves, and the asperities, without the pin's inertia: the "
        "quasi-static wear model's), whichever wear model ran.  The dynamic wear model "
        "integrates the pin's motion with its inertia instead (on Rodas4, at a tolerance "
        "scaled by the roughness), so its film and its wear differ from these where the "
        "pin's inertia matters.",
        Table(("joint", "viscosity [Pa s]", "roughness [um]", "h min [um]", "lambda min",
               "interference [um]", "asperity share", "meaning (smallest lambda)", "file"), rows)])


def _to_limit(w: dict) -> str:
    """The report's "cycles to limit" cell of one wearing joint."""
    if w.get("cycles_to_limit") is not None and math.isfinite(w["cycles_to_limit"]):
        return f"{w['cycles_to_limit']:,.0f} (to {w['limit_mm']:g} mm)"
    return f"not within the run's settings (to {w['limit_mm']:g} mm)" if "limit_mm" in w else "-"


def run(mfile: MechanismFile, out_dir: str, *, overwrite: bool = False,
        input_text: str | None = None, cycles: float | None = None,
        limit: float | None = None, model: str = "quasi-static", method: str = "constant",
        resume: bool = False, progress: bool = False, yes: bool = True,
        log: Callable[..., None] = print) -> dict:
    """Assemble, integrate, write; with ``cycles`` also the wear of every
    clearance joint with a wear law (`diffwear.mechanism_file`) on ``model``
    ("quasi-static" or "dynamic", the latter with ``method`` and checkpoints
    in ``out_dir``, which ``resume=True`` continues), and with ``limit`` [m]
    the cycles to that depth.  Bad input fails before ``out_dir`` is touched,
    and so does, unless ``yes``, a file whose compile is estimated beyond the
    compile budget (`diffwear.mechanism_file.size`); a long compile says its
    progress (with ``progress``)."""
    started = time.perf_counter()
    check_step_budget(mfile)
    slow = check_size(mfile, yes=yes)
    if slow is not None:  # said now, before the wait
        print(f"diffwear: warning: {slow}", file=sys.stderr)
    wait = size.estimate(mfile).seconds
    if cycles is None and (resume or model != "quasi-static" or method != "constant"):
        raise InputError("--model, --method and --resume belong to a wear mfile: give "
                         "--cycles N")
    wear_model = None
    if cycles is not None:
        check_wear_options(model, method, resume)
        # a file's dynamic run: about `FILE_DYNAMIC_CYCLES` dynamic cycles
        wear_model = objects.wear_model(model, cycles=cycles, method=method,
                                        target_dynamic=FILE_DYNAMIC_CYCLES)
        mechanism_wear.check_wear(mfile, wear_model, limit=limit,
                                  resume_folder=out_dir if resume else None)
    y0 = initial_state(mfile)
    check_motion(mfile, y0)
    out = OutputDir(out_dir, overwrite=overwrite, resume=resume)
    log(f"[{mfile.file}] integrating {mfile.simulation.duration:g} s (first run compiles) ...")
    # a motion the integrator cannot finish is written up to where it stopped
    if slow is not None and progress:  # a long compile: a line now and then, never silence
        with progress_line("compiling and integrating", wait):
            timed = integrate_timed(mfile, y0, partial=True)
    else:
        timed = integrate_timed(mfile, y0, partial=True)
    traj = timed.trajectory
    results = postprocess(mfile, traj)
    wear = None
    if cycles is not None and timed.failure is None:
        log(f"[{mfile.file}] wear over {cycles:,.0f} cycles ({model} model) ...")
        evolved = mechanism_wear.evolve_file(
            mfile, y0, cycles=cycles, limit=limit,
            model=None if model == "quasi-static" else wear_model,
            checkpoints=Checkpoints(out, {}, resume=resume, progress=progress))
        wear = wear_outputs(mfile, evolved, limit=limit)
    summary = write(mfile, results, out, steps=int(traj.num_steps),
                    simulate_time=timed.compile_time_s + timed.run_time_s,
                    compile_time=timed.compile_time_s, input_text=input_text, started=started,
                    wear=wear, stopped=None if timed.failure is None
                    else timed.failure.removeprefix(f"{mfile.file}: "))
    for w in summary["warnings"]:
        print(f"diffwear: warning: {w}", file=sys.stderr)
    log(f"[{mfile.file}] max constraint violation {summary['max_constraint_violation']:.2e}; "
        f"report: {out.path / 'report.md'}")
    if wear is not None and wear["stopped"]:
        raise SolverError(f"{mfile.file}: " + "; ".join(wear["stopped"])
                          + f"; stopped, results so far written to {out.path}")
    return summary


def wear_outputs(mfile: MechanismFile, wear: dict, *, limit: float | None) -> dict:
    """The wear's files (``outputs``: CSV files per joint and one figure,
    ``figure``) and the summary's ``joints`` and ``warnings``, and
    ``stopped``: a sentence per joint that wore through its wall or whose
    model failed (the caller reports them as a failure once everything is
    written)."""
    files = Outputs()
    joints, warnings, pierced = {}, [], []
    for name, w in wear.items():
        files.csv(f"wear_profile_{name}.csv",
                  {"theta_rad": w["theta"], "depth_mm": w["depth"] * 1e3})
        files.csv(f"wear_history_{name}.csv", {"cycles": w["history_cycles"],
                                               "max_depth_mm": w["history_peak"] * 1e3})
        joints[name] = {"max_wear_depth_mm": float(np.max(w["depth"])) * 1e3,
                        "wear_volume_mm3": w["volume"] * 1e9, "cycles": w["cycles"],
                        "model": w["model"], "status": status_name(w["status"]),
                        **{k: w[k] for k in _REPORTED if k in w}}
        if limit is not None:
            joints[name]["limit_mm"] = limit * 1e3
            joints[name]["cycles_to_limit"] = w["cycles_to_limit"]
        if w["status"] == RESULTS.contact_lost:
            warnings.append(f"clearance joint {name!r}: the load cannot hold the pin on the "
                            f"bushing wall (contact margin {w['contact_margin']:.2g} < 1): the "
                            "quasi-static wear model does not hold there")
        elif w["status"] == RESULTS.wall_reached:
            pierced.append(f"clearance joint {name!r} wore through its {w['wall'] * 1e3:g} mm "
                           f"bushing wall after {w['cycles']:,.0f} cycles (max depth "
                           f"{joints[name]['max_wear_depth_mm']:.4f} mm)")
        elif w["status"] != RESULTS.ok:
            causes = w["causes"]
            pierced.append(f"the wear of clearance joint {name!r} stopped after "
                           f"{w['cycles']:,.0f} cycles: "
                           f"{message(w['status'])}"
                           + (f"; likely cause: {'; and '.join(causes)}" if causes else ""))
        elif w.get("contact_margin_worn", math.inf) < 1.0:
            warnings.append(f"clearance joint {name!r}: on the worn profile the pin may lift "
                            f"off the wall (contact margin {w['contact_margin_worn']:.2g})")
        if "film" in w:
            joints[name] |= _film_outputs(mfile, files, name, w["film"])
            if w["film"].get("out_of_range"):
                warnings.append(f"clearance joint {name!r}: {w['film']['out_of_range']}")
            soft = _soft_bore(w["film"]["unworn"])
            joints[name]["rigid_bore_film_holds"] = soft is None
            if soft:
                warnings.append(f"clearance joint {name!r}: {soft}")
            if not (w["film"]["loads_ok"] and w["film"]["unworn"]["ok"]
                    and w["film"]["worn"]["ok"]):
                warnings.append(f"clearance joint {name!r}: the film's equilibrium did not "
                                "converge at every sample of the cycle: its film numbers are "
                                "not reliable")
    models = "/".join(sorted({w["model"] for w in wear.values()}))
    title = plots.wear_title(mfile.title or str(mfile.file),
                             {n: w["cycles"] for n, w in wear.items()},
                             {n: w["status"] for n, w in wear.items()}, model=models)
    figure = files.figure("wear.png", lambda path: plots.wear_panels(
        path, {n: (w["theta"], w["depth"]) for n, w in wear.items()},
        {n: (w["history_cycles"], w["history_peak"]) for n, w in wear.items()}, title=title,
        walls={n: w["wall"] for n, w in wear.items()}, limit=limit,
        lives={n: w["cycles_to_limit"] for n, w in wear.items()}))
    return {"joints": joints, "warnings": warnings, "figure": figure, "stopped": pierced,
            "outputs": files}


# The rigid-bore film holds where the bore's deflection under the film's peak
# pressure is at most a quarter of the film thickness there (a deflection of
# that size changes the film's h^3 flow by ~2 x): a stated, conservative bound.
SOFT_BORE_LIMIT = 0.25


def _soft_bore(f: dict) -> str | None:
    """A sentence where the bore's deflection under the peak film pressure
    (p / k_f, the foundation's stiffness) is more than `SOFT_BORE_LIMIT` of the
    film thickness at some sample of the cycle, else None."""
    h, d, p = f["min_film_thickness"], f["bore_deflection"], f["film_peak_pressure"]
    worst = int(np.argmax(d - SOFT_BORE_LIMIT * h))
    if d[worst] <= SOFT_BORE_LIMIT * h[worst]:
        return None
    against = (f"against a film of {h[worst] * 1e6:.3g} um (more than {SOFT_BORE_LIMIT:g} "
               "of it)" if h[worst] > 0.0 else "where no film is left (the asperities touch)")
    return (f"soft bore: the film's peak pressure {p[worst] / 1e6:.3g} MPa deflects the bore "
            f"by {d[worst] * 1e6:.3g} um {against}: the rigid-bore film is not "
            "self-consistent there, its numbers are those of a rigid bore")


def _film_outputs(mfile: MechanismFile, files: Outputs, name: str, film: dict) -> dict:
    """``film_<joint>.csv`` and ``.png`` of a lubricated joint (its film over
    the cycle, unworn and worn bushing), added to ``files``; returns its
    summary.json keys."""
    cols = {"crank_angle_deg": film["crank_angle_deg"]}
    for case, suffix in (("unworn", ""), ("worn", "_worn")):
        f = film[case]
        cols |= {f"h_min_um{suffix}": f["min_film_thickness"] * 1e6,
                 f"film_ratio{suffix}": f["film_ratio"],
                 f"interference_um{suffix}": f["interference"] * 1e6,
                 f"asperity_share{suffix}": f["asperity_share"],
                 f"film_load_N{suffix}": f["film_load"],
                 f"asperity_load_N{suffix}": f["asperity_load"]}
    files.csv(f"film_{name}.csv", cols)
    title = (f"{mfile.title or mfile.file}: lubricated joint {name} "
             f"(η = {film['viscosity']:g} Pa s, σ = {film['roughness'] * 1e6:.3g} µm), "
             "quasi-static orbit over the cycle, unworn and worn bushing")
    files.figure(f"film_{name}.png", lambda path: plots.film_panels(
        path, film["crank_angle_deg"],
        {case: (film[case]["min_film_thickness"], film[case]["asperity_share"],
                film[case]["interference"]) for case in ("unworn", "worn")},
        onset=film["onset_gap"], onset_ratio=film["onset_ratio"], roughness=film["roughness"],
        title=title))
    keys: dict[str, Any] = {}
    for case, suffix in (("unworn", ""), ("worn", "_worn")):
        f = film[case]
        keys |= {f"min_film_thickness_um{suffix}": float(np.min(f["min_film_thickness"])) * 1e6,
                 f"film_ratio_min{suffix}": float(np.min(f["film_ratio"])),
                 f"max_interference_um{suffix}": float(np.max(f["interference"])) * 1e6,
                 f"peak_film_pressure_MPa{suffix}": float(np.max(f["film_peak_pressure"])) / 1e6,
                 f"max_bore_deflection_um{suffix}": float(np.max(f["bore_deflection"])) * 1e6,
                 f"asperity_load_share{suffix}": float(np.mean(f["asperity_share"]))}
    keys["lubricant"] = {"viscosity_Pa_s": film["viscosity"],
                         "roughness_um": film["roughness"] * 1e6, "bearing": film["bearing"]}
    keys["film_file"] = f"film_{name}.csv"
    return keys


def check_wear_options(model: str, method: str, resume: bool) -> None:
    """`InputError` for a wear model or method that does not exist, or one the
    quasi-static model does not take (it has no extrapolation and no
    checkpoints: it integrates the wear in the cycle count, in seconds)."""
    if method not in WEAR_METHODS:
        raise InputError(f"--method {method!r}; allowed: {', '.join(WEAR_METHODS)}")
    objects.check_wear_model(model, ((method != "constant", f"--method {method}"),
                             (resume, "--resume")))


__all__ = ["check_wear_options", "run", "wear_outputs", "write"]
