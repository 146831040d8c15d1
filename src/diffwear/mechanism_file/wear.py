"""Wear of a mechanism file's clearance joints: ``diffwear run FILE --cycles N``.

Every clearance joint of the file that has a wear law evolves over ``cycles``
crank revolutions (the first driver's period) with the quasi-static wear model
(`diffwear.quasistatic.QuasiStatic`: the ideal mechanism's joint loads, the pin
at the equilibrium of the EFM springs, the profile integrated in the cycle
count), and, with a depth ``limit``, the revolutions until each joint's peak
wear reaches it.  The joints must use the elastic-foundation law (a pressure
distribution to wear), lubricated or not.  Per joint: the worn profile, the
peak-depth history and the worn volume, and for a lubricated joint its film
over the cycle (`QuasiStatic.film_cycle`) on the unworn and the worn bushing
(`diffwear.cli.run` writes them).
"""

from __future__ import annotations

import math
import time
import zlib
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from .._checks import require_float64
from ..config import MechanismFile
from ..contact.clearance_joint import ClearanceJoint
from ..contact.finite_bearing import film_out_of_range
from ..contact.mixed import MixedLubrication
from ..errors import InputError
from ..mechanism.constraints import Driver
from ..models import MAX_CYCLES, AbstractWearModel, QuasiStatic, WearSolution
from ..models.execution import Checkpoints, RunTimes, run_model
from ..studies.model_words import describe
from ..wear import worn_volume
from ..wear.status import at
from .motion import first_driver

FILE_WEAR_SLOTS = 2000


def wearing_joints(mfile: MechanismFile) -> tuple[str, ...]:
    """Names of the clearance joints with a wear law; `InputError` if none."""
    names = tuple(f.name for f in mfile.mechanism.forces
                  if isinstance(f, ClearanceJoint) and f.wear is not None)
    if not names:
        raise InputError(f"{mfile.file}: the mechanism has no clearance joint with a wear law "
                         "to wear; allowed: a [[joints]] type = \"clearance\" entry with "
                         "wear = { coefficient = ... }")
    return names


def drive(mfile: MechanismFile) -> Driver:
    """The first driver with a non-zero speed: its revolution is the cycle."""
    driver = first_driver(mfile.mechanism)
    if driver is not None:
        return driver
    raise InputError(f"{mfile.file}: a wear mfile needs a driver with a non-zero speed (the "
                     "crank cycle); allowed: a [[joints]] type = \"driver\" entry")


def drive_period(mfile: MechanismFile) -> float:
    """2 pi / |omega| of `drive`: the period of one cycle [s]."""
    return drive(mfile).period


def bushing_walls(mfile: MechanismFile, joints, limit: float | None = None) -> list[float]:
    """Per joint, its bushing wall thickness [m] (the elastic foundation's
    layer thickness; infinite where the file states none); `InputError` for a
    depth ``limit`` the wall does not allow."""
    stated = dict(mfile.bushing_walls)
    walls = [stated.get(name, math.inf) for name in joints]
    for name, wall in zip(joints, walls):
        if limit is not None and limit >= wall:
            raise InputError(f"{mfile.file}: --limit {limit * 1e3:g} mm is not less than the "
                             f"bushing wall of clearance joint {name!r} ({wall * 1e3:g} mm): "
                             "the joint wears through first; allowed: a limit below the wall")
    return walls


def likely_causes(mfile: MechanismFile, name: str) -> list[str]:
    """Inputs of clearance joint ``name`` that make its cycle model fail,
    in words naming the keys to change (for the message of a failed run)."""
    el = mfile.mechanism.element(name)
    rp, rb = float(el.pin_radius), float(el.bushing_radius)
    c = rb - rp
    wall = dict(mfile.bushing_walls).get(name, math.inf)
    out = []
    if c > rp:
        out.append(f"its clearance ({c * 1e3:.4g} mm) is larger than its pin radius "
                   f"({rp * 1e3:.4g} mm): the pin crosses the bore without holding contact "
                   "(clearances are fractions of a percent of the radius; change clearance "
                   "or bushing_radius)")
    if wall < c and not out:
        out.append(f"its bushing wall (law.layer_thickness {wall * 1e3:.4g} mm) is thinner "
                   f"than its clearance ({c * 1e3:.4g} mm): the foundation stiffness E / "
                   "wall makes the contact too stiff to integrate (change layer_thickness)")
    return out


def check_wear(mfile: MechanismFile, model: AbstractWearModel, *, limit: float | None = None,
               resume_folder=None) -> tuple[tuple[str, ...], float, list[float]]:
    """Every check of a file's wear run, before anything runs or is written:
    a wearing joint, a driver, walls that allow ``limit``, the checkpoint in
    ``resume_folder`` (if resuming) of a run of this file, and joints
    ``model`` evolves (`InputError` naming the file).  Returns what they read:
    (the wearing joints, the cycle's period [s], each joint's wall [m])."""
    joints = wearing_joints(mfile)
    period = drive_period(mfile)
    walls = bushing_walls(mfile, joints, limit)
    if resume_folder is not None:
        check_resumed_file(mfile, resume_folder)
    check_joints(mfile, model, joints)
    return joints, period, walls


