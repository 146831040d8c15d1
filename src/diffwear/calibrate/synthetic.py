"""Synthetic measured datasets: the model plus one effect plus noise.

`synthesize` runs a forward model (by default the dynamic `RigHistory`, the
reference) with chosen effects, samples it the way a rig campaign would
(`Plan`: worn profiles at a few cycle counts, the bushing weighed regularly,
the joint force recorded at the start and near the end; `CAMPAIGN_21400`:
the thesis's own Ch. 7 test), adds Gaussian noise of the stated 1-sigma and
writes a dataset folder in the documented format.  The effect is recorded only by the caller (the
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
from .effects import EffectValues
from .fit import ModelSettings
from .model import Observation, RigHistory, rig_defaults

# the parameters a dataset states even at the thesis rig's values
LEGACY_STATED = ("k", "clearance", "depth", "diameter", "mu", "free_length")


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
    # profiles clipped at zero depth (as a user who refuses negative readings
    # would); False: the raw readings, noise around zero included
    clip_negative: bool = True


# The thesis's own test (Ch. 7): 21,400 cycles, the bore measured at four
# inspections (360 points, a 6 um form tracer), the bushing weighed at the
# same inspections, the joint force over the first cycle; the last inspection
# held out.
CAMPAIGN_21400 = Plan(
    cycles=21400.0, profile_cycles=(5350.0, 10700.0, 16050.0, 21400.0), profile_angles=360,
    profile_sigma=6.0e-6, volume_cycles=(5350.0, 10700.0, 16050.0, 21400.0),
    force_cycles=(0.0,), holdout_from_cycles=21400.0, clip_negative=False)


def synthesize(folder, *, name: str, effects: EffectValues | None = None, seed: int = 0,
               plan: Plan = Plan(), settings: ModelSettings = ModelSettings(model=RigHistory),
               truth: dict | None = None, distort=None, description: str = "",
               stated: dict | None = None, overwrite: bool = False) -> Dataset:
    """Write a synthetic dataset to ``folder`` (see module notes).  ``effects``:
    the effects in the data (default none).  ``truth``: rig parameters (SI)
    that differ from the thesis rig; the dataset states the thesis values
    (or ``stated``) for them, the calibration must move the fitted ones (a
    parameter not fitted is the model error a suspect should name).
    ``distort(theta, cycles) -> extra depth [m]``: an outside-library effect
    added to every measured profile."""
    rng = np.random.default_rng(seed)
    model = settings.build(plan.cycles, (*plan.profile_cycles, *plan.volume_cycles))
    base = {**rig_defaults(), **(stated or {})}
    true = {**rig_defaults(), **(truth or {})}
    effects = EffectValues.zero() if effects is None else effects
    history = jax.jit(model)({k: jnp.asarray(v) for k, v in true.items()}, effects)
    if not bool(history.ok):
        raise RuntimeError("synthesize: the model failed")

    def observe(kind, x, cycles=0.0, basis="mass"):
        return np.asarray(Observation(kind, np.asarray(x, float), cycles=cycles,
                                      basis=basis)(history))

    def held(counts):
        return np.asarray(counts, float) >= plan.holdout_from_cycles

    series = []
    theta = 2 * np.pi * np.arange(plan.profile_angles) / plan.profile_angles
    for n in plan.profile_cycles:
        depth = observe("profile", theta, n)
        if distort is not None:
            depth = depth + distort(theta, n)
        depth = depth + rng.normal(0.0, plan.profile_sigma, theta.shape)
        if plan.clip_negative:
            depth = np.maximum(depth, 0.0)
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
        elif key in (stated or {}) or key in LEGACY_STATED:
            params[key] = Parameter(key, value if key in (stated or {}) else true[key])
    return write_dataset(folder, name=name, description=description, preset="rig",
                         parameters=params, series=series, bushing_density=PTFE_DENSITY,
                         holdout_from_cycles=plan.holdout_from_cycles, overwrite=overwrite)
