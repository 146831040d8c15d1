"""Study ``rig-lubricated``: the thesis Ch. 7 rig with its crank-rod joint in oil.

The rig of ``rig-21400`` (Tables 7-1 .. 7-3) with the wearing joint
lubricated (`MixedLubrication`: the film `default_film` gives the bushing,
the finite-length one at its L/D = 0.69, plus the bushing's asperities),
worn over the rig's 21,400 cycles on the quasi-static model; the oil and
the roughness are those of the shipped mechanism file
``rig_lubricated.toml`` (its comments give their sources).  Beside the wear
outputs of the other wear studies it writes the film over the cycle on the
unworn bushing.  The thesis's rig ran dry: there are no thesis values to
compare with; the dry rig's are in the report.
"""

from __future__ import annotations

from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import plots
from ..contact import MixedLubrication, default_film, oils
from ..io import OutputDir
from ..models import QuasiStatic
from ..presets import RIG_CYCLES, RIG_JOINT
from ..report import Bullets
from . import _wear_common as common
from . import rig_21400

NAME = "rig-lubricated"
DESCRIPTION = ("Ch. 7 rig with its crank-rod joint in oil (mixed lubrication): quasi-static "
               "wear over 21,400 cycles, film thickness and load share")

# ISO VG 10 spindle oil at the rig's room temperature, 25 degC (ASTM D341 from
# the grade, diffwear.contact.oils: 15.0 mPa s); combined RMS roughness of a
# ground steel pin (Ra 0.2 um) and a fine-bored PTFE bore (Ra 0.5 um),
# Rq = 1.25 Ra: sqrt(0.25^2 + 0.62^2) um (rig_lubricated.toml gives the sources).
OIL, TEMPERATURE = "ISO VG 10", "25 degC"
VISCOSITY = oils.grade(OIL).viscosity(oils.parse_temperature(TEMPERATURE))  # Pa s
ROUGHNESS = 0.65e-6  # m
# The dry rig's quasi-static result (rig-21400 --model quasi-static, README).
DRY = {"max_wear_depth_mm": 0.4449, "wear_volume_mm3": 106.71}


def lubricated(mech, viscosity=VISCOSITY, roughness=ROUGHNESS):
    """``mech`` with its crank-rod joint in oil of ``viscosity`` [Pa s] on
    surfaces of combined roughness ``roughness`` [m]."""
    el = mech.element(common.JOINT)
    c = el.bushing_radius - el.pin_radius
    film = default_film(viscosity, el.law.depth, c, el.pin_radius,
                        MixedLubrication.saturation(roughness, c))
    law = MixedLubrication(film, el.law, roughness)
    return eqx.tree_at(lambda m: m.element(common.JOINT).law, mech, law)


def run(out: OutputDir, *, cycles: int = RIG_CYCLES, log=print) -> dict:
    _, dry, y0 = rig_21400._setup()
    mech = lubricated(dry)
    model = QuasiStatic()
    joint = common.JOINT

    @jax.jit
    def film(y):
        loads = model.loads(mech, (joint,), y, rig_21400.PERIOD).joints[0]
        qs = model.joints(mech, (joint,))[0]
        return qs.equilibrium(jnp.zeros(qs.n), loads)

    eq = film(y0)
    law = mech.element(joint).law
    crank = 360.0 * np.arange(model.samples) / model.samples
    out.csv("film.csv", {"crank_angle_deg": crank,
                         "h_min_um": np.asarray(eq.min_film_thickness) * 1e6,
                         "film_ratio": np.asarray(eq.film_ratio),
                         "interference_um": np.asarray(eq.interference) * 1e6,
                         "asperity_share": np.asarray(eq.asperity_share),
                         "film_load_N": np.asarray(eq.film_load),
                         "asperity_load_N": np.asarray(eq.normal_load)})
    plots.film_panels(out.file("film.png"), crank,
                      {"unworn": (np.asarray(eq.min_film_thickness),
                                  np.asarray(eq.asperity_share),
                                  np.asarray(eq.interference))},
                      onset=float(law.onset_gap), onset_ratio=float(law.onset_ratio),
                      roughness=ROUGHNESS,
                      title=f"{NAME}: film over the cycle, unworn bushing "
                            f"(μ = {VISCOSITY:g} Pa s, σ = {ROUGHNESS * 1e6:.3g} µm)")
    pressed = float(jnp.max(eq.interference)) * 1e6  # um past the mean surfaces
    lube: dict[str, Any] = {
        "viscosity_Pa_s": VISCOSITY, "roughness_um": ROUGHNESS * 1e6,
        "film": type(law.film).__name__,
        "min_film_thickness_um": float(jnp.min(eq.min_film_thickness)) * 1e6,
        "film_ratio_min": float(jnp.min(eq.film_ratio)),
        "max_interference_um": pressed,
        "asperity_load_share": float(jnp.mean(eq.asperity_share)),
        "film_solves_converged": bool(eq.ok)}
    words = Bullets([
        f"oil {VISCOSITY * 1e3:.3g} mPa s ({OIL} at {TEMPERATURE}), combined roughness "
        f"{ROUGHNESS * 1e6:g} um: over the unworn bushing's cycle the thinnest film is "
        f"{lube['min_film_thickness_um']:.3g} um, lambda = h_min / sigma "
        f"{lube['film_ratio_min']:.3g} (> 3 full film, 1-3 mixed, < 1 boundary)"
        + (f", and where no film is left the pin presses the asperities up to "
           f"{pressed:.3g} um past the mean surfaces" if pressed > 0.0 else "")
        + f"; the asperities carry {100 * lube['asperity_load_share']:.3g} % of the load on "
        "average "
        "([film.png](film.png), [film.csv](film.csv))",
        f"the dry rig (rig-21400, quasi-static): {DRY['max_wear_depth_mm']} mm, "
        f"{DRY['wear_volume_mm3']} mm^3 over the same cycles"])
    study = common.WearStudy(
        name=NAME, mech_of=_itself, p=mech, design=RIG_JOINT, y0=y0, period=rig_21400.PERIOD,
        thesis={},
        description=("The Ch. 7 rig (rig-21400) with its crank-rod joint lubricated: film "
                     "(the finite-length Reynolds film) and asperities share the load, only the "
                     "asperities wear the bushing."),
        extra_summary={"lubricant": lube, "dry": DRY}, extra_report=(words,))
    return common.run_wear_study(out, study, cycles=cycles, model=model, log=log)


def _itself(mech):
    return mech
