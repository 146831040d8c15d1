"""Generate the shipped synthetic measured datasets.

Each dataset is the dynamic rig model (`diffwear.calibrate.model.RigHistory`,
the reference the faster models are checked against) with at most ONE effect
switched on, sampled by a campaign plan plus Gaussian noise:

* ``synthetic_*`` (2,000 cycles, `synthetic.Plan`): worn profiles at
  500/1000/1500/2000 cycles, the bushing weighed every 250 cycles, the joint
  force over the first cycle and near the end; measurements at >= 1500
  cycles held out.  Made with 80 dynamic cycles (A = 25): within 0.08 um of
  A = 12.5 on the profiles, so the data carry the physics, not a coarse step.
* ``campaign_*`` (21,400 cycles, `synthetic.CAMPAIGN_21400`, the thesis's own
  Ch. 7 test): four inspections of 360-point profiles (6 um noise, negative
  readings kept), weighings at the same inspections, the force over the first
  cycle; the last inspection held out.  Made with 214 dynamic cycles (A = 100),
  the two campaigns of run-in with creep with the quasi-static model (see
  their entries).

The effect and its strength are recorded HERE only, never in the dataset
folders: `diffwear calibrate` has to find them.  The true rig also differs from
the stated thesis values (k 20 % higher, a spring free length 10 mm longer) so
that the base fit has work to do.

    python design_studies/calibration/make_datasets.py [--overwrite] [--only NAME ...]

tests/test_calibrate_campaigns.py (long tests) checks that `calibrate` names
each effect and recovers its strength and shape.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)

from diffwear.calibrate.discrepancy import SIZES  # noqa: E402
from diffwear.calibrate.effects import EffectValues  # noqa: E402
from diffwear.calibrate.fit import ModelSettings  # noqa: E402
from diffwear.calibrate.model import RigHistory, rig_defaults  # noqa: E402
from diffwear.calibrate.quasi_static import QuasiStaticRigHistory  # noqa: E402
from diffwear.calibrate.synthetic import CAMPAIGN_21400, Plan, synthesize  # noqa: E402

HERE = Path(__file__).resolve().parent
_D = rig_defaults()
TRUTH = {"k": 1.2 * _D["k"], "free_length": _D["free_length"] + 0.010}
SHORT = ModelSettings(model=RigHistory, dynamic_cycles=80)
LONG = ModelSettings(model=RigHistory, dynamic_cycles=214)
QUASI_STATIC = ModelSettings(model=QuasiStaticRigHistory)


def lobed_k(lobes: int, peak_deg: float, amplitude: float = 0.6) -> EffectValues:
    """Outside the library: a wear coefficient that varies with the bushing
    angle, k (1 + a cos(m (theta - theta_peak))) (``lobes`` = m peaks, e.g. an
    anisotropic fibre lay or the seam of a wrapped bushing), written in the
    learned discrepancy's angle basis (cos / sin of order m)."""
    c = np.zeros(SIZES["angle"])
    phase = lobes * np.radians(peak_deg)
    c[2 * (lobes - 1)] = amplitude * np.cos(phase)
    c[2 * (lobes - 1) + 1] = amplitude * np.sin(phase)
    return EffectValues.zero().with_discrepancy("angle", c)


def oval_bore(theta, cycles, amplitude=4e-6, angle=0.3):
    """Outside the library: a bore machined 8 um oval (depth offset up to 4 um
    against the nominal circle, present from the start)."""
    return amplitude * (1.0 + np.cos(2.0 * (theta - angle)))


def lobed_bore(theta, cycles, amplitude=6e-6, angle=0.5):
    """Outside the library: a three-lobed bore (the lobing a three-jaw chuck
    leaves), up to 12 um over the nominal circle, present from the start."""
    return amplitude * (1.0 + np.cos(3.0 * (theta - angle)))


def coating(thickness: float, inside: float, width: float = 15e-6):
    """Outside the library and the discrepancy's bases: a bore coated with a
    layer ``thickness`` [m] thick whose wear coefficient is ``inside`` times
    the bulk's; once the local depth passes it the rate steps to the bulk's
    over ``width`` (a smoothed step in the depth of each node)."""
    import jax.numpy as jnp

    def factor(theta, depth, cycles):
        through = 0.5 * (1.0 + jnp.tanh((depth - thickness) / width))
        return inside + (1.0 - inside) * through

    factor.words = (f"a layer {thickness * 1e3:g} mm thick wearing at {inside:.2g} x the bulk's "
                    "rate")
    return EffectValues.zero().with_outside(factor)


