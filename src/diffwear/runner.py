"""``diffwear run FILE.toml``: simulate a loaded `Study` and write its outputs.

Stages, each with its own error class so that the CLI's exit code says which
one failed: `initial_state` (assembly; `InputError`), `integrate`
(`SolverError`), `write` (files).  Outputs in the results folder:

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

import functools
import math
import sys
import time
from collections.abc import Callable
from typing import NamedTuple

import equinox as eqx
import jax
import numpy as np

from . import plots
from .choices import WEAR_METHODS, WEAR_MODELS
from .config import Study
from .config.study import Simulation
from .contact import centred_state, contact_history
from .dynamics import (
    along_trajectory,
    check_assembly,
    consistent_state,
    reaction_wrench,
    simulate,
)
from .dynamics.kinematics import check_cycle_motion
from .dynamics.simulate import Trajectory
from .errors import InputError, SolverError
from .io import OutputDir
from .mechanism import Mechanism
from .mechanism.constraints import Driver
from .quasistatic.loads import fully_driven, ideal_parent

_consistent_state = eqx.filter_jit(functools.partial(consistent_state, check=False))


def initial_state(study: Study):
    """Consistent y0 = [q, qd, aux] at t = 0 from the file's ``[initial]`` guess;
    `InputError` if the mechanism does not assemble near it.

    Same result as ``consistent_state(mech, q_guess)`` but compiled (the eager
    Newton iteration costs seconds); the check then runs on concrete values.
    With clearance joints the assembly is that of ``study.assembly`` (each one
    an ideal revolute at the same points): the pins start centred with the
    ideal joints' velocities, and the contact states at their initial values.
    """
    mech = study.mechanism if study.assembly is None else study.assembly
    y0 = _consistent_state(mech, study.q_guess)
    finite = bool(np.all(np.isfinite(np.asarray(y0))))
    try:
        check_assembly(mech, y0[: mech.n_coords], finite, q_guess=study.q_guess)
    except InputError as err:
        raise InputError(f"{study.file}: initial: {err}") from None
    if study.assembly is None:
        return y0
    return centred_state(mech, y0, study.mechanism)


@eqx.filter_jit
def _integrate(mech: Mechanism, y0, sim: Simulation) -> Trajectory:
    return simulate(mech, y0, sim.duration, ts=sim.ts(), baumgarte=sim.baumgarte(),
                    stepsize_controller=sim.controller(), max_steps=sim.max_steps)


def integrate(study: Study, y0) -> Trajectory:
    """The study's trajectory; `SolverError` (naming the file) if the solve failed."""
    traj = _integrate(study.mechanism, y0, study.simulation)
    return traj.raise_if_failed(study.file, study.mechanism)


class Results(NamedTuple):
    ts: np.ndarray          # (T,) s
    q: np.ndarray           # (T, n) m / rad
    qd: np.ndarray          # (T, n) m/s / rad/s
    violation: np.ndarray   # (T, m) constraint residuals (m or rad per row)
    reactions: dict         # joint -> (T, 3): fx [N], fy [N], moment about COM [N m]
    contacts: dict = {}     # clearance joint -> (T, 4): |F| [N], normal load [N],
                            #   contact angle [rad], penetration [m]


@eqx.filter_jit
def _contacts(mech: Mechanism, ys, joints):
    out = {}
    for joint in joints:
        h = contact_history(mech, joint, ys)
        out[joint] = jax.numpy.stack([h.force_magnitude, h.normal_load, h.contact_angle,
                                      h.penetration], axis=-1)
    return out


@eqx.filter_jit
def _post(mech: Mechanism, ts, ys, sim: Simulation, outputs):
    _, lam, _ = along_trajectory(mech, ts, ys, sim.baumgarte())
    q, qd, _ = jax.vmap(mech.split)(ys)
    phi = jax.vmap(mech.phi)(q, ts)
    wrenches = {
        o.joint: jax.vmap(lambda qq, ll, t, o=o: reaction_wrench(mech, qq, ll, t, o.joint, o.on))(
            q, lam, ts)
        for o in outputs
    }
    return q, qd, phi, wrenches


