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
# How far a suspect may move from its stated value and still be a finding
# (factors, by dimension): a rig measured with a rule and a balance is not off
# by more than a factor 2 in a length or a wall, 4 in a mass or a spring
# rate, 10 in an inertia derived from the geometry; a fit that asks for more
# stands for a model error of another kind, not for that parameter.
PLAUSIBLE_FACTOR = {"length": 2.0, "mass": 4.0, "stiffness": 4.0, "inertia": 10.0}


def plausible_range(name: str) -> tuple[float, float] | None:
    """(lowest, highest) factor on the stated value of suspect ``name`` that
    is still a finding (None: no stated range)."""
    p = RIG_PARAMETERS.get(name)
    f = PLAUSIBLE_FACTOR.get(p.dimension or "") if p is not None else None
    return None if f is None else (1.0 / f, f)


NAMES = tuple(RIG_PARAMETERS)
MECHANISM = tuple(n for n, p in RIG_PARAMETERS.items() if p.group == "mechanism")