def file_meta(mfile: MechanismFile) -> dict:
    """What a checkpoint records of the file it belongs to: its name and the
    CRC-32 of its bytes (an edited file is another file)."""
    return {"mfile": f"run {Path(mfile.file).name}",
            "file_crc32": f"{zlib.crc32(Path(mfile.file).read_bytes()):08x}"}


def check_resumed_file(mfile: MechanismFile, folder) -> None:
    """--resume ``folder``: `InputError` unless its checkpoint belongs to a
    run of this file (checked before the folder is touched)."""
    from ..io import CHECKPOINT
    from ..models.execution import load_checkpoint

    _, saved = load_checkpoint(Path(folder) / CHECKPOINT)
    mine = file_meta(mfile)
    if "mfile" not in saved:  # a study's checkpoint, not a file's run
        whose = f"the study {saved['study']!r}" if "study" in saved else "another command"
        raise InputError(f"--resume {folder}: the checkpoint belongs to a run of {whose}, "
                         f"not of a mechanism file ({mine['mfile']!r}); resume it with the "
                         "command that started it, or start this file in another folder")
    for key, value in mine.items():
        if key in saved and saved[key] != value:
            raise InputError(
                f"--resume {folder}: the checkpoint belongs to a run with {key} = "
                f"{saved[key]!r}, this run has {key} = {value!r}; resume it with the file "
                "it was started from (unchanged), or start this file in another folder")


def evolve_file(mfile: MechanismFile, y0, *, cycles: float, limit: float | None = None,
                model: AbstractWearModel | None = None,
                checkpoints: Checkpoints | None = None) -> dict:
    """Per joint: depth profile [m], grid angles, peak-depth history, volume
    [m^3], status, the inputs to change should its cycle model fail
    (``causes``), and (with ``limit`` [m]) the cycles to reach it, on
    ``model`` (default `QuasiStatic`; the dynamic model evolves one joint and
    keeps ``checkpoints``, whose meta this adds the file's name and checksum
    to: the checkpoint of another file, or an edited one, is not resumed);
    a lubricated joint's ``film`` over the cycle on the unworn and the worn
    bushing (`film_settings`, `QuasiStatic.film_cycle`)."""
    require_float64("wear of a mechanism file")
    # one mechanism, not a vmapped sweep: slots to spare for a groove whose
    # peak grows slower than the step rule expects (slots after the end cost
    # nothing; the four-bar example's joint needs ~12x the 40 steps to its wall)
    model = QuasiStatic(max_steps=FILE_WEAR_SLOTS) if model is None else model
    joints, period, walls = check_wear(mfile, model, limit=limit)
    mech = mfile.mechanism
    # what the file says before anything runs: what to change should a
    # joint's cycle model fail, and its film's settings
    causes = {name: likely_causes(mfile, name) for name in joints}
    films = film_settings(mfile, joints)
    life = None
    if limit is not None and isinstance(model, QuasiStatic):
        res, life, times = _run_and_life(model, mech, joints, y0, period, cycles, limit, walls)
    else:
        if checkpoints is not None:
            # a lubricated joint anywhere runs the cycles on a Rosenbrock method
            lubricated = bool(lubricated_joints(mfile))
            checkpoints = checkpoints._replace(meta={
                **checkpoints.meta, **file_meta(mfile), **describe(model, cycles, lubricated),
                "limit_mm": None if limit is None else round(limit * 1e3, 12),
                "cycles": float(cycles), "n_theta": int(mech.element(joints[0]).profile.n)})
        res, times = run_model(model, lambda _: mech, jnp.zeros(()), joints, y0, period=period,
                               cycles=cycles, wall_thickness=walls, checkpoints=checkpoints)
        if limit is not None:
            life = jax.jit(lambda y: model.life(mech, joints, y, period=period,
                                                limit=limit))(y0)
    out = {}
    for k, name in enumerate(joints):
        el = mech.element(name)
        hist = res.history[k]
        valid = np.asarray(hist.valid)
        depth = np.asarray(res.depth[k])  # as far as it got (`WearSolution.reached`)
        out[name] = {
            "theta": np.asarray(el.profile.theta), "depth": depth,
            "history_cycles": np.asarray(hist.cycles)[valid],
            "history_peak": np.asarray(hist.peak)[valid],
            "volume": float(worn_volume(depth, el.bushing_radius, el.law.depth)),
            "cycles": float(res.joint_cycles[k]), "wall": walls[k],
            "status": at(res.joint_result, k),
            "cycles_to_limit": (float(life.life[k]) if life is not None else None),
            "model": model.name, "wall_time_s": times.wall_time,
            "compile_time_s": times.compile_time, **times.info,
            **model_numbers(model, res, k, cycles), "causes": causes[name],
        }
    if films:
        # the loads of the ideal mechanism, as the quasi-static wear model takes them
        names, worn = tuple(films), tuple(jnp.asarray(out[n]["depth"]) for n in films)
        per_joint, loads_ok = jax.jit(lambda y, worn: QuasiStatic().film_cycle(
            mech, names, y, period, worn))(y0, worn)
        for name, (unworn, worn_parts) in zip(names, per_joint):
            el = mech.element(name)
            out[name]["film"] = {
                **films[name], "loads_ok": bool(loads_ok),
                "out_of_range": film_out_of_range(films[name]["bearing"], el.law, el.pin_radius),
                "unworn": {k: np.asarray(v) for k, v in unworn.items()},
                "worn": {k: np.asarray(v) for k, v in worn_parts.items()}}
    return out