def humidity(amplitude: float, period: float, phase: float = 0.0,
             base: EffectValues | None = None):
    """Outside the library: a wear coefficient that follows the laboratory's
    humidity over the test, k (1 + a sin(2 pi N / period + phase)): up, down
    and up again over the 21,400 cycles (polymer wear is humidity-sensitive:
    e.g. PTFE's rate rises several-fold in humid air, Lancaster 1971)."""
    import jax.numpy as jnp

    def factor(theta, depth, cycles):
        return 1.0 + amplitude * jnp.sin(2.0 * jnp.pi * cycles / period + phase) + 0.0 * depth

    factor.words = f"k x (1 + {amplitude:g} sin(2 pi N / {period:,.0f}))"
    return (base or EffectValues.zero()).with_outside(factor)


def run_in_beside_lobes() -> EffectValues:
    """A run-in (x2 at the start over 4,000 cycles) beside a three-lobed k."""
    lobes = lobed_k(3, 23.0)
    return EffectValues.of(run_in=1.0, run_in_cycles=4000.0).with_discrepancy(
        "angle", lobes.discrepancy[:SIZES["angle"]])


# name -> (effects, plan, settings, truth, distortion, seed, description)
# pressure_exponent was 0.5 at first: identified but its held-out error before
# the effect was only 1.87 sigma; at 1.0 (wear ~ p^2, within the exponents
# reported for polymers) the effect stands clear of the noise.
DATASETS = {
    "synthetic_run_in": (EffectValues.of(run_in=2.0), Plan(), SHORT, TRUTH, None, 11,
                         "Rig campaign A (synthetic)"),
    "synthetic_pressure_exponent": (EffectValues.of(pressure_exponent=1.0), Plan(), SHORT, TRUTH,
                                    None, 12, "Rig campaign B (synthetic)"),
    "synthetic_creep": (EffectValues.of(creep=0.3), Plan(), SHORT, TRUTH, None, 13,
                        "Rig campaign C (synthetic)"),
    "synthetic_guide_friction": (EffectValues.of(guide_friction=0.15), Plan(), SHORT, TRUTH,
                                 None, 14, "Rig campaign D (synthetic)"),
    "synthetic_no_effect": (None, Plan(), SHORT, TRUTH, None, 15, "Rig campaign E (synthetic)"),
    "synthetic_outside_library": (None, Plan(), SHORT, TRUTH, oval_bore, 16,
                                  "Rig campaign F (synthetic)"),
    # run-in six times slower than the library's default time scale
    "campaign_slow_run_in": (EffectValues.of(run_in=1.5, run_in_cycles=3000.0), CAMPAIGN_21400,
                             LONG, TRUTH, None, 21, "21,400-cycle rig campaign G (synthetic)"),
    "campaign_clean": (None, CAMPAIGN_21400, LONG, TRUTH, None, 22,
                       "21,400-cycle rig campaign H (synthetic)"),
    "campaign_lobed_bore": (None, CAMPAIGN_21400, LONG, TRUTH, lobed_bore, 23,
                            "21,400-cycle rig campaign I (synthetic)"),
    # a clean campaign on a rig whose crank is 1.5x the stated one
    "campaign_long_crank": (None, CAMPAIGN_21400, LONG,
                            {**TRUTH, "crank_length": 1.5 * _D["crank_length"]}, None, 24,
                            "21,400-cycle rig campaign J (synthetic)"),
    # a pressure-dependent wear law (wear ~ p^2); run-in is the tempting
    # alternative (an early excess of wear also steepens the first inspections)
    "campaign_pressure_exponent": (EffectValues.of(pressure_exponent=1.0), CAMPAIGN_21400, LONG,
                                   TRUTH, None, 25, "21,400-cycle rig campaign K (synthetic)"),
    # two effects at once, each strong enough for these inspections: the slow
    # run-in of campaign G and a creeping bushing (the profile grows 15 % more
    # than the mass says).  Made with the quasi-static model, the one the loop
    # fits, so that they test the selection and not the model: made with the
    # dynamic model, the quasi-static fit prefers a transfer film, creep and
    # a pressure exponent of -0.5 (chi2 1209), which the dynamic check then
    # fits at 15,173, and the report warns that the fit does not carry over.
    # (A pressure exponent of 0.6 beside a run-in of 2.5 over 2,000 cycles is
    # not strong enough: the run-in's time scale absorbs it, score 1.2.)
    "campaign_run_in_and_creep": (
        EffectValues.of(run_in=1.5, run_in_cycles=3000.0, creep=0.15),
        CAMPAIGN_21400, QUASI_STATIC, TRUTH, None, 26, "21,400-cycle rig campaign L (synthetic)"),
    # the same run-in with creep below what these data can detect
    "campaign_run_in_weak_creep": (
        EffectValues.of(run_in=1.5, run_in_cycles=3000.0, creep=0.002),
        CAMPAIGN_21400, QUASI_STATIC, TRUTH, None, 27,
        "21,400-cycle rig campaign M (synthetic)"),
    # outside the library: k varies with the bushing angle (two and three lobes)
    "campaign_two_lobe_k": (lobed_k(2, 40.0), CAMPAIGN_21400, LONG, TRUTH, None, 28,
                            "21,400-cycle rig campaign N (synthetic)"),
    "campaign_three_lobe_k": (lobed_k(3, 23.0), CAMPAIGN_21400, LONG, TRUTH, None, 29,
                              "21,400-cycle rig campaign O (synthetic)"),
    # a run-in over the first 30 cycles, half as strong again as the base
    # rate: about 0.07 mm^3 of extra wear, under 2 sigma of a weighing, long
    # before the first inspection: these inspections cannot show it
    "campaign_unseen_run_in": (EffectValues.of(run_in=0.5, run_in_cycles=30.0), CAMPAIGN_21400,
                               LONG, TRUTH, None, 31, "21,400-cycle rig campaign P (synthetic)"),
    # outside the library and the discrepancy's bases: a hard coating 60 um
    # thick wearing at a third of the bulk's rate, worn through between the
    # first and the second inspection (at 0.25 mm it would still hold at the
    # last: the data could not show it)
    "campaign_coating_worn_through": (coating(60e-6, 1.0 / 3.0, 6e-6), CAMPAIGN_21400, LONG,
                                      TRUTH, None, 32, "21,400-cycle rig campaign Q (synthetic)"),
    # a low-wear skin 0.1 mm thick (half the bulk's rate): a library effect
    # (debris raising the rate with the worn volume) fits the fit window
    "campaign_low_wear_skin": (coating(0.1e-3, 0.5, 10e-6), CAMPAIGN_21400, LONG, TRUTH, None,
                               33, "21,400-cycle rig campaign R (synthetic)"),
    # a wear coefficient that swings with the laboratory's humidity
    "campaign_humidity_k": (humidity(0.4, 14000.0), CAMPAIGN_21400, LONG, TRUTH, None, 34,
                            "21,400-cycle rig campaign S (synthetic)"),
    # a run-in beside a three-lobed k: both must be named
    "campaign_run_in_and_lobes": (run_in_beside_lobes(), CAMPAIGN_21400, LONG, TRUTH, None, 35,
                                  "21,400-cycle rig campaign T (synthetic)"),
}