def postprocess(study: Study, traj: Trajectory) -> Results:
    q, qd, phi, wrenches = _post(study.mechanism, traj.ts, traj.ys, study.simulation,
                                 study.reactions)
    contacts = _contacts(study.mechanism, traj.ys, tuple(o.joint for o in study.contacts))
    return Results(np.asarray(traj.ts), np.asarray(q), np.asarray(qd), np.asarray(phi),
                   {k: np.asarray(v) for k, v in wrenches.items()},
                   {k: np.asarray(v) for k, v in contacts.items()})


# ----------------------------------------------------------------------------- files
def _trajectory_columns(mech: Mechanism, r: Results) -> dict:
    cols = {"t_s": r.ts}
    for i, b in enumerate(mech.body_names):
        cols |= {f"{b}_x_m": r.q[:, 3 * i], f"{b}_y_m": r.q[:, 3 * i + 1],
                 f"{b}_phi_rad": r.q[:, 3 * i + 2]}
    for i, b in enumerate(mech.body_names):
        cols |= {f"{b}_vx_m_s": r.qd[:, 3 * i], f"{b}_vy_m_s": r.qd[:, 3 * i + 1],
                 f"{b}_omega_rad_s": r.qd[:, 3 * i + 2]}
    return cols


def write(study: Study, r: Results, out: OutputDir, *, steps: int, simulate_time: float,
          input_text: str | None = None, started: float | None = None,
          wear: dict | None = None) -> dict:
    """Write every output file; returns the summary (also ``summary.json``)."""
    mech, sim = study.mechanism, study.simulation
    if input_text is not None:
        out.text("input.toml", input_text)
    out.csv("trajectory.csv", _trajectory_columns(mech, r))
    by_joint = {c.name: float(np.max(np.abs(r.violation[:, mech.constraint_rows(c.name)])))
                for c in mech.constraints}
    reactions = {}
    for o in study.reactions:
        w = r.reactions[o.joint]
        name = f"reaction_{o.joint}.csv"
        out.csv(name, {"t_s": r.ts, "fx_N": w[:, 0], "fy_N": w[:, 1], "m_Nm": w[:, 2]})
        reactions[o.joint] = {
            "on_body": o.on,
            "max_force_N": float(np.max(np.hypot(w[:, 0], w[:, 1]))),
            "max_abs_moment_Nm": float(np.max(np.abs(w[:, 2]))),
            "file": name,
        }
    contacts = {}
    warnings = []
    for co in study.contacts:
        h = r.contacts[co.joint]
        name = f"contact_{co.joint}.csv"
        out.csv(name, {"t_s": r.ts, "force_N": h[:, 0], "normal_load_N": h[:, 1],
                       "theta_rad": h[:, 2], "penetration_m": h[:, 3]})
        contacts[co.joint] = {
            "max_force_N": float(np.max(h[:, 0])),
            "max_penetration_m": float(np.max(h[:, 3])),
            "fraction_in_contact": float(np.mean(h[:, 3] > 0)),
            "file": name,
        }
        warnings += contact_warnings(mech.element(co.joint), contacts[co.joint])

    panels = [(f"{c} [{u}]", {b: r.q[:, 3 * i + k] for i, b in enumerate(mech.body_names)})
              for k, (c, u) in enumerate((("x", "m"), ("y", "m"), ("φ", "rad")))]
    if r.violation.shape[1]:
        panels.append(("max |Φ| [m, rad]", {"all constraints": np.max(np.abs(r.violation), axis=1)
                                             + 1e-300}))
    figures = [plots.stacked(out.file("trajectory.png"), r.ts, panels, xlabel="time [s]",
                             logy=[False, False, False, True][: len(panels)],
                             title=f"{study.title or study.file}: body coordinates")]
    if study.reactions:
        figures.append(plots.stacked(out.file("reactions.png"), r.ts, [
            ("|F| [N]", {f"{o.joint} on {o.on}": np.hypot(r.reactions[o.joint][:, 0],
                                                           r.reactions[o.joint][:, 1])
                         for o in study.reactions}),
            ("M about COM [N m]", {f"{o.joint} on {o.on}": r.reactions[o.joint][:, 2]
                                   for o in study.reactions}),
        ], xlabel="time [s]", title=f"{study.title or study.file}: joint reactions"))

    wall = time.perf_counter() - started if started is not None else simulate_time
    summary = {
        "file": study.file,
        "title": study.title,
        "duration_s": sim.duration,
        "n_save": sim.n_save,
        "max_constraint_violation": max(by_joint.values(), default=0.0),
        "max_constraint_violation_by_joint": by_joint,
        "reactions": reactions,
        "contacts": contacts,
        "integrator_steps": steps,
        "simulate_time_s": simulate_time,
        "wall_time_s": wall,
        "files": sorted(set(out.files)) + ["report.md", "summary.json"],
        "warnings": [w for w, _ in warnings] + (wear["warnings"] if wear else []),
    }
    if wear is not None:
        summary["joints"] = wear["joints"]
        if wear["stopped"]:
            summary["wear_stopped"] = wear["stopped"]
        figures.append(out.path / wear["figure"])
    out.text("report.md", _report(study, summary, [f.name for f in figures]))
    out.json("summary.json", summary)
    fatal = [w for w, is_fatal in warnings if is_fatal]
    if fatal:  # the outputs are written; the run is reported as failed
        raise SolverError(f"{study.file}: {fatal[0]} (results written to {out.path})")
    return summary


