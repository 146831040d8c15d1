"""The rig parameters a dataset may state, fit or leave to suspicion.

One table serves the dataset format (dimension of each value), the model
(`model.rig_mechanism` reads every name) and the identification (the
``mechanism`` group are the suspects scored when no wear effect explains the
data).  Pure Python: the format reads it without importing JAX.
"""

from __future__ import annotations

from typing import NamedTuple


class RigParameter(NamedTuple):
    dimension: str | None   # `config.units` dimension (None: a plain number in [0, 1])
    group: str              # "joint" | "mechanism"
    description: str


RIG_PARAMETERS: dict[str, RigParameter] = {
    "k": RigParameter("wear coefficient", "joint", "wear coefficient"),
    "clearance": RigParameter("length", "joint", "radial clearance"),
    "depth": RigParameter("length", "joint", "bushing depth"),
    "diameter": RigParameter("length", "joint", "pin diameter"),
    "mu": RigParameter(None, "joint", "pin-bushing friction coefficient"),
    "wall": RigParameter("length", "mechanism",
                         "bushing wall (EFM layer: foundation stiffness E / wall)"),
    "free_length": RigParameter("length", "mechanism", "slider-spring free length"),
    "spring_stiffness": RigParameter("stiffness", "mechanism", "slider-spring rate"),
    "crank_length": RigParameter("length", "mechanism", "crank length (joint to joint)"),
    "rod_length": RigParameter("length", "mechanism", "rod length (joint to joint)"),
    "crank_mass": RigParameter("mass", "mechanism", "crank mass"),
    "rod_mass": RigParameter("mass", "mechanism", "rod mass"),
    "slider_mass": RigParameter("mass", "mechanism", "slider mass"),
    "crank_inertia": RigParameter("inertia", "mechanism", "crank inertia about its centre"),
    "rod_inertia": RigParameter("inertia", "mechanism", "rod inertia about its centre"),
}
NAMES = tuple(RIG_PARAMETERS)
MECHANISM = tuple(n for n, p in RIG_PARAMETERS.items() if p.group == "mechanism")
