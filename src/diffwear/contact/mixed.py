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
- **Asperities**: the Greenwood-Tripp asperity pressure of the two rough
  surfaces (`GreenwoodTripp`, contact/asperities.py), in series with the
  bushing's elastic foundation (`ElasticFoundation`, the bulk layer the
  bushing's asperities stand on).  At each node of the bushing grid the
  rigid-body gap g_k = c(theta_k) - e . u_k (the local film) sets the common
  pressure p_k = p_a(h_k) = k_f (h_k - g_k): the bulk, compressed by p_k /
  k_f, opens the mean surfaces' separation h_k.  So the asperities start to
  carry load smoothly as the film thins (p_a(3 sigma) / p_a(0) = 3e-4, p_a(4
  sigma) / p_a(0) = 4e-6), stiffen as they are pressed past the mean
  surfaces, and there the foundation's stiffness with the asperity layer's
  compliance in series stops the pin (`GreenwoodTripp.on_foundation`).  The
  foundation's Kelvin-Voigt damping acts on the pair: p_k + tau k_s,k
  delta_dot_k, k_s,k the pair's stiffness (0 out of contact, k_f deep in it);
  where the rebound's damping would pull, the pressure tends to zero without
  a sign change (p^2 / (p - d) for a damping term d < 0).  Friction: the dry
  joint's Coulomb friction on each node's asperity load (boundary friction).
- **Wear** (Archard) comes from the asperity pressure only: a separated film
  does not wear the bushing.

lambda_c = 3 (`ONSET_FILM_RATIO`, the onset of mixed lubrication in the
regimes above) is kept as the film thickness reported as the asperities'
onset and where the quasi-static solver's dry start places the pin; the
contact law itself has no onset.  The asperities are elastic (Greenwood-Tripp
assumes no plastic flow of the summits) and their parameters (summit density
and radius) are stated, not measured (`diffwear.contact.asperities`: their
defaults and sources).
"""

from __future__ import annotations

from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_positive, concrete, float_leaf
from ..errors import InputError
from ..mechanism.geometry import dot2, safe_angle
from . import smoothing
from .asperities import GreenwoodTripp
from .friction import CoulombFriction
from .kinematics import ContactResult, PinKinematics
from .laws import OFFSET_NORM_WIDTH, AbstractContactLaw, ElasticFoundation, _interp_periodic
from .lubrication import AbstractFilm, FilmForce, _safe_unit
from .profile import BushingProfile

# Film parameter lambda = h_min / sigma reported as the onset of asperity
# contact: 3, the boundary between full-film and mixed lubrication (Hamrock,
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
# Added to the denominator of the damping's saturation p d / (p - d): 1e-9 Pa,
# far below any pressure that matters (the damping of a node is cut by
# 1e-9 Pa / p), and it keeps the derivative finite where the asperity
# pressure's Gaussian tail underflows (p = 0 beyond lambda ~ 38).
PRESSURE_FLOOR = 1e-9  # Pa


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
            unworn bore; its saturation is replaced by lambda_b's
        asperity: the `ElasticFoundation` of the bushing (the dry law): the
            bulk layer under the asperities
        roughness: the `GreenwoodTripp` asperity law of the two surfaces, or
            the combined RMS roughness sigma [m] (> 0) alone (then
            `GreenwoodTripp(sigma)`: default summits, steel on PTFE)
        boundary_ratio: lambda_b, the film parameter where the film is
            saturated (> 0, at most lambda_c = 3; default 1)
    """

    film: AbstractFilm
    asperity: ElasticFoundation
    summits: GreenwoodTripp
    boundary_ratio: Float[Array, ""]

    def __init__(self, film, asperity, roughness, boundary_ratio=BOUNDARY_FILM_RATIO):
        if not isinstance(film, AbstractFilm):
            raise InputError(f"the film of a lubricated joint must be a film law "
                             f"(ShortBearingFilm, LongBearingFilm), got {film!r}")
        if not isinstance(asperity, ElasticFoundation):
            raise InputError("the asperity contact of a lubricated joint must be an "
                             f"ElasticFoundation, got {type(asperity).__name__}")
        summits = roughness if isinstance(roughness, GreenwoodTripp) else GreenwoodTripp(roughness)
        check_positive("film ratio at the film's saturation lambda_b", boundary_ratio)
        lb = concrete(boundary_ratio)
        if lb is not None and lb > ONSET_FILM_RATIO:
            raise InputError(f"film ratio at the film's saturation lambda_b = {float(lb)} must "
                             f"lie in (0, {ONSET_FILM_RATIO:g}] (the onset of mixed lubrication "
                             "lambda_c)")
        self.film = film
        self.asperity = asperity
        self.summits = summits
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
    def roughness(self) -> Float[Array, ""]:
        """Combined RMS roughness sigma [m] (the asperity law's)."""
        return self.summits.roughness

    @property
    def onset_ratio(self) -> Float[Array, ""]:
        """lambda_c = 3: the film parameter reported as the onset of mixed
        lubrication (module notes)."""
        return jnp.asarray(ONSET_FILM_RATIO)

    @property
    def onset_gap(self) -> Float[Array, ""]:
        """lambda_c sigma [m]: the film thickness reported as the asperities'
        onset."""
        return self.onset_ratio * self.roughness

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

    def asperity_pressure(self, kin: PinKinematics, profile: BushingProfile):
        """The asperity pressure p_k [Pa] on the bushing grid: Greenwood-Tripp
        in series with the foundation at the local gap, with the pair's
        damping (module notes)."""
        bulk = self.asperity
        u = profile.normals
        gap = profile.clearance - dot2(u, kin.offset)
        p, k_s = self.summits.on_foundation(gap, bulk.stiffness)
        d = bulk.damping_time * k_s * dot2(u, kin.offset_rate)
        # p + d, tending to 0 without a sign change where d < 0 (module notes);
        # the floor keeps the ratio's derivative finite where p underflows
        den = p + smoothing.ramp(-d, bulk.stiffness * bulk.penetration_width) + PRESSURE_FLOOR
        return p + d * p / den

    def lubrication(self, kin: PinKinematics, memory: Float[Array, " m"],
                    profile: BushingProfile, friction: CoulombFriction) -> Lubrication:
        """The film's and the asperities' parts (see `Lubrication`)."""
        film = self.saturated_film().film(kin)
        asperity = self.asperity.resultant(kin, profile, self.asperity_pressure(kin, profile),
                                           friction)
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