# A penalty contact holds for elastic penetrations of microns: one of 10 % of
# the pin radius means the pin is through the bushing (e.g. a rod shorter than
# the crank forcing an assembly the clearance cannot take).
MAX_PENETRATION_OF_PIN_RADIUS = 0.1


def contact_warnings(joint, contact: dict) -> list[tuple[str, bool]]:
    """(message, fatal) for results outside the clearance joint model's
    validity: no contact at all (a warning), or a penetration beyond
    `MAX_PENETRATION_OF_PIN_RADIUS` of the pin radius (fatal)."""
    out = []
    if contact["fraction_in_contact"] == 0.0:
        out.append((f"clearance joint {joint.name!r} never made contact: the pin moved freely "
                    "inside the bushing for the whole run (a clearance larger than the "
                    "motion?)", False))
    radius = float(joint.pin_radius)
    if contact["max_penetration_m"] > MAX_PENETRATION_OF_PIN_RADIUS * radius:
        out.append((f"clearance joint {joint.name!r}: penetration "
                    f"{contact['max_penetration_m'] * 1e3:.3g} mm is "
                    f"{contact['max_penetration_m'] / radius:.0%} of the pin radius "
                    f"{radius * 1e3:g} mm: the pin is through the bushing and the contact model "
                    "does not hold (geometry that cannot assemble with this clearance, e.g. a "
                    "rod shorter than the crank?)", True))
    return out


# Integrator steps per crank revolution, a lower bound: the ideal slider-crank
# takes 2,276 steps per revolution at the default tolerances (performance docs).
MIN_STEPS_PER_REVOLUTION = 500


def check_step_budget(study: Study) -> None:
    """Refuse up front a run whose drivers turn more revolutions than the step
    budget (``max_steps``) can take at `MIN_STEPS_PER_REVOLUTION`."""
    sim = study.simulation
    for c in study.mechanism.constraints:
        omega = getattr(c, "omega", None)
        if omega is None:
            continue
        turns = sim.duration * abs(float(omega)) / (2 * np.pi)
        need = turns * MIN_STEPS_PER_REVOLUTION
        if need > sim.max_steps:
            raise InputError(
                f"{study.file}: driver {c.name!r} turns {turns:.3g} revolutions in "
                f"{sim.duration:g} s: at least {need:.2g} integrator steps, beyond the budget "
                f"max_steps = {sim.max_steps:,}; allowed: a speed or duration within it, "
                "or a larger [simulation] max_steps")


# Samples of the cycle in the motion check (5 degrees of the driver apart).
MOTION_SAMPLES = 73


def check_motion(study: Study, y0) -> None:
    """Refuse up front a linkage that cannot move through its cycle (links too
    short to reach, a crank that cannot turn fully, a dead point): the ideal
    mechanism (clearance joints taken as revolute joints) is closed at
    `MOTION_SAMPLES` instants over one revolution of its first driver (or the
    run's duration, if shorter).  Mechanisms the drivers do not fully
    determine are not checked (their motion is not kinematic)."""
    ideal = ideal_parent(study.mechanism)
    drivers = [c for c in ideal.constraints if isinstance(c, Driver) and float(c.omega) != 0.0]
    if not drivers or not fully_driven(ideal):
        return
    sim = study.simulation
    span = min(sim.duration, 2 * math.pi / abs(float(drivers[0].omega)))
    q0, _, _ = ideal.split(y0)
    ts = np.linspace(0.0, span, MOTION_SAMPLES)
    check_cycle_motion(ideal, q0, ts, what=str(study.file), driver=f"driver {drivers[0].name!r}")


