"""Synthetic measured datasets: the model plus one effect plus noise.

`synthesize` runs `RigHistory` with a chosen effect strength, samples it the
way a rig campaign would (`Plan`: worn profiles at a few cycle counts, the
bushing weighed regularly, the joint force recorded at the start and near the
end), adds Gaussian noise of the stated 1-sigma and writes a dataset folder in
the documented format.  The effect is recorded only by the caller (the
generator script ``design_studies/calibration/make_datasets.py``), never in
the dataset: calibration has to find it.  ``distort`` adds an effect from
outside the library to the measured profiles (e.g. an oval bore).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from ..presets import PTFE_DENSITY
from .dataset import Dataset, Parameter, Series, write_dataset
from .effects import INDEX, NAMES
from .fit import ModelSettings
from .model import Observation, rig_defaults


@dataclass(frozen=True)
class Plan:
    """What a (synthetic) campaign measures, and how precisely."""

    cycles: float = 2000.0
    profile_cycles: tuple = (500.0, 1000.0, 1500.0, 2000.0)
    profile_angles: int = 72                 # every 5 degrees
    profile_sigma: float = 1.0e-6            # m: a form-tracer profile, 1 um
    volume_cycles: tuple = tuple(250.0 * i for i in range(1, 9))
    mass_sigma: float = 0.1e-6               # kg: 0.1 mg balance
    force_cycles: tuple = (0.0, 1750.0)
    force_angles: int = 72
    force_sigma: float = 1.0                 # N: load cell
    holdout_from_cycles: float = 1500.0
    fit: tuple = ("k", "free_length")
    # stated prior spread of the fitted parameters (sets the optimiser's scale)
    prior_rel_std: float = 0.3


def synthesize(folder, *, name: str, effect: str | None = None, strength: float = 0.0,
               seed: int = 0, plan: Plan = Plan(), settings: ModelSettings = ModelSettings(),
               truth: dict | None = None, distort=None, description: str = "",
               overwrite: bool = False) -> Dataset:
    """Write a synthetic dataset to ``folder`` (see module notes).  ``truth``:
    rig parameters (SI) that differ from the thesis rig; the dataset states the
    thesis values for the fitted ones (the calibration must move them).
    ``distort(theta, cycles) -> extra depth [m]``: an outside-library effect
    added to every measured profile."""
    rng = np.random.default_rng(seed)
    model = settings.model(plan.cycles)
    base = rig_defaults()
    true = {**base, **(truth or {})}
    strengths = np.zeros(len(NAMES))
    if effect is not None:
        strengths[INDEX[effect]] = strength
    history = jax.jit(model)({k: jnp.asarray(v) for k, v in true.items()},
                             jnp.asarray(strengths))
    if not bool(history.ok):
        raise RuntimeError("synthesize: the model failed")
    a, d = model.extrapolation, model.dynamic_cycles

    def observe(kind, x, cycles=0.0, basis="mass"):
        return np.asarray(Observation(kind, np.asarray(x, float), a, d, cycles=cycles,
                                      basis=basis)(history))

    def held(counts):
        return np.asarray(counts, float) >= plan.holdout_from_cycles

    series = []
    theta = 2 * np.pi * np.arange(plan.profile_angles) / plan.profile_angles
    for n in plan.profile_cycles:
        depth = observe("profile", theta, n)
        if distort is not None:
            depth = depth + distort(theta, n)
        depth = np.maximum(depth + rng.normal(0.0, plan.profile_sigma, theta.shape), 0.0)
        series.append(Series(f"profile_{int(n):05d}", "profile",
                             Path(f"profile_{int(n):05d}.csv"), n, theta, depth,
                             plan.profile_sigma, holdout=np.full(theta.shape, held(n))))
    vc = np.asarray(plan.volume_cycles, float)
    mass = observe("volume", vc) * PTFE_DENSITY + rng.normal(0.0, plan.mass_sigma, vc.shape)
    series.append(Series("worn_volume", "volume", Path("worn_mass.csv"), None, vc,
                         mass / PTFE_DENSITY, plan.mass_sigma / PTFE_DENSITY, holdout=held(vc),
                         basis="mass"))
    angle = 2 * np.pi * np.arange(plan.force_angles) / plan.force_angles
    for n in plan.force_cycles:
        force = observe("force", angle, n) + rng.normal(0.0, plan.force_sigma, angle.shape)
        series.append(Series(f"force_{int(n):05d}", "force", Path(f"force_{int(n):05d}.csv"),
                             n, angle, force, plan.force_sigma,
                             holdout=np.full(angle.shape, held(n))))
    params = {}
    for key, value in base.items():
        if key in plan.fit:
            params[key] = Parameter(key, value, plan.prior_rel_std * value, True)
        else:
            params[key] = Parameter(key, true[key], None, False)
    return write_dataset(folder, name=name, description=description, preset="rig",
                         parameters=params, series=series, bushing_density=PTFE_DENSITY,
                         holdout_from_cycles=plan.holdout_from_cycles, overwrite=overwrite)