# What the calibration must answer on each campaign whose answer is not the
# single strongest effect of its truth (tests/test_calibrate.py, long):
# "effects": the effects to be named; "below_limit": effects present but
# below what these data detect (named nowhere, their detection limit above
# the truth); "discrepancy": the learned discrepancy's variable and lobes.
EXPECT = {
    "campaign_run_in_and_creep": {"effects": ("run_in", "creep")},
    "campaign_run_in_weak_creep": {"effects": ("run_in",), "below_limit": ("creep",)},
    "campaign_two_lobe_k": {"effects": (), "discrepancy": ("angle", 2, (40.0, 220.0))},
    "campaign_three_lobe_k": {"effects": (), "discrepancy": ("angle", 3, (23.0, 143.0, 263.0))},
    "campaign_unseen_run_in": {"effects": ()},
    "campaign_coating_worn_through": {"effects": (), "discrepancy": ("depth",)},
    "campaign_low_wear_skin": {"effects": (), "discrepancy": ("depth",)},
    "campaign_humidity_k": {"effects": (), "discrepancy": ("cycles",)},
    "campaign_run_in_and_lobes": {"effects": ("run_in",),
                                  "discrepancy": ("angle", 3, (23.0, 143.0, 263.0))},
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--overwrite", action="store_true")
    ap.add_argument("--only", nargs="*", default=None, help="dataset names")
    args = ap.parse_args(argv)
    for name, (effects, plan, settings, truth, distort, seed, text) in DATASETS.items():
        if args.only and name not in args.only:
            continue
        synthesize(HERE / name, name=name.replace("_", "-"), effects=effects, plan=plan,
                   settings=settings, seed=seed, truth=truth, distort=distort,
                   description=text, overwrite=args.overwrite)
        print("wrote", HERE / name, flush=True)


if __name__ == "__main__":
    main()