def _report(study: Study, s: dict, figures: list[str]) -> str:
    mech, sim = study.mechanism, study.simulation
    lines = [
        f"# {study.title or study.file}\n",
        f"Mechanism file: `{study.file}` (copy: [input.toml](input.toml)).  "
        + (f"Source of the numbers: {study.source}." if study.source else ""),
        "",
        f"{len(mech.bodies)} bodies ({', '.join(mech.body_names)}), "
        f"{len(mech.constraints)} joints ({', '.join(c.name for c in mech.constraints) or '-'}), "
        f"{len(mech.forces)} force elements ({', '.join(f.name for f in mech.forces) or '-'}); "
        f"{mech.n_coords} coordinates, {mech.n_constraints} constraint rows.\n",
        f"Simulated 0 .. {sim.duration:g} s ({sim.n_save} saved states) with Tsit5, PID step "
        f"control (rtol {sim.rtol:g}, atol {sim.atol:g}), Baumgarte alpha = "
        f"{sim.baumgarte_alpha:g} 1/s, "
        f"beta = {sim.baumgarte_beta:g} 1/s.\n",
        "| quantity | value |", "|---|---|",
        f"| max constraint violation | {s['max_constraint_violation']:.3e} "
        "(m; rad for angle rows) |",
        f"| integrator steps | {s['integrator_steps']} |",
        f"| simulation time (incl. compilation) | {s['simulate_time_s']:.2f} s |",
        f"| wall time | {s['wall_time_s']:.2f} s |\n",
    ]
    if s["reactions"]:
        lines += [
            "## Joint reactions\n",
            "Wrench the joint exerts **on** the named body: force in global axes, moment about "
            "that body's centre of mass (for a driver: the driving torque).\n",
            "| joint | on body | max abs(F) [N] | max abs(M) [N m] | file |",
            "|---|---|---|---|---|",
        ]
        lines += [f"| {j} | {r['on_body']} | {r['max_force_N']:.4g} | {r['max_abs_moment_Nm']:.4g} "
                  f"| [{r['file']}]({r['file']}) |" for j, r in s["reactions"].items()]
        lines.append("")
    if s["contacts"]:
        lines += [
            "## Clearance joints\n",
            "Contact force on the bushing body; penetration > 0 means contact.\n",
            "| joint | max abs(F) [N] | max penetration [m] | in contact | file |",
            "|---|---|---|---|---|",
        ]
        lines += [f"| {j} | {c['max_force_N']:.4g} | {c['max_penetration_m']:.3e} | "
                  f"{100 * c['fraction_in_contact']:.1f} % | [{c['file']}]({c['file']}) |"
                  for j, c in s["contacts"].items()]
        lines.append("")
    if s.get("joints"):
        models = "/".join(sorted({w["model"] for w in s["joints"].values()}))
        lines += [
            f"## Wear ({models} model)\n",
            "Every clearance joint with a wear law, over the cycles given (one cycle: one "
            "revolution of the first driver).\n",
            "| joint | cycles | max depth [mm] | volume [mm^3] | cycles to limit | files |",
            "|---|---|---|---|---|---|",
        ]
        for j, w in s["joints"].items():
            to_limit = (f"{w['cycles_to_limit']:,.0f} (to {w['limit_mm']:g} mm)"
                        if w.get("cycles_to_limit") is not None and
                        math.isfinite(w["cycles_to_limit"]) else
                        (f"not within the run's settings (to {w['limit_mm']:g} mm)"
                         if "limit_mm" in w else "-"))
            lines.append(f"| {j} | {w['cycles']:,.0f} | {w['max_wear_depth_mm']:.4g} | "
                         f"{w['wear_volume_mm3']:.4g} | {to_limit} | "
                         f"[profile](wear_profile_{j}.csv), [history](wear_history_{j}.csv) |")
        lines.append("")
        lines += [f"- **stopped: {why}**" for why in s.get("wear_stopped", [])]
        lines.append("")
    if s.get("warnings"):
        lines += ["## Warnings\n"] + [f"- **{w}**" for w in s["warnings"]] + [""]
    lines += [
        "## Files\n",
        "- [summary.json](summary.json): the numbers above",
        "- [trajectory.csv](trajectory.csv): t_s; every body's x_m, y_m, phi_rad (centre of "
        "mass), then vx_m_s, vy_m_s, omega_rad_s",
        "",
    ]
    lines += [f"![{name}]({name})\n" for name in figures]
    return "\n".join(lines)


