"""Hydrodynamic film force of a lubricated pin in a bushing: the short
(Ocvirk) journal bearing with squeeze and wedge action and the Gumbel
(half-Sommerfeld) cavitation condition.

The law returns the force and the viscous friction torque of the oil film on
the pin, in the bushing frame, and the minimum film thickness.  It is an
`AbstractContactLaw`, so a `ClearanceJoint` can carry it, but it models the
film only: no asperity contact (mixed lubrication) and no wear.

Model (derived below, in the notation of `PinKinematics`): the bushing is
at rest in its own frame, the pin centre sits at e = eps c n (n the unit vector
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
The forces grow like (1 - eps^2)^(-5/2): the film is evaluated at the pin's
own eccentricity ratio up to eps_max - w and, beyond, at
eps_max - w + w (1 - exp(-(eps - eps_max + w) / w)) (w =
``saturation_width``), with the same centre velocity e_dot: exact up to
eps_max - w, C1, never at a larger eps than the pin's, finite and
differentiable for every offset; the film force stops growing as eps_f
tends to eps_max and a contact law must carry the rest (see
docs/notes/lubricated-joint.md).
"""

from __future__ import annotations

import abc
from typing import NamedTuple

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_positive, check_range, concrete, float_leaf
from ..errors import InputError
from ..mechanism.geometry import perp
from .friction import CoulombFriction
from .kinematics import ContactResult, PinKinematics
from .laws import OFFSET_NORM_WIDTH, AbstractContactLaw
from .profile import BushingProfile

