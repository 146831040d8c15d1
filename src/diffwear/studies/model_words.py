"""What the reports say of a wear model: its label, the words for its history's
steps, the settings a summary reports (and a checkpoint records) and what a
comparison of routes reports beyond the wear.

The models (`diffwear.models`) are the physics; these words are the reports'.
Each is looked up by the model's class, the nearest along its bases (a
`FemRoute` is a `Dynamic` where it has no words of its own; a model of none of
these classes gets the plain ones).
"""

from __future__ import annotations

import numpy as np

from ..models import AbstractWearModel, Dynamic, FemRoute, QuasiStatic, WearSolution
from ..wear.cycle import film_integrator, integrator_name

# how a model's results are labelled in the reports' tables and figures
LABELS = {AbstractWearModel: "diffwear", Dynamic: "diffwear (EFM)",
          QuasiStatic: "diffwear (quasi-static)", FemRoute: "diffwear (FEM route)"}
# what the steps of a model's history are (the markers of the history figure)
STEP_WORDS = {AbstractWearModel: "steps", Dynamic: "simulated dynamic cycles",
              QuasiStatic: "wear ODE steps"}


def _nearest(table: dict, model: AbstractWearModel):
    return next(table[cls] for cls in type(model).__mro__ if cls in table)


def label(model: AbstractWearModel) -> str:
    """How ``model``'s results are labelled (``LABELS``)."""
    return _nearest(LABELS, model)


def step_words(model: AbstractWearModel) -> str:
    """What the steps of ``model``'s history are (``STEP_WORDS``)."""
    return _nearest(STEP_WORDS, model)


def describe(model: AbstractWearModel, cycles, lubricated: bool = False) -> dict:
    """The settings of an evolution of ``model`` over ``cycles`` that a summary
    reports and a checkpoint records (a checkpoint resumes only a run with the
    same); ``lubricated``: the mechanism has a lubricated joint, whose cycles
    run on a Rosenbrock method (`film_integrator`)."""
    if isinstance(model, FemRoute):
        assert model.fem is not None
        fem = model.fem
        return {**_dynamic_settings(model, cycles, lubricated), "model": "dynamic",
                "contact": "fem",
                "fem_refresh_interval": float(fem.refresh_interval),
                "fem_samples": fem.n_samples, "fem_layers": fem.n_layers,
                "fem_force": fem.force}
    if isinstance(model, Dynamic):
        return _dynamic_settings(model, cycles, lubricated)
    if isinstance(model, QuasiStatic):
        return {"model": model.name, "load_samples_per_cycle": model.samples}
    return {"model": model.name}


def _dynamic_settings(model: Dynamic, cycles, lubricated: bool) -> dict:
    solver = model.solver(cycles)
    integrator = film_integrator(model.cycle.solver) if lubricated else model.cycle.solver
    return {"model": model.name, "method": solver.name,
            "extrapolation": float(solver.first_step(cycles)), "contact": "efm",
            "integrator": integrator_name(integrator)}


def route_summary(model: AbstractWearModel, evolution: WearSolution) -> dict:
    """What a comparison of routes reports of ``model``'s run ``evolution``
    beyond the wear: the FEM route's ring and its explicit fallbacks."""
    if not isinstance(model, FemRoute):
        return {}
    assert model.fem is not None
    fem = model.fem
    assert evolution.state is not None  # a FEM route's evolution simulates cycles
    fallback = evolution.state.memory["fem_explicit"]
    return {"explicit_fallback_cycles": int(np.asarray(fallback)),
            "refresh_interval": float(fem.refresh_interval),
            "samples_per_cycle": fem.n_samples + 1, "layers": fem.n_layers,
            "force": fem.force, "youngs_modulus_Pa": float(fem.youngs_modulus),
            "poisson_ratio": float(fem.poisson_ratio),
            "outer_radius_m": float(fem.outer_radius)}


__all__ = ["LABELS", "STEP_WORDS", "label", "step_words", "describe", "route_summary"]