def run(study: Study, out_dir: str, *, overwrite: bool = False, input_text: str | None = None,
        cycles: float | None = None, limit: float | None = None, model: str = "quasi-static",
        method: str = "constant", resume: bool = False, progress: bool = False,
        log: Callable[..., None] = print) -> dict:
    """Assemble, integrate, write; with ``cycles`` also the wear of every
    clearance joint with a wear law (`mechanism_wear`) on ``model``
    ("quasi-static" or "dynamic", the latter with ``method`` and checkpoints
    in ``out_dir``, which ``resume=True`` continues), and with ``limit`` [m]
    the cycles to that depth.  Bad input fails before ``out_dir`` is touched."""
    from . import mechanism_wear

    started = time.perf_counter()
    check_step_budget(study)
    if cycles is None and (resume or model != "quasi-static" or method != "constant"):
        raise InputError("--model, --method and --resume belong to a wear study: give "
                         "--cycles N")
    if cycles is not None:
        check_wear_options(model, method, resume)
        if model == "dynamic":
            mechanism_wear.dynamic_wear_joint(study)
        mechanism_wear.bushing_walls(study, mechanism_wear.wearing_joints(study), limit)
        mechanism_wear.drive_period(study)
    y0 = initial_state(study)
    check_motion(study, y0)
    out = OutputDir(out_dir, overwrite=overwrite, resume=resume)
    log(f"[{study.file}] integrating {study.simulation.duration:g} s (first run compiles) ...")
    t0 = time.perf_counter()
    traj = jax.block_until_ready(integrate(study, y0))
    simulate_time = time.perf_counter() - t0
    results = postprocess(study, traj)
    wear = None
    if cycles is not None:
        log(f"[{study.file}] wear over {cycles:,.0f} cycles ({model} model) ...")
        if model == "dynamic":
            evolved = mechanism_wear.evolve_file_dynamic(
                study, y0, cycles=cycles, method=method, limit=limit, out=out, resume=resume,
                progress=progress)
        else:
            evolved = mechanism_wear.evolve_file(study, y0, cycles=cycles, limit=limit)
        wear = mechanism_wear.write_wear(study, out, evolved, cycles=cycles, limit=limit)
    summary = write(study, results, out, steps=int(traj.num_steps), simulate_time=simulate_time,
                    input_text=input_text, started=started, wear=wear)
    for w in summary["warnings"]:
        print(f"diffwear: warning: {w}", file=sys.stderr)
    log(f"[{study.file}] max constraint violation {summary['max_constraint_violation']:.2e}; "
        f"report: {out.path / 'report.md'}")
    if wear is not None and wear["stopped"]:
        raise SolverError(f"{study.file}: " + "; ".join(wear["stopped"])
                          + f"; stopped, results so far written to {out.path}")
    return summary


def check_wear_options(model: str, method: str, resume: bool) -> None:
    """`InputError` for a wear model or method that does not exist, or one the
    quasi-static model does not take (it has no extrapolation and no
    checkpoints: it integrates the wear in the cycle count, in seconds)."""
    if model not in WEAR_MODELS:
        raise InputError(f"--model {model!r}; allowed: {', '.join(WEAR_MODELS)}")
    if method not in WEAR_METHODS:
        raise InputError(f"--method {method!r}; allowed: {', '.join(WEAR_METHODS)}")
    if model == "quasi-static":
        for given, why in ((method != "constant", f"--method {method}"), (resume, "--resume")):
            if given:
                raise InputError(f"{why} belongs to the dynamic model (--model dynamic); the "
                                 "quasi-static model integrates the wear in the cycle count "
                                 "itself (seconds, no checkpoints)")


__all__ = ["initial_state", "integrate", "postprocess", "write", "run", "Results"]
