"""Wear of a mechanism file's clearance joints: ``diffwear run FILE --cycles N``.

Every clearance joint of the file that has a wear law evolves over ``cycles``
crank revolutions (the first driver's period) with the quasi-static wear model
(`diffwear.quasistatic.QuasiStatic`: the ideal mechanism's joint loads, the pin
at the equilibrium of the EFM springs, the profile integrated in the cycle
count), and, with a depth ``limit``, the revolutions until each joint's peak
wear reaches it.  The joints must use the elastic-foundation law (a pressure
distribution to wear).  Outputs per joint: the worn profile and the peak-depth
history (CSV), the worn volume; a figure of the profiles and histories.
"""

from __future__ import annotations

import math

import jax
import numpy as np

from . import plots
from ._checks import require_float64
from .config import Study
from .contact.clearance_joint import ClearanceJoint
from .errors import InputError, SolverError
from .io import OutputDir
from .mechanism.constraints import Driver
from .quasistatic import QuasiStatic
from .wear import worn_volume
from .wear.status import STATUS_CONTACT_LOSS, STATUS_OK, STATUS_PIERCED

FILE_WEAR_SLOTS = 2000


def wearing_joints(study: Study) -> tuple[str, ...]:
    """Names of the clearance joints with a wear law; `InputError` if none."""
    names = tuple(f.name for f in study.mechanism.forces
                  if isinstance(f, ClearanceJoint) and f.wear is not None)
    if not names:
        raise InputError(f"{study.file}: the mechanism has no clearance joint with a wear law "
                         "to wear; allowed: a [[joints]] type = \"clearance\" entry with "
                         "wear = { coefficient = ... }")
    return names


def drive(study: Study) -> Driver:
    """The first driver with a non-zero speed: its revolution is the cycle."""
    for c in study.mechanism.constraints:
        if isinstance(c, Driver) and float(c.omega) != 0.0:
            return c
    raise InputError(f"{study.file}: a wear study needs a driver with a non-zero speed (the "
                     "crank cycle); allowed: a [[joints]] type = \"driver\" entry")


def drive_period(study: Study) -> float:
    """2 pi / |omega| of `drive`: the period of one cycle [s]."""
    return 2 * math.pi / abs(float(drive(study).omega))


def bushing_walls(study: Study, joints, limit: float | None = None) -> list[float]:
    """Per joint, its bushing wall thickness [m] (the elastic foundation's
    layer thickness; infinite where the file states none); `InputError` for a
    depth ``limit`` the wall does not allow."""
    stated = dict(study.bushing_walls)
    walls = [stated.get(name, math.inf) for name in joints]
    for name, wall in zip(joints, walls):
        if limit is not None and limit >= wall:
            raise InputError(f"{study.file}: --limit {limit * 1e3:g} mm is not less than the "
                             f"bushing wall of clearance joint {name!r} ({wall * 1e3:g} mm): "
                             "the joint wears through first; allowed: a limit below the wall")
    return walls


def evolve_file(study: Study, y0, *, cycles: float, limit: float | None = None,
                model: QuasiStatic | None = None) -> dict:
    """Per joint: depth profile [m], grid angles, peak-depth history, volume
    [m^3], status, and (with ``limit`` [m]) the cycles to reach it."""
    require_float64("wear of a mechanism file")
    # one mechanism, not a vmapped sweep: slots to spare for a groove whose
    # peak grows slower than the step rule expects (slots after the end cost
    # nothing; the four-bar example's joint needs ~12x the 40 steps to its wall)
    model = QuasiStatic(max_steps=FILE_WEAR_SLOTS) if model is None else model
    joints = wearing_joints(study)
    period = drive_period(study)
    walls = bushing_walls(study, joints, limit)
    mech = study.mechanism
    res = jax.jit(lambda y: model.evolve(mech, joints, y, period=period, cycles=cycles,
                                         wall_thickness=walls))(y0)
    life = None
    if limit is not None:
        life = jax.jit(lambda y: model.life(mech, joints, y, period=period, limit=limit))(y0)
    out = {}
    for k, name in enumerate(joints):
        el = mech.element(name)
        depth = np.asarray(res.depth[k])
        hist = res.history[k]
        valid = np.asarray(hist.valid)
        status = int(res.joint_status[k])
        out[name] = {
            "theta": np.asarray(el.profile.theta), "depth": depth,
            "history_cycles": np.asarray(hist.cycles)[valid],
            "history_peak": np.asarray(hist.peak)[valid],
            "volume": float(worn_volume(depth, el.bushing_radius, el.law.depth)),
            "cycles": float(res.joint_cycles[k]), "wall": walls[k],
            "status": status, "contact_margin": float(res.contact_margin[k]),
            "contact_margin_worn": float(res.contact_margin_worn[k]),
            "cycles_to_limit": (float(life.cycles[k]) if life is not None else None),
        }
    return out


def write_wear(study: Study, out: OutputDir, wear: dict, *, cycles: float,
               limit: float | None) -> dict:
    """CSV files and a figure per joint; returns the summary's ``joints`` and
    warnings, and ``stopped``: a sentence per joint that wore through its wall
    (the caller reports them as a failure once everything is written).  A
    joint whose model failed raises `SolverError` after writing."""
    joints, warnings, pierced = {}, [], []
    for name, w in wear.items():
        out.csv(f"wear_profile_{name}.csv", {"theta_rad": w["theta"], "depth_mm": w["depth"] * 1e3})
        out.csv(f"wear_history_{name}.csv", {"cycles": w["history_cycles"],
                                             "max_depth_mm": w["history_peak"] * 1e3})
        joints[name] = {"max_wear_depth_mm": float(np.max(w["depth"])) * 1e3,
                        "wear_volume_mm3": w["volume"] * 1e9, "cycles": w["cycles"],
                        "model": QuasiStatic.name, "status": w["status"],
                        "contact_margin": w["contact_margin"]}
        if limit is not None:
            joints[name]["limit_mm"] = limit * 1e3
            joints[name]["cycles_to_limit"] = w["cycles_to_limit"]
        if w["status"] == STATUS_CONTACT_LOSS:
            warnings.append(f"clearance joint {name!r}: the load cannot hold the pin on the "
                            f"bushing wall (contact margin {w['contact_margin']:.2g} < 1): the "
                            "quasi-static wear model does not hold there")
        elif w["status"] == STATUS_PIERCED:
            pierced.append(f"clearance joint {name!r} wore through its {w['wall'] * 1e3:g} mm "
                           f"bushing wall after {w['cycles']:,.0f} cycles (max depth "
                           f"{joints[name]['max_wear_depth_mm']:.4f} mm)")
        elif w["status"] != STATUS_OK:
            raise SolverError(f"{study.file}: wear of clearance joint {name!r} failed (status "
                              f"{w['status']}); outputs so far are in {out.path}")
        elif w["contact_margin_worn"] < 1.0:
            warnings.append(f"clearance joint {name!r}: on the worn profile the pin may lift "
                            f"off the wall (contact margin {w['contact_margin_worn']:.2g})")
    figure = out.file("wear.png")
    plots.wear_panels(figure, {n: (w["theta"], w["depth"]) for n, w in wear.items()},
                      {n: (w["history_cycles"], w["history_peak"]) for n, w in wear.items()},
                      title=f"{study.title or study.file}: wear after {cycles:,.0f} cycles "
                            "(quasi-static model)")
    return {"joints": joints, "warnings": warnings, "figure": figure.name, "stopped": pierced}