def _run_and_life(model: QuasiStatic, mech, joints, y0, period, cycles, limit, walls):
    """The run over ``cycles`` [with ``walls``] and the life to ``limit`` [m]
    of the quasi-static ``model``: one program (`QuasiStatic.solve` with
    traced cycles, limit and walls) compiled once, run twice with the numbers
    of `QuasiStatic.evolve` and `QuasiStatic.life`.  (The `WearSolution` of
    the run, that of the life, RunTimes: the compile, and the two runs
    together.)"""
    never = jnp.asarray(jnp.inf)
    walls = jnp.asarray(walls, dtype=float)  # `bushing_walls`: inf where none

    def solve(y, n, lim, w):
        return model.solve(mech, joints, y, period=period, cycles=n, limit=lim, wall_thickness=w)

    run = (y0, jnp.asarray(float(cycles)), never, walls)
    # a life has no end but the limit (`Stop`: max_cycles) and no wall
    to_limit = (y0, jnp.asarray(MAX_CYCLES), jnp.asarray(float(limit)),
                jnp.full_like(walls, jnp.inf))
    started = time.perf_counter()
    compiled = jax.jit(solve).lower(*run).compile()
    compile_time = time.perf_counter() - started
    started = time.perf_counter()
    res = jax.block_until_ready(compiled(*run))
    life = jax.block_until_ready(compiled(*to_limit))
    return res.reached(), life, RunTimes(compile_time, time.perf_counter() - started, {})


def model_numbers(model: AbstractWearModel, res: WearSolution, k: int, cycles) -> dict:
    """What a joint's summary says of the model beyond the wear: the contact
    check where the model has one, the extrapolation and the dynamic cycles
    where it simulates them."""
    out: dict = {}
    margin = float(res.contact_margin[k])
    if np.isfinite(margin):
        out.update(contact_margin=margin,
                   contact_margin_worn=float(res.contact_margin_worn[k]))
    if "dynamic_cycles" in res.stats:
        out.update(method=describe(model, cycles).get("method"),
                   dynamic_cycles=int(res.stats["dynamic_cycles"]))
    return out


def check_joints(mfile: MechanismFile, model: AbstractWearModel, joints) -> None:
    """`InputError` naming the file for wearing joints ``model`` does not evolve."""
    try:
        model.check_joints(mfile.mechanism, joints, what="file")
    except InputError as err:
        raise InputError(f"{mfile.file}: {err}") from None


def lubricated_joints(mfile: MechanismFile, joints=None) -> tuple[str, ...]:
    """Those of ``joints`` (default: every force element) whose law is a
    `MixedLubrication` (a ``lubricant`` key)."""
    mech = mfile.mechanism
    elements = mech.forces if joints is None else [mech.element(n) for n in joints]
    return tuple(e.name for e in elements
                 if isinstance(getattr(e, "law", None), MixedLubrication))


def bearing_name(law: MixedLubrication) -> str:
    """The ``lubricant.bearing`` name of a lubricated law's film model."""
    from ..config.clearance import BEARINGS
    from ..contact.finite_table import DynamicFiniteFilm, ShippedFiniteFilm

    if isinstance(law.film, (ShippedFiniteFilm, DynamicFiniteFilm)):
        return "finite"  # the finite film, tabulated for a moving journal
    return next((k for k, cls in BEARINGS.items() if type(law.film) is cls),
                type(law.film).__name__)


def film_settings(mfile: MechanismFile, joints) -> dict:
    """Per lubricated joint of ``joints``, what the file sets of its film:
    the crank angle [deg] of each of the quasi-static wear model's samples
    of the cycle (where `QuasiStatic.film_cycle` gives the film), the
    lubricant and the film model (``bearing``)."""
    mech = mfile.mechanism
    driver = drive(mfile)
    samples = QuasiStatic().samples
    t = driver.period * np.arange(samples) / samples
    crank = np.degrees(float(driver.angle0) + float(driver.omega) * t)
    out = {}
    for name in lubricated_joints(mfile, joints):
        law = mech.element(name).law
        out[name] = {
            "crank_angle_deg": crank,
            "viscosity": float(law.film.viscosity), "roughness": float(law.roughness),
            "bearing": bearing_name(law), "onset_gap": float(law.onset_gap),
            "onset_ratio": float(law.onset_ratio),
        }
    return out