# Largest eccentricity ratio at which the film is evaluated: 0.95.  The forces
# grow like (1 - eps^2)^(-5/2) (x 160 from eps = 0.5 to 0.95, x 50 more to
# 0.99).  At 0.95 the minimum film of a c = 0.1 mm joint is 5 um: with two
# fine-turned surfaces (Ra ~ 1 um, Rq ~ 1.25 Ra each, combined
# sigma = sqrt(2) 1.25 um ~ 1.8 um) the film parameter h_min / sigma is ~ 3,
# where asperity contact (mixed lubrication) begins and the smooth-film model
# stops being valid.
MAX_ECCENTRICITY_RATIO = 0.95
# Width of the saturation below eps_max: the film is exact up to eps_max - w =
# 0.94 and, past it, evaluated at 0.94 + w (1 - exp(-(eps - 0.94) / w)), below
# the pin's eps and below eps_max.
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
    NaN in the derivatives there ("double where", as in `laws.py`).  v is first
    divided by its largest component, so that a tiny v (|v|^2 below the
    smallest double, e.g. components of 1e-170) still has a unit direction."""
    is_zero = jnp.all(v == 0.0)
    v_safe = jnp.where(is_zero, jnp.array([1.0, 0.0]), v)
    # the scale drops out of both results, so its derivative is not needed (and
    # would divide by scale^2, which underflows for such a v)
    scale = jax.lax.stop_gradient(jnp.max(jnp.abs(v_safe)))
    w = v_safe / scale
    norm_w = jnp.sqrt(w @ w)  # in [1, sqrt 2]
    return w / norm_w, jnp.where(is_zero, 0.0, scale * norm_w)


def _half_film_excess(eps, cos1, sin1):
    """(I_cc - pi/2, I_cs, I_ss - pi/2): the integrals of cos^2, sin cos and sin^2
    of psi over (1 - eps cos psi)^3 on the half psi_1 < psi < psi_1 + pi, less
    their value pi/2, 0, pi/2 at eps = 0, with cos1 = cos psi_1, sin1 = sin psi_1
    and 0 <= eps < 1.

    Antiderivatives (D = 1 - eps cos psi, beta = sqrt(1 - eps^2); each checked
    by differentiating, and against quadrature in the tests):

        cos^2 / D^3:   sin psi (a + b cos psi) / D^2 + k Phi,
                       a = 3 eps / (2 beta^4), b = (1 - 4 eps^2) / (2 beta^4),
                       k = (1 + 2 eps^2) / (2 beta^4)
        sin cos / D^3: -cos^2 psi / (2 D^2)
        sin^2 / D^3:   sin psi (eps - cos psi) / (2 beta^2 D^2) + Phi / (2 beta^2)
        1 / D:         Phi = (psi + 2 atan(eps sin psi / (1 + beta - eps cos psi))) / beta

    (a, b, k from matching the derivative of sin psi (a + b cos psi) / D^2 + k Phi,
    a polynomial in cos psi over D^3, to the integrand.)  Phi is the continuous
    form of 2 / beta atan(sqrt((1 + eps) / (1 - eps)) tan(psi / 2)): its atan
    argument has the denominator 1 + beta - eps cos psi >= 1 + beta - eps > 0, so
    it has no branch jump and the half need not avoid psi = pi.

    Between psi_1 and psi_1 + pi (where cos = -cos1, sin = -sin1), with
    d1, d2 = 1 -+ eps cos1 and P = (d1 d2)^2: 1/d1^2 + 1/d2^2 = 2 (1 + eps^2 cos1^2) / P,
    1/d1^2 - 1/d2^2 = 4 eps cos1 / P, and Phi grows by (pi + tau) / beta,
    tau = -2 atan(eps sin1 / (1 + beta + eps cos1)) - 2 atan(eps sin1 / (1 + beta - eps cos1)).
    The constant parts are taken out exactly:
    pi k / beta - pi/2 = pi eps^2 (1 / (1 + beta) + 2 (1 + beta) - eps^2 beta) / (2 beta^5)
    and pi / (2 beta^3) - pi/2 = pi eps^2 (1 + beta + beta^2) / (2 (1 + beta) beta^3)
    (from 1 - beta = eps^2 / (1 + beta)), so every excess is an explicit multiple
    of eps: near e = 0 the force's dependence on the direction of e (whose
    derivative grows like 1 / |e|) is not a difference of large terms.
    """
    eps2 = eps**2
    beta2 = 1.0 - eps2
    beta = jnp.sqrt(beta2)
    p = (1.0 - eps2 * cos1**2) ** 2  # (d1 d2)^2
    tau = (-2.0 * jnp.arctan(eps * sin1 / (1.0 + beta + eps * cos1))
           - 2.0 * jnp.arctan(eps * sin1 / (1.0 + beta - eps * cos1)))
    a = 3.0 * eps / (2.0 * beta2**2)
    b = (1.0 - 4.0 * eps2) / (2.0 * beta2**2)
    k = (1.0 + 2.0 * eps2) / (2.0 * beta2**2)
    beta3, beta5 = beta2 * beta, beta2**2 * beta
    excess_cc = (-sin1 * a * 2.0 * (1.0 + eps2 * cos1**2) / p
                 - 4.0 * eps * b * sin1 * cos1**2 / p + k * tau / beta
                 + jnp.pi * eps2 * (1.0 / (1.0 + beta) + 2.0 * (1.0 + beta) - eps2 * beta)
                 / (2.0 * beta5))
    integral_cs = 2.0 * eps * cos1**3 / p
    excess_ss = (eps * sin1 * (4.0 * cos1**2 - 2.0 - 2.0 * eps2 * cos1**2) / (2.0 * beta2 * p)
                 + tau / (2.0 * beta3)
                 + jnp.pi * eps2 * (1.0 + beta + beta2) / (2.0 * (1.0 + beta) * beta3))
    return excess_cc, integral_cs, excess_ss


def _half_film_integrals(eps, cos1, sin1):
    """(I_cc, I_cs, I_ss) over the half psi_1 < psi < psi_1 + pi (see
    `_half_film_excess`)."""
    excess_cc, integral_cs, excess_ss = _half_film_excess(eps, cos1, sin1)
    return 0.5 * jnp.pi + excess_cc, integral_cs, 0.5 * jnp.pi + excess_ss


class AbstractFilm(AbstractContactLaw):
    """What the journal-bearing films share: the oil and bore parameters (float64
    array leaves, `float_leaf`), their checks, the saturation of the eccentricity
    ratio at eps_max, the minimum film thickness and the film as a contact law.
    The force in the line-of-centres frame (`film`, `line_of_centres_forces`)
    is shared too; a subclass gives its scale `_film_factor` and its part beyond
    eps = 0, `_excess_components`, and must read the parameters from the fields
    on every call (a mixed-lubrication law swaps ``max_eccentricity_ratio`` with
    `eqx.tree_at`)."""

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
        self.viscosity = float_leaf(viscosity)
        self.length = float_leaf(length)
        self.clearance = float_leaf(clearance)
        self.max_eccentricity_ratio = float_leaf(max_eccentricity_ratio)
        self.saturation_width = float_leaf(saturation_width)

    def min_film_thickness(self, kin: PinKinematics) -> Float[Array, ""]:
        """h_min = c - |e| = c (1 - eps) [m] (smooth norm, finite at e = 0)."""
        e = kin.offset
        return self.clearance - jnp.sqrt(e @ e + OFFSET_NORM_WIDTH**2)

    def _saturated(self, eps):
        """The eccentricity ratio the film is evaluated at: the pin's own eps up
        to eps_max - w (to the last bit) and eps_max - w + w (1 - exp(-(eps -
        eps_max + w) / w)) beyond, C1, never above the pin's eps (1 - exp(-x)
        <= x: the film is never evaluated thicker-loaded than the pin's) and
        tending to eps_max; w = ``saturation_width``."""
        width = self.saturation_width
        onset = self.max_eccentricity_ratio - width
        over = jnp.maximum(eps - onset, 0.0)
        return jnp.where(eps <= onset, eps, onset - width * jnp.expm1(-over / width))

    def _torque(self, eps_f, tangential, omega, radius):
        """Viscous moment on the pin [N m] from the film's tangential force
        F_t [N]: the Couette shear over the whole circumference plus the Poiseuille
        part, -(e / 2) F_t, the same for both films (module docstrings)."""
        couette = (2.0 * jnp.pi * self.viscosity * omega * radius**3 * self.length
                   / (self.clearance * jnp.sqrt(1.0 - eps_f**2)))
        return -couette - 0.5 * eps_f * self.clearance * tangential

    @abc.abstractmethod
    def steady_peak_pressure(self, eccentricity_ratio, omega, radius):
        """The film's largest pressure [Pa] with the journal centre at rest
        (the soft-bore check: it deflects the bore by p / k_f)."""

    @abc.abstractmethod
    def _film_factor(self, radius):
        """K [N s]: the film's scale, its eps = 0 forces being -K pi/2 (A n - B t)
        with A = 2 eps_dot, B = eps (omega - 2 gamma_dot)."""

    @abc.abstractmethod
    def _excess_components(self, eps_f, squeeze, wedge, radius):
        """The film force along n and t [N] beyond its eps = 0 values, from the
        saturated eps, A = 2 eps_dot and B = eps omega - 2 eps gamma_dot [1/s]."""

    def line_of_centres_forces(self, eccentricity_ratio, eccentricity_rate, line_rate,
                               omega, radius):
        """(F_n, F_t, T): the film force on the pin along the line of centres
        (F_n, positive away from the bushing centre) and normal to it (F_t,
        along k x n) [N], and its moment on the pin [N m], from the
        eccentricity ratio eps, its rate eps_dot [1/s], the line-of-centres
        angular rate gamma_dot [rad/s], the pin's spin omega relative to the
        bushing [rad/s] and the journal radius R [m].  The classical form; it
        needs eps > 0 for gamma_dot to exist (`film` works from the offset and
        is safe at e = 0).  Past eps_max the film is that at eps_max with the
        same centre velocity (eps_dot, eps gamma_dot), as in `film`."""
        eps = jnp.asarray(eccentricity_ratio, dtype=float)
        eps_f = self._saturated(eps)
        squeeze = 2.0 * jnp.asarray(eccentricity_rate, dtype=float)
        wedge = eps_f * omega - 2.0 * eps * jnp.asarray(line_rate, dtype=float)
        excess_n, excess_t = self._excess_components(eps_f, squeeze, wedge, radius)
        k = self._film_factor(radius)
        radial = -0.5 * jnp.pi * k * squeeze + excess_n
        tangential = 0.5 * jnp.pi * k * wedge + excess_t
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
        excess_n, excess_t = self._excess_components(eps_f, squeeze, wedge, kin.pin_radius)
        # the eps = 0 part -K pi/2 (A n - B t) = -K pi/2 (2 e_dot / c - eps_f omega t)
        # (K the film's `_film_factor`),
        # written from e and e_dot (eps t = k x e / c below the saturation), so that it
        # does not depend on the direction n, which is lost at e -> 0
        saturation_loss = (eps - eps_f) * t
        centred = -0.5 * jnp.pi * self._film_factor(kin.pin_radius) * (
            2.0 * kin.offset_rate / self.clearance
            - kin.omega * (perp(kin.offset) / self.clearance - saturation_loss))
        force = centred + excess_n * n + excess_t * t
        tangential = force @ t
        return FilmForce(force=force,
                         torque=self._torque(eps_f, tangential, kin.omega, kin.pin_radius),
                         radial=force @ n, tangential=tangential, eccentricity_ratio=eps,
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


class ShortBearingFilm(AbstractFilm):
    """Short-bearing (Ocvirk) hydrodynamic film with squeeze and wedge action
    and Gumbel cavitation (the model, its derivation and its limits are in the
    module docstring and docs/notes/lubricated-joint.md).

    Arguments (each a float64 array leaf, `float_leaf`: sweep or differentiate them):
        viscosity: dynamic viscosity mu of the oil [Pa s] (> 0)
        length: axial length L of the bearing [m] (> 0; short-bearing theory
            wants L / D < ~0.5)
        clearance: radial clearance c of the round bore [m] (> 0); the film
            uses it, not a worn `BushingProfile`
        max_eccentricity_ratio: eps_max in (0, 1), default 0.95; the film is
            evaluated at the pin's eps up to eps_max - w and saturates towards eps_max
        saturation_width: width w of the saturation below eps_max, in
            (0, eps_max), default 0.01

    Journal radius R: the pin radius of the `PinKinematics` (wedge speed
    U = omega R and film area 2 pi R L; the bore radius differs by c << R).

    References: Flores, Ambrosio, Claro & Lankarani, Mech. Mach. Theory 41
    (2006) 247-261 (short-bearing pressure and forces of a dynamically loaded
    journal bearing in a multibody joint); Daniel, Machado & Cavalca, Mech.
    Mach. Theory 99 (2016) 19-36 (positive-pressure region that moves with the
    squeeze); Hamrock, Schmid & Jacobson, Fundamentals of Fluid Film
    Lubrication (steady short-bearing load, attitude and friction).
    """

    def steady_peak_pressure(self, eccentricity_ratio, omega, radius):
        """The film's largest pressure [Pa] with the centre at rest (e_dot = 0):
        the maximum over psi of 3 mu L^2 / (4 c^2) eps |omega| |sin psi| /
        (1 - eps cos psi)^3 (the module's pressure at z = 0), on a 2048-point
        grid; at the saturated eps, like the force."""
        eps = self._saturated(jnp.asarray(eccentricity_ratio, dtype=float))
        psi = jnp.linspace(0.0, jnp.pi, 2048)
        shape = jnp.max(jnp.sin(psi) / (1.0 - eps * jnp.cos(psi)) ** 3)
        return (3.0 * self.viscosity * self.length**2 / (4.0 * self.clearance**2)
                * eps * jnp.abs(omega) * shape)

    def _film_factor(self, radius):
        """K = mu R L^3 / (2 c^2) [N s]: the pressure 3 mu / c^2 (L^2/4 - z^2) times
        the area R dtheta dz, integrated over z (L^3 / 6)."""
        return self.viscosity * radius * self.length**3 / (2.0 * self.clearance**2)

    def _excess_components(self, eps_f, squeeze, wedge, radius):
        """The parts of F_n = -K (A I_cc - B I_cs) and F_t = -K (A I_cs - B I_ss)
        [N] beyond their eps = 0 values -K pi/2 A and K pi/2 B, from the
        saturated eps, A = 2 eps_dot and B = eps omega - 2 eps gamma_dot [1/s]."""
        # the positive half starts at psi_1 = psi_V - pi/2, psi_V the direction of
        # V ~ (A, -B) from n: cos psi_1 = -B / |V|, sin psi_1 = -A / |V|.  At V = 0
        # the film carries nothing and any half will do (the force is A, B times it).
        v_dir, _ = _safe_unit(jnp.stack([squeeze, wedge]))
        cos1, sin1 = -v_dir[1], -v_dir[0]
        excess_cc, integral_cs, excess_ss = _half_film_excess(eps_f, cos1, sin1)
        k = self._film_factor(radius)
        return (-k * (squeeze * excess_cc - wedge * integral_cs),
                -k * (squeeze * integral_cs - wedge * excess_ss))
