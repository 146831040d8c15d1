"""Mixed lubrication of a pin in a bushing: the oil film and the asperities
share the load.

A lubricated joint carries its load on a hydrodynamic film while the film is
thick compared with the surface roughness, and partly on the surfaces' asperities
once it is not (the load-sharing concept of Johnson, Greenwood & Poon, Wear 19
(1972) 91: the load is the sum of the film's and the asperities' shares).  The
film parameter lambda = h_min / sigma, sigma the combined RMS roughness
sqrt(sigma_pin^2 + sigma_bushing^2), names the regime: above 3 full film, 1 to 3
mixed, below 1 boundary (Hamrock, Schmid & Jacobson, Fundamentals of Fluid
Film Lubrication, the film-parameter regimes).

The law here (stated, simple, smooth):

- **Film**: a hydrodynamic film law (`ShortBearingFilm` or `LongBearingFilm`)
  of the unworn round bore (clearance c).  Through the mixed regime it keeps
  growing as the film thins (the asperities carry beside it); at lambda =
  lambda_b (1, boundary lubrication: the film no longer separates the
  surfaces) it is saturated: eps_max = 1 - lambda_b sigma / c (kept within
  [`MIN_SATURATION`, `MAX_SATURATION`]); past it the film force stops
  growing.  (Saturating it where the asperities touch, at lambda_c, left a
  band where neither grows: a film-borne pin settled in the saturation's
  blend and rang at every load reversal.)  The film of a
  worn bore is not modelled: where the wear has deepened the bore, the pin
  sinks into the groove past eps_max and the asperities carry what the
  saturated film does not.  (A film on the local clearance of the worn bore,
  c(theta_e), weakens as the groove deepens, ~ 1 / c^2: that feeds the wear
  back on itself and made the wear's response to the profile indefinite, so
  the implicit wear steps failed; docs/notes/lubricated-joint.md.)
- **Film thickness**: h_min = max(c(theta_e) - |e|, 0), the gap along the
  line of centres on the worn bore, never negative; lambda = h_min / sigma.
  Where the pin is pressed past the mean surfaces (c(theta_e) - |e| < 0, the
  asperities and the bushing compressed) the film thickness is 0 and the
  overlap is reported as the asperity interference |e| - c(theta_e).
- **Asperities**: the elastic foundation (`ElasticFoundation`) of the bushing
  pressed by the asperity summits, which stand lambda_c sigma above the mean
  surfaces: each spring's penetration is delta_k = e . u_k - (c_k -
  lambda_c sigma) = lambda_c sigma - h_k, with h_k the local film.  So the
  asperities start to carry load where the film's validity ends, and with the
  same Coulomb friction as the dry joint (boundary friction).
- **Wear** (Archard) comes from the asperity pressure only: a separated film
  does not wear the bushing.

lambda_c = 3 by default (`ONSET_FILM_RATIO`): the onset of mixed lubrication in
the regimes above.  The asperities' stiffness is the foundation's, not a
statistical asperity model (Greenwood-Williamson): the summits are taken as a
rigid layer on the elastic bushing, so a rough surface's softer first contact
is not modelled (docs/notes/lubricated-joint.md).
"""

from __future__ import annotations

from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_positive, concrete, float_leaf
from ..errors import InputError
from ..mechanism.geometry import safe_angle
from .friction import CoulombFriction
from .kinematics import ContactResult, PinKinematics
from .laws import OFFSET_NORM_WIDTH, AbstractContactLaw, ElasticFoundation, _interp_periodic
from .lubrication import AbstractFilm, FilmForce, _safe_unit
from .profile import BushingProfile

# Film parameter lambda = h_min / sigma at which the asperities start to carry
# load: 3, the boundary between full-film and mixed lubrication (Hamrock,
# Schmid & Jacobson, Fundamentals of Fluid Film Lubrication).
ONSET_FILM_RATIO = 3.0
# Film parameter below which the film no longer separates the surfaces
# (boundary lubrication, same source): the film is saturated there.
BOUNDARY_FILM_RATIO = 1.0
# Bounds of the film's saturation eps_max = 1 - lambda_b sigma / c: a rough,
# tight joint (c < 2 sigma) still has a film up to eps = 0.5 (the asperities
# carry beside it), and a smooth one's film is cut at 0.995, where the short
# bearing's steady load has grown ~ 10,000-fold from its value at eps = 0.5.
MIN_SATURATION, MAX_SATURATION = 0.5, 0.995


def asperity_share(asperity_load, film_load):
    """asperity load / (asperity + film load): 0 for a full film, 1 dry (0
    where neither carries anything)."""
    total = asperity_load + film_load
    return asperity_load / jnp.where(total > 0.0, total, 1.0)


class Lubrication(NamedTuple):
    """The film and the asperities of a lubricated joint at one instant.

    film: the film's `FilmForce` (on the pin, bushing frame)
    asperity: the asperities' `ContactResult` (their force, friction torque,
        normal load and pressure on the bushing grid)
    film_load: |film force| [N]
    asperity_load: the asperities' normal load [N]
    min_film_thickness: h_min = max(c_e - |e|, 0) [m]
    film_ratio: lambda = h_min / sigma [-]
    interference: max(|e| - c_e, 0) [m]: how far the pin presses the asperities
        past the mean surfaces (0 while a gap remains)
    """

    film: FilmForce
    asperity: ContactResult
    film_load: Float[Array, ""]
    asperity_load: Float[Array, ""]
    min_film_thickness: Float[Array, ""]
    film_ratio: Float[Array, ""]
    interference: Float[Array, ""]

    @property
    def asperity_share(self) -> Float[Array, ""]:
        """See `asperity_share`."""
        return asperity_share(self.asperity_load, self.film_load)


