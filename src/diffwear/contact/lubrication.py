"""Hydrodynamic film force of a lubricated pin in a bushing: the short
(Ocvirk) journal bearing with squeeze and wedge action and the Gumbel
(half-Sommerfeld) cavitation condition.

The law returns the force and the viscous friction torque of the oil film on
the pin, in the bushing frame, and the minimum film thickness.  It is a
`AbstractContactLaw`, so a `ClearanceJoint` can carry it, but it models the
film only: no asperity contact (mixed lubrication) and no wear.

Model (derived below, in the notation of `PinKinematics`): the bushing is
still in its own frame, the pin centre sits at e = eps c n (n the unit vector
along the line of centres, t = k x n, c the radial clearance) and spins at
omega relative to the bushing.  At the bushing angle theta = gamma + psi the
film is h = c (1 - eps cos psi) (to first order in c / R).  Dropping the
circumferential pressure flow (short bearing, Ocvirk) the Reynolds equation
is

    d/dz (h^3 dp/dz) = 6 mu (omega dh/dtheta + 2 dh/dt),        p(z = +-L/2) = 0,

with dh/dtheta = eps c sin psi and dh/dt = -(eps_dot c cos psi + eps c
gamma_dot sin psi) at a fixed bushing point, so

    p(psi, z) = 3 mu / c^2 (L^2/4 - z^2) [2 eps_dot cos psi
                - eps (omega - 2 gamma_dot) sin psi] / (1 - eps cos psi)^3.

This is the short-bearing pressure of a dynamically loaded journal bearing
used for lubricated revolute joints by Flores, Ambrosio, Claro & Lankarani,
Mech. Mach. Theory 41 (2006) 247-261 (and Flores et al., Kinematics and
dynamics of multibody systems with imperfect joints, Springer 2008), written
here with psi measured from the minimum film; the wedge speed
omega_journal + omega_bearing - 2 gamma_dot of the inertial-frame form is
omega - 2 gamma_dot with the bushing at rest.

**Cavitation (Gumbel).**  p is set to zero where it is negative.  Its sign is
that of the bracket, which does not depend on z:

    2 eps_dot cos psi - eps (omega - 2 gamma_dot) sin psi = (V . u(theta)) / c,
    V = 2 e_dot - omega k x e,

so the pressure is positive on exactly one half of the film, the half centred
on the direction of V.  In steady running (e_dot = 0, omega > 0) that is the
classical half pi < psi < 2 pi, from the widest gap to the minimum film; in
pure squeeze (omega = 0) it is the half facing the approach e_dot.  The
widely used closed-form dynamic forces integrate over the steady half whatever
the squeeze (their squeeze term pi (1 + 2 eps^2) / (1 - eps^2)^(5/2) is that
half's integral of cos^2 psi / (1 - eps cos psi)^3, see
`_half_film_integrals`); here the half follows V, as Daniel, Machado &
Cavalca, Mech. Mach. Theory 99 (2016) 19-36, argue for joints of mechanisms:
integrate over the time-dependent region of positive pressure.

**Forces on the pin** (F = -int int p u(theta) R dtheta dz, int (L^2/4 - z^2)
dz = L^3 / 6), with K = mu R L^3 / (2 c^2), A = 2 eps_dot,
B = eps (omega - 2 gamma_dot) and the positive half psi_1 < psi < psi_1 + pi:

    F_n = -K (A I_cc - B I_cs),      F_t = -K (A I_cs - B I_ss),
    I_xy = integral over the half of x(psi) y(psi) / (1 - eps cos psi)^3.

The three integrals have the closed forms of `_half_film_integrals` (derived
there, checked against quadrature in tests/test_lubrication.py).  Over the
steady half they give F_n = -2 K eps^2 omega / (1 - eps^2)^2 and
F_t = K pi eps omega / (2 (1 - eps^2)^(3/2)): the short-bearing load
W = mu U L^3 eps / (4 c^2 (1 - eps^2)^2) sqrt(16 eps^2 + pi^2 (1 - eps^2)),
U = omega R, at the attitude tan phi = pi sqrt(1 - eps^2) / (4 eps)
(Hamrock, Schmid & Jacobson, Fundamentals of Fluid Film Lubrication, the
short-width journal bearing).

**Friction torque on the pin.**  The film's shear on the journal surface is
tau = mu omega R / h + (h / 2R) dp/dpsi (Couette plus Poiseuille, bushing at
rest).  Its moment about the pin centre, the Couette part taken over the
whole circumference (the cavitated zone still shears oil, as in Petroff's law
and the usual short-bearing friction) and the Poiseuille part integrated by
parts (p is continuous and periodic):

    T = -2 pi mu omega R^3 L / (c sqrt(1 - eps^2)) - (e / 2) F_t,   e = eps c.

At eps = 0 this is Petroff's torque -2 pi mu omega R^3 L / c.  The bushing
receives -T - e x F (the oil is in moment balance).

**Validity.**  Short-bearing theory needs L / D below about 0.5 (it
overestimates the load of longer bearings), an incompressible isoviscous
Newtonian film, laminar flow, rigid surfaces, an aligned journal and c << R.
The forces grow like (1 - eps^2)^(-5/2): the film is evaluated at the
eccentricity ratio min(eps, eps_max) (a C1 blend of width
``saturation_width`` below eps_max), so it stays finite and differentiable for
every offset; beyond eps_max the film force stops growing and a contact law
must carry the load (see docs/notes/lubricated-joint.md).
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_positive, check_range, concrete
from ..errors import InputError
from ..mechanism.geometry import perp
from . import smoothing
from .friction import CoulombFriction
from .kinematics import ContactResult, PinKinematics
from .laws import OFFSET_NORM_WIDTH, AbstractContactLaw
from .profile import BushingProfile

# Largest eccentricity ratio at which the film is evaluated: 0.95.  The forces
# grow like (1 - eps^2)^(-5/2) (x 100 from eps = 0.5 to 0.95, x 2000 to 0.99);
# at 0.95 the minimum film of a c = 0.1 mm joint is 5 um, a few roughness
# heights of a turned or honed bore (Ra 0.4..1.6 um), where asperity contact
# (mixed lubrication) begins and the smooth-film model stops being valid.
MAX_ECCENTRICITY_RATIO = 0.95
# Width of the blend into the saturation: the film is exact up to
# eps_max - 0.01 = 0.94 and C1 across the band.
SATURATION_WIDTH = 0.01


class FilmForce(NamedTuple):
    """The oil film's action on the pin, in the bushing frame.

    force: force on the pin [N]
    torque: viscous friction moment on the pin about its centre [N m]
    radial: force component along the line of centres n = e / |e| [N]
        (negative: pushes the pin back towards the bushing centre)
    tangential: component along t = k x n [N]
    eccentricity_ratio: eps = |e| / c (not saturated) [-]
    min_film_thickness: h_min = c - |e| = c (1 - eps) [m] (negative once the
        pin reaches past the round bore)
    """

    force: Float[Array, "2"]
    torque: Float[Array, ""]
    radial: Float[Array, ""]
    tangential: Float[Array, ""]
    eccentricity_ratio: Float[Array, ""]
    min_film_thickness: Float[Array, ""]


def _safe_unit(v: Float[Array, "2"]) -> tuple[Float[Array, "2"], Float[Array, ""]]:
    """(v / |v|, |v|), with the direction (1, 0) and length 0 at v = 0 and no
    NaN in the derivatives there ("double where", as in `laws.py`)."""
    is_zero = jnp.all(v == 0.0)
    v_safe = jnp.where(is_zero, jnp.array([1.0, 0.0]), v)
    norm_safe = jnp.sqrt(v_safe @ v_safe)
    return v_safe / norm_safe, jnp.where(is_zero, 0.0, norm_safe)


def _half_film_integrals(eps, cos1, sin1):
    """(I_cc, I_cs, I_ss): the integrals of cos^2, sin cos and sin^2 of psi over
    (1 - eps cos psi)^3 on the half psi_1 < psi < psi_1 + pi, with
    cos1 = cos psi_1, sin1 = sin psi_1 and 0 <= eps < 1.

    Antiderivatives (D = 1 - eps cos psi, beta = sqrt(1 - eps^2); each checked
    by differentiating, and against quadrature in the tests):

        1 / D^3 cos^2:   sin psi (a + b cos psi) / D^2 + k Phi,
                         a = 3 eps / (2 beta^4), b = (1 - 4 eps^2) / (2 beta^4),
                         k = (1 + 2 eps^2) / (2 beta^4)
        1 / D^3 sin cos: -cos^2 psi / (2 D^2)
        1 / D^3 sin^2:   sin psi (eps - cos psi) / (2 beta^2 D^2) + Phi / (2 beta^2)
        1 / D:           Phi = (psi + 2 atan(eps sin psi / (1 + beta - eps cos psi))) / beta

    (a, b, k from matching the derivative of sin psi (a + b cos psi) / D^2 + k Phi,
    a polynomial in cos psi over D^3, to the integrand.)  Phi is the continuous
    form of 2 / beta atan(sqrt((1 + eps) / (1 - eps)) tan(psi / 2)): its atan
    argument has the denominator 1 + beta - eps cos psi >= beta + 1 - eps > 0, so
    it has no branch jump and the half need not avoid psi = pi.  At the far end
    psi_1 + pi: cos = -cos1, sin = -sin1.  None of the forms divides by eps.
    """
    beta2 = 1.0 - eps**2
    beta = jnp.sqrt(beta2)
    d1 = 1.0 - eps * cos1  # film at psi_1, over c
    d2 = 1.0 + eps * cos1  # film at psi_1 + pi, over c
    delta_phi = (jnp.pi
                 - 2.0 * jnp.arctan(eps * sin1 / (1.0 + beta + eps * cos1))
                 - 2.0 * jnp.arctan(eps * sin1 / (1.0 + beta - eps * cos1))) / beta
    a = 3.0 * eps / (2.0 * beta2**2)
    b = (1.0 - 4.0 * eps**2) / (2.0 * beta2**2)
    k = (1.0 + 2.0 * eps**2) / (2.0 * beta2**2)
    i_cc = -sin1 * (a - b * cos1) / d2**2 - sin1 * (a + b * cos1) / d1**2 + k * delta_phi
    # -cos^2/(2 D^2) from psi_1 to psi_1 + pi: (cos1^2 / 2)(1/d1^2 - 1/d2^2), with
    # d2^2 - d1^2 = 4 eps cos1
    i_cs = 2.0 * eps * cos1**3 / (d1 * d2) ** 2
    i_ss = (-sin1 * (eps + cos1) / d2**2 - sin1 * (eps - cos1) / d1**2
            + delta_phi) / (2.0 * beta2)
    return i_cc, i_cs, i_ss


class ShortBearingFilm(AbstractContactLaw):
    """Short-bearing (Ocvirk) hydrodynamic film with squeeze and wedge action
    and Gumbel cavitation (the model, its derivation and its limits are in the
    module docstring and docs/notes/lubricated-joint.md).

    Arguments (each a float64 array leaf: sweep or differentiate them):
        viscosity: dynamic viscosity mu of the oil [Pa s] (> 0)
        length: axial length L of the bearing [m] (> 0; short-bearing theory
            wants L / D < ~0.5)
        clearance: radial clearance c of the round bore [m] (> 0); the film
            uses it, not a worn `BushingProfile`
        max_eccentricity_ratio: eps_max in (0, 1), default 0.95; the film is
            evaluated at min(eps, eps_max) (C1 blend of ``saturation_width``)
        saturation_width: width of that blend, in (0, eps_max), default 0.01

    Journal radius R: the pin radius of the `PinKinematics` (wedge speed
    U = omega R and film area 2 pi R L; the bore radius differs by c << R).

    References: Flores, Ambrosio, Claro & Lankarani, Mech. Mach. Theory 41
    (2006) 247-261 (short-bearing pressure and forces of a dynamically loaded
    journal bearing in a multibody joint); Daniel, Machado & Cavalca, Mech.
    Mach. Theory 99 (2016) 19-36 (positive-pressure region that moves with the
    squeeze); Hamrock, Schmid & Jacobson, Fundamentals of Fluid Film
    Lubrication (steady short-bearing load, attitude and friction).
    """

    viscosity: Float[Array, ""]
    length: Float[Array, ""]
    clearance: Float[Array, ""]
    max_eccentricity_ratio: Float[Array, ""]
    saturation_width: Float[Array, ""]

    def __init__(self, viscosity, length, clearance,
                 max_eccentricity_ratio=MAX_ECCENTRICITY_RATIO,
                 saturation_width=SATURATION_WIDTH):
        check_positive("lubricant viscosity mu [Pa s]", viscosity)
        check_positive("bearing length L [m]", length)
        check_positive("radial clearance c [m]", clearance)
        check_range("maximum eccentricity ratio eps_max", max_eccentricity_ratio,
                    0.0, 1.0, low_open=True, high_open=True)
        check_range("eccentricity saturation width", saturation_width, 0.0, 1.0,
                    low_open=True, high_open=True)
        eps_max, width = concrete(max_eccentricity_ratio), concrete(saturation_width)
        if eps_max is not None and width is not None and width >= eps_max:
            raise InputError(f"eccentricity saturation width {float(width)} must be smaller "
                             f"than the maximum eccentricity ratio {float(eps_max)}")
        for what, value in [("lubricant viscosity mu [Pa s]", viscosity),
                            ("bearing length L [m]", length),
                            ("radial clearance c [m]", clearance)]:
            v = concrete(value)
            if v is not None and v.ndim != 0:
                raise InputError(f"{what} must be a scalar, got shape {v.shape}")
        self.viscosity = jnp.asarray(viscosity, dtype=float)
        self.length = jnp.asarray(length, dtype=float)
        self.clearance = jnp.asarray(clearance, dtype=float)
        self.max_eccentricity_ratio = jnp.asarray(max_eccentricity_ratio, dtype=float)
        self.saturation_width = jnp.asarray(saturation_width, dtype=float)

    def min_film_thickness(self, kin: PinKinematics) -> Float[Array, ""]:
        """h_min = c - |e| = c (1 - eps) [m] (smooth norm, finite at e = 0)."""
        e = kin.offset
        return self.clearance - jnp.sqrt(e @ e + OFFSET_NORM_WIDTH**2)

    def _saturated(self, eps):
        """min(eps, eps_max) = eps_max - ramp(eps_max - eps): exact below
        eps_max - saturation_width, C1 across the band."""
        return self.max_eccentricity_ratio - smoothing.ramp(
            self.max_eccentricity_ratio - eps, self.saturation_width)

    def _components(self, eps_f, squeeze, wedge, radius):
        """(F_n, F_t) on the pin along n and t = k x n [N] from the saturated
        eps, A = 2 eps_dot and B = eps (omega - 2 gamma_dot) [1/s]."""
        # the positive half starts at psi_1 = psi_V - pi/2, psi_V the direction of
        # V ~ (A, -B) from n: cos psi_1 = -B / |V|, sin psi_1 = -A / |V|.  At V = 0
        # the film carries nothing and any half will do (the force is A, B times it).
        v_dir, _ = _safe_unit(jnp.stack([squeeze, wedge]))
        cos1, sin1 = -v_dir[1], -v_dir[0]
        i_cc, i_cs, i_ss = _half_film_integrals(eps_f, cos1, sin1)
        k = self.viscosity * radius * self.length**3 / (2.0 * self.clearance**2)
        return -k * (squeeze * i_cc - wedge * i_cs), -k * (squeeze * i_cs - wedge * i_ss)

    def _torque(self, eps_f, tangential, omega, radius):
        """Viscous moment on the pin [N m] (module docstring)."""
        couette = (2.0 * jnp.pi * self.viscosity * omega * radius**3 * self.length
                   / (self.clearance * jnp.sqrt(1.0 - eps_f**2)))
        return -couette - 0.5 * eps_f * self.clearance * tangential

    def line_of_centres_forces(self, eccentricity_ratio, eccentricity_rate, line_rate,
                               omega, radius):
        """(F_n, F_t, T): the film force on the pin along the line of centres
        (F_n, positive away from the bushing centre) and normal to it (F_t,
        along k x n) [N], and its moment on the pin [N m], from the
        eccentricity ratio eps, its rate eps_dot [1/s], the line-of-centres
        angular rate gamma_dot [rad/s], the pin's spin omega relative to the
        bushing [rad/s] and the journal radius R [m].  The classical form; it
        needs eps > 0 for gamma_dot to exist (`film` works from the offset and
        is safe at e = 0)."""
        eps_f = self._saturated(jnp.asarray(eccentricity_ratio, dtype=float))
        squeeze = 2.0 * jnp.asarray(eccentricity_rate, dtype=float)
        wedge = eps_f * (omega - 2.0 * jnp.asarray(line_rate, dtype=float))
        radial, tangential = self._components(eps_f, squeeze, wedge, radius)
        return radial, tangential, self._torque(eps_f, tangential, omega, radius)

    def film(self, kin: PinKinematics) -> FilmForce:
        """Force and friction torque of the film on the pin (see `FilmForce`)."""
        n, dist = _safe_unit(kin.offset)
        t = perp(n)
        eps = dist / self.clearance
        eps_f = self._saturated(eps)
        # A = 2 eps_dot and B = eps (omega - 2 gamma_dot), written without gamma_dot
        # (singular at e = 0): eps_dot = n . e_dot / c and eps gamma_dot = t . e_dot / c
        squeeze = 2.0 * (n @ kin.offset_rate) / self.clearance
        wedge = eps_f * kin.omega - 2.0 * (t @ kin.offset_rate) / self.clearance
        radial, tangential = self._components(eps_f, squeeze, wedge, kin.pin_radius)
        return FilmForce(force=radial * n + tangential * t,
                         torque=self._torque(eps_f, tangential, kin.omega, kin.pin_radius),
                         radial=radial, tangential=tangential, eccentricity_ratio=eps,
                         min_film_thickness=self.min_film_thickness(kin))

    def evaluate(self, kin: PinKinematics, memory: Float[Array, " m"],
                 profile: BushingProfile, friction: CoulombFriction) -> ContactResult:
        """The film as a contact law: its force and viscous torque; normal_load
        is the film's load |F| [N]; pressure is zero (no solid contact on the
        bushing grid, so no wear); the profile and Coulomb friction are not
        used (the film's friction is viscous)."""
        f = self.film(kin)
        _, load = _safe_unit(f.force)
        return ContactResult(force=f.force, torque=f.torque, normal_load=load,
                             pressure=jnp.zeros(profile.n), memory_rate=jnp.zeros(0))
