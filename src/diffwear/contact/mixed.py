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

- **Film**: a hydrodynamic film law (`ShortBearingFilm` or `LongBearingFilm`),
  evaluated on the clearance of the (worn) bore at the line of centres,
  c_e = c(theta_e), so that h_min = c_e - |e|.  Its smooth-surface Reynolds
  solution stops being valid at lambda = lambda_c: the film is saturated at
  eps_max = 1 - lambda_c sigma / c_e (kept within [`MIN_SATURATION`,
  `MAX_SATURATION`]); past it the film force stops growing.
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

from .._checks import check_positive, float_leaf
from ..errors import InputError
from ..mechanism.geometry import safe_angle
from .friction import CoulombFriction
from .kinematics import ContactResult, PinKinematics
from .laws import AbstractContactLaw, ElasticFoundation, _interp_periodic
from .lubrication import FilmForce, _safe_unit
from .profile import BushingProfile

# Film parameter lambda = h_min / sigma at which the asperities start to carry
# load: 3, the boundary between full-film and mixed lubrication (Hamrock,
# Schmid & Jacobson, Fundamentals of Fluid Film Lubrication).
ONSET_FILM_RATIO = 3.0
# Bounds of the film's saturation eps_max = 1 - lambda_c sigma / c_e: a rough,
# tight joint (c_e < 6 sigma) still has a film up to eps = 0.5 (the asperities
# carry beside it), and a smooth one's film is cut at 0.99, where the short
# bearing's force has grown 2,500-fold from eps = 0 to 0.5's 1.8-fold.
MIN_SATURATION, MAX_SATURATION = 0.5, 0.99


class Lubrication(NamedTuple):
    """The film and the asperities of a lubricated joint at one instant.

    film: the film's `FilmForce` (on the pin, bushing frame)
    asperity: the asperities' `ContactResult` (their force, friction torque,
        normal load and pressure on the bushing grid)
    film_load: |film force| [N]
    asperity_load: the asperities' normal load [N]
    min_film_thickness: h_min = c_e - |e| [m]
    film_ratio: lambda = h_min / sigma [-]
    """

    film: FilmForce
    asperity: ContactResult
    film_load: Float[Array, ""]
    asperity_load: Float[Array, ""]
    min_film_thickness: Float[Array, ""]
    film_ratio: Float[Array, ""]

    @property
    def asperity_share(self) -> Float[Array, ""]:
        """asperity load / (asperity + film load): 0 for a full film, 1 dry."""
        total = self.asperity_load + self.film_load
        return self.asperity_load / jnp.where(total > 0.0, total, 1.0)


class MixedLubrication(AbstractContactLaw):
    """A lubricated clearance joint: hydrodynamic film plus asperity contact
    (module notes).

    Arguments:
        film: the film law (`ShortBearingFilm` or `LongBearingFilm`); its
            viscosity and length are used, its clearance and saturation are
            replaced at each evaluation by the worn bore's and lambda_c's
        asperity: the `ElasticFoundation` of the bushing (the dry law)
        roughness: combined RMS roughness sigma of pin and bushing [m] (> 0)
        onset_ratio: lambda_c, the film parameter where the asperities touch
            (> 0, default 3)
    """

    film: AbstractContactLaw
    asperity: ElasticFoundation
    roughness: Float[Array, ""]
    onset_ratio: Float[Array, ""]

    def __init__(self, film, asperity, roughness, onset_ratio=ONSET_FILM_RATIO):
        if not all(hasattr(film, f) for f in ("film", "clearance", "max_eccentricity_ratio")):
            raise InputError(f"the film of a lubricated joint must be a film law "
                             f"(ShortBearingFilm, LongBearingFilm), got {film!r}")
        if not isinstance(asperity, ElasticFoundation):
            raise InputError("the asperity contact of a lubricated joint must be an "
                             f"ElasticFoundation, got {type(asperity).__name__}")
        check_positive("combined RMS roughness sigma [m]", roughness)
        check_positive("film ratio at the asperity onset lambda_c", onset_ratio)
        self.film = film
        self.asperity = asperity
        self.roughness = float_leaf(roughness)
        self.onset_ratio = float_leaf(onset_ratio)

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

    def local_film(self, kin: PinKinematics, profile: BushingProfile) -> AbstractContactLaw:
        """The film law on the bore's clearance at the line of centres, saturated
        where lambda reaches lambda_c."""
        c_e = _interp_periodic(profile.clearance, safe_angle(kin.offset))
        eps_max = jnp.clip(1.0 - self.onset_gap / c_e, MIN_SATURATION, MAX_SATURATION)
        return eqx.tree_at(lambda f: (f.clearance, f.max_eccentricity_ratio), self.film,
                           (c_e, eps_max))

    def lubrication(self, kin: PinKinematics, memory: Float[Array, " m"],
                    profile: BushingProfile, friction: CoulombFriction) -> Lubrication:
        """The film's and the asperities' parts (see `Lubrication`)."""
        local = self.local_film(kin, profile)
        film = local.film(kin)
        asperity = self.asperity.evaluate(kin, memory, self.summits(profile), friction)
        _, film_load = _safe_unit(film.force)
        h_min = film.min_film_thickness
        return Lubrication(film=film, asperity=asperity, film_load=film_load,
                           asperity_load=asperity.normal_load, min_film_thickness=h_min,
                           film_ratio=h_min / self.roughness)

    def evaluate(self, kin, memory, profile, friction):
        """Film plus asperities: their forces and torques add; normal_load and
        pressure are the asperities' (the load that wears, Archard)."""
        parts = self.lubrication(kin, memory, profile, friction)
        return ContactResult(force=parts.film.force + parts.asperity.force,
                             torque=parts.film.torque + parts.asperity.torque,
                             normal_load=parts.asperity.normal_load,
                             pressure=parts.asperity.pressure,
                             memory_rate=parts.asperity.memory_rate)