class MixedLubrication(AbstractContactLaw):
    """A lubricated clearance joint: hydrodynamic film plus asperity contact
    (module notes).

    Arguments:
        film: the film law (`ShortBearingFilm` or `LongBearingFilm`) of the
            unworn bore; its saturation is replaced by lambda_c's
        asperity: the `ElasticFoundation` of the bushing (the dry law)
        roughness: combined RMS roughness sigma of pin and bushing [m] (> 0)
        onset_ratio: lambda_c, the film parameter where the asperities touch
            (> 0, default 3)
        boundary_ratio: lambda_b, the film parameter where the film is
            saturated (> 0, at most lambda_c; default 1)
    """

    film: AbstractFilm
    asperity: ElasticFoundation
    roughness: Float[Array, ""]
    onset_ratio: Float[Array, ""]
    boundary_ratio: Float[Array, ""]

    def __init__(self, film, asperity, roughness, onset_ratio=ONSET_FILM_RATIO,
                 boundary_ratio=BOUNDARY_FILM_RATIO):
        if not isinstance(film, AbstractFilm):
            raise InputError(f"the film of a lubricated joint must be a film law "
                             f"(ShortBearingFilm, LongBearingFilm), got {film!r}")
        if not isinstance(asperity, ElasticFoundation):
            raise InputError("the asperity contact of a lubricated joint must be an "
                             f"ElasticFoundation, got {type(asperity).__name__}")
        check_positive("combined RMS roughness sigma [m]", roughness)
        check_positive("film ratio at the asperity onset lambda_c", onset_ratio)
        check_positive("film ratio at the film's saturation lambda_b", boundary_ratio)
        lc, lb = concrete(onset_ratio), concrete(boundary_ratio)
        if lc is not None and lb is not None and lb > lc:
            raise InputError(f"film ratio at the film's saturation lambda_b = {float(lb)} must "
                             f"not exceed the asperity onset lambda_c = {float(lc)}")
        self.film = film
        self.asperity = asperity
        self.roughness = float_leaf(roughness)
        self.onset_ratio = float_leaf(onset_ratio)
        self.boundary_ratio = float_leaf(boundary_ratio)

    # the bushing's axial depth and its foundation, as the dry law's (the wear
    # routes read them)
    @property
    def depth(self) -> Float[Array, ""]:
        return self.asperity.depth

    @property
    def solid_contact(self) -> ElasticFoundation:
        return self.asperity

    @property
    def onset_gap(self) -> Float[Array, ""]:
        """lambda_c sigma [m]: the film thickness where the asperities touch."""
        return self.onset_ratio * self.roughness

    def summits(self, profile: BushingProfile) -> BushingProfile:
        """The profile of the asperity summits: the bore less lambda_c sigma."""
        return eqx.tree_at(lambda p: p.clearance, profile, profile.clearance - self.onset_gap)

    @staticmethod
    def saturation(roughness, clearance, boundary_ratio=BOUNDARY_FILM_RATIO):
        """eps_max = 1 - lambda_b sigma / c, kept in [`MIN_SATURATION`,
        `MAX_SATURATION`]: the eccentricity ratio where the film is saturated."""
        return jnp.clip(1.0 - boundary_ratio * roughness / clearance,
                        MIN_SATURATION, MAX_SATURATION)

    def saturated_film(self) -> AbstractFilm:
        """The film law, saturated where lambda reaches lambda_b on the unworn
        bore: eps_max = 1 - lambda_b sigma / c (module notes)."""
        eps_max = self.saturation(self.roughness, self.film.clearance, self.boundary_ratio)
        return eqx.tree_at(lambda f: f.max_eccentricity_ratio, self.film, eps_max)

    def min_film_thickness(self, kin: PinKinematics, profile: BushingProfile):
        """c(theta_e) - |e| [m]: the gap along the line of centres, on the
        (worn) bore; negative where the pin presses the asperities past the
        mean surfaces (`lubrication` reports max(gap, 0) as the film and the
        rest as the interference)."""
        c_e = _interp_periodic(profile.clearance, safe_angle(kin.offset))
        return c_e - jnp.sqrt(kin.offset @ kin.offset + OFFSET_NORM_WIDTH**2)

    def lubrication(self, kin: PinKinematics, memory: Float[Array, " m"],
                    profile: BushingProfile, friction: CoulombFriction) -> Lubrication:
        """The film's and the asperities' parts (see `Lubrication`)."""
        film = self.saturated_film().film(kin)
        asperity = self.asperity.evaluate(kin, memory, self.summits(profile), friction)
        _, film_load = _safe_unit(film.force)
        gap = self.min_film_thickness(kin, profile)
        h_min = jnp.maximum(gap, 0.0)
        return Lubrication(film=film, asperity=asperity, film_load=film_load,
                           asperity_load=asperity.normal_load, min_film_thickness=h_min,
                           film_ratio=h_min / self.roughness,
                           interference=jnp.maximum(-gap, 0.0))

    def evaluate(self, kin, memory, profile, friction):
        """Film plus asperities: their forces and torques add; normal_load and
        pressure are the asperities' (the load that wears, Archard)."""
        parts = self.lubrication(kin, memory, profile, friction)
        return ContactResult(force=parts.film.force + parts.asperity.force,
                             torque=parts.film.torque + parts.asperity.torque,
                             normal_load=parts.asperity.normal_load,
                             pressure=parts.asperity.pressure,
                             memory_rate=parts.asperity.memory_rate)
