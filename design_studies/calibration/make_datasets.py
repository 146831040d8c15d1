"""Generate the shipped synthetic measured datasets.

Each dataset is the rig model (`diffwear.calibrate.model.RigHistory`) with ONE
effect switched on, sampled by the standard campaign (`synthetic.Plan`: worn
profiles at 500/1000/1500/2000 cycles, the bushing weighed every 250 cycles,
the joint force over the first cycle; measurements at >= 1500 cycles held
out) plus Gaussian noise.  The effect and its strength are recorded HERE only,
never in the dataset folders: `diffwear calibrate` has to find them.
The true rig also differs from the stated thesis values (k 20 % higher, a
spring free length 10 mm longer) so that the base fit has work to do.

    python design_studies/calibration/make_datasets.py [--overwrite]

tests/test_calibrate.py (long tests) checks that `calibrate` names each
effect and recovers its strength; the README lists the results.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)

from diffwear.calibrate.model import rig_defaults  # noqa: E402
from diffwear.calibrate.synthetic import synthesize  # noqa: E402

HERE = Path(__file__).resolve().parent
_D = rig_defaults()
TRUTH = {"k": 1.2 * _D["k"], "free_length": _D["free_length"] + 0.010}


def oval_bore(theta, cycles, amplitude=4e-6, angle=0.3):
    """Outside the library: a bore machined 8 um oval (depth offset up to 4 um
    against the nominal circle, present from the start)."""
    return amplitude * (1.0 + np.cos(2.0 * (theta - angle)))


# name -> (effect, strength, distortion, seed, description)
# pressure_exponent was 0.5 at first: identified (0.528 +- 0.056) but its
# held-out error before the effect was only 1.87 sigma, so no model could cut
# it threefold (the identification bar); at 1.0 (wear ~ p^2, within the exponents
# reported for polymers) the effect stands clear of the noise.
DATASETS = {
    "synthetic_run_in": ("run_in", 2.0, None, 11, "Rig campaign A (synthetic)"),
    "synthetic_pressure_exponent": ("pressure_exponent", 1.0, None, 12,
                                    "Rig campaign B (synthetic)"),
    "synthetic_creep": ("creep", 0.3, None, 13, "Rig campaign C (synthetic)"),
    "synthetic_guide_friction": ("guide_friction", 0.15, None, 14, "Rig campaign D (synthetic)"),
    "synthetic_no_effect": (None, 0.0, None, 15, "Rig campaign E (synthetic)"),
    "synthetic_outside_library": (None, 0.0, oval_bore, 16, "Rig campaign F (synthetic)"),
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--overwrite", action="store_true")
    ap.add_argument("--only", nargs="*", default=None, help="dataset names")
    args = ap.parse_args(argv)
    for name, (effect, strength, distort, seed, text) in DATASETS.items():
        if args.only and name not in args.only:
            continue
        synthesize(HERE / name, name=name.replace("_", "-"), effect=effect, strength=strength,
                   seed=seed, truth=TRUTH, distort=distort, description=text,
                   overwrite=args.overwrite)
        print("wrote", HERE / name)


if __name__ == "__main__":
    main()
