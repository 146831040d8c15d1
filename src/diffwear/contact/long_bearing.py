"""Hydrodynamic film force of a lubricated pin in a bushing: the long
(Sommerfeld, infinitely long) journal bearing with squeeze and wedge action
and the Gumbel (half-Sommerfeld) cavitation condition.

The long-bearing counterpart of `ShortBearingFilm` (lubrication.py): the same
parameters, checks, saturation at eps_max and outputs, for bearings whose
length is large against their diameter.  Like it, the law models the film
only: no asperity contact (mixed lubrication) and no wear.

Model (notation of `PinKinematics` and lubrication.py): the bushing is at
rest in its own frame, the pin centre sits at e = eps c n (t = k x n, c the
radial clearance) and spins at omega relative to the bushing; at the bushing
angle theta = gamma + psi the film is h = c (1 - eps cos psi) = c D.
Dropping the axial pressure flow instead of the circumferential one (long
bearing: p does not depend on z) the Reynolds equation is

    d/dtheta (h^3 dp/dtheta) = 6 mu R^2 (omega dh/dtheta + 2 dh/dt),    p periodic,

with dh/dtheta = eps c sin psi and dh/dt = -c (eps_dot cos psi + eps
gamma_dot sin psi) at a fixed bushing point.  With A = 2 eps_dot and
B = eps (omega - 2 gamma_dot) the right-hand side is 6 mu R^2 c (B sin psi -
A cos psi); integrating once (B sin psi = (B / eps c) dh/dpsi, and the flow
constant C / D^3 fixed by the periodicity of p, int_0^2pi dp/dpsi = 0, with
int 1/D^2 = 2 pi / beta^3 and int 1/D^3 = pi (2 + eps^2) / beta^5 over the
period, beta = sqrt(1 - eps^2)):

    dp/dpsi = 6 mu R^2 / c^2 [(B / eps) (1 / D^2 - kappa / D^3) - A sin psi / D^3],
    kappa = 2 beta^2 / (2 + eps^2),

and once more, up to a constant p_0,

    p = 6 mu R^2 / c^2 [-B sin psi (2 - eps cos psi) / ((2 + eps^2) D^2)
                        + A (1 / D^2 - 1) / (2 eps)] + p_0.

The wedge part is Sommerfeld's solution (zero at the minimum and maximum
film); the squeeze part A (1 / D^2 - 1) / (2 eps) -> A cos psi is finite at
eps = 0.  Both share the factor 2 - eps cos psi = 1 + D, so

    p = 6 mu R^2 / c^2 (2 - eps cos psi) / D^2 [A cos psi / 2 - B sin psi / (2 + eps^2)] + p_0
      = 6 mu R^2 (c + h) (V_L . u(theta)) / ((2 c^2 + |e|^2) h^2) + p_0,
    V_L = 2 e_dot + (e . e_dot) e / c^2 - omega k x e

(u(theta) the unit vector of the bushing angle; n . V_L / c = (1 + eps^2 / 2) A
and t . V_L / c = -B).  This is the dynamically loaded long-bearing pressure
used for lubricated revolute joints by Flores, Ambrosio, Claro & Lankarani,
Mech. Mach. Theory 41 (2006) 247-261 (and Flores et al., Kinematics and
dynamics of multibody systems with imperfect joints, Springer 2008), wedge
speed omega - 2 gamma_dot with the bushing at rest, except for the choice of
p_0 and of the region below.

**Cavitation (Gumbel) and the constant p_0.**  A periodic film fixes p only
up to the constant p_0 (the supply level; Sommerfeld's steady solution puts
it at the minimum and maximum film).  Here p_0 = 0: the one constant for
which the pressure is at the ambient level at two diametrically opposite
points of the film, the ends of a half.  (p - p_0 takes equal values at psi
and psi + pi only where V_L . u = 0, where it is zero, because 1 + D > 0.)
The pressure is set to zero where it is negative; its sign is that of
V_L . u(theta), so it is positive on exactly one half of the film, the half
centred on the direction of V_L.  In steady running (e_dot = 0, omega > 0)
that is the classical half pi < psi < 2 pi and the pressure is the
half-Sommerfeld one; in pure squeeze (omega = 0) it is the half facing the
approach (V_L is along e_dot there when e_dot is along e or across it).  It
differs from V = 2 e_dot - omega k x e of the short bearing by the
(e . e_dot) e / c^2 term (the long film's squeeze pressure leans more on the
thin side).  The widely used closed-form dynamic long-bearing forces instead
integrate over the steady half pi .. 2 pi whatever the squeeze and whatever
the sign of omega - 2 gamma_dot, with zero pressure imposed at both of its
ends (a non-periodic squeeze pressure); that region carries negative
pressure in most non-steady states (an attractive force when the wedge
reverses).  Integrating where p > 0, as Daniel, Machado & Cavalca, Mech.
Mach. Theory 99 (2016) 19-36, argue for joints of mechanisms, and as
`ShortBearingFilm` does, keeps the two films comparable.  Another p_0 (e.g.
zero at the maximum film) would make the positive region a different arc;
it would not be a half in general and its ends would need a root finder.

**Forces on the pin** (F = -int p u(theta) R L dtheta over the positive half
psi_1 < psi < psi_1 + pi, integrated by parts: p = 0 at both ends, so
int p cos psi = -int p' sin psi and int p sin psi = int p' cos psi), with
K_L = 6 mu R^3 L / c^2:

    F_n = K_L [B 2 eps c1 (3 - (2 + eps^2) c1^2) / ((2 + eps^2) P) - A I_ss],
    F_t = K_L [B (I_cc - 3 eps I_c / (2 + eps^2)) + A I_cs],
    c1 = cos psi_1,  P = (1 - eps^2 c1^2)^2,
    I_c = integral over the half of cos psi / D^3, I_xy of x(psi) y(psi) / D^3.

(From int_half sin / D^2 = 2 c1 / (P^(1/2)), int_half sin / D^3 = 2 c1 / P and
(B / eps) ((1 - kappa) c - eps c^2), 1 - kappa = 3 eps^2 / (2 + eps^2): no
1 / eps is left.)  I_cc, I_cs, I_ss are the short bearing's
`_half_film_excess`; I_c is `_half_film_cos` below.  Over the steady half
(A = 0, B = eps omega, c1 = -1) they give

    F_n = -12 mu omega R^3 L eps^2 / (c^2 (2 + eps^2) (1 - eps^2)),
    F_t = 6 pi mu omega R^3 L eps / (c^2 (2 + eps^2) sqrt(1 - eps^2)),

the half-Sommerfeld load W = sqrt(F_n^2 + F_t^2) at the attitude
tan phi = pi sqrt(1 - eps^2) / (2 eps) (Hamrock, Schmid & Jacobson,
Fundamentals of Fluid Film Lubrication, the infinitely wide journal bearing;
checked against quadrature in tests/test_long_bearing.py).  At eps = 0 the
film is the centred damper F = -K_L pi / 2 (2 e_dot / c - omega k x e / c),
12 (R / L)^2 times the short bearing's.

**Friction torque on the pin.**  As in the short bearing: the shear on the
journal is tau = mu omega R / h + (h / 2R) dp/dpsi; the Couette part taken
over the whole circumference, the Poiseuille part over the positive half,
where int h p' dpsi = [h p] - int p h' dpsi = -eps c int p sin psi dpsi (p = 0
at the ends, h' = eps c sin psi) = eps c F_t / (R L), so

    T = -2 pi mu omega R^3 L / (c sqrt(1 - eps^2)) - (e / 2) F_t,   e = eps c,

the same form as the short bearing's (`AbstractFilm._torque`), with the
long bearing's F_t; Petroff's torque at eps = 0.

**Validity.**  Long-bearing theory needs L / D above about 2 (it
overestimates the load of shorter bearings, as the short-bearing theory
overestimates that of longer ones: the finite bearing carries less than
either), an incompressible isoviscous Newtonian film, laminar flow, rigid
surfaces, an aligned journal and c << R.  Its forces grow like
(1 - eps^2)^(-3/2) (squeeze) and (1 - eps^2)^(-1) (steady radial): the film is
evaluated at the pin's eps up to eps_max - w and saturates towards eps_max with the
same centre velocity, as the short bearing's, and stops growing past eps_max.
"""

from __future__ import annotations

import jax.numpy as jnp

from .lubrication import (
    AbstractFilm,
    _half_film_excess,
    _safe_unit,
)

__all__ = ["LongBearingFilm"]


def _half_film_cos(eps, cos1, sin1):
    """I_c: the integral of cos psi / (1 - eps cos psi)^3 over the half
    psi_1 < psi < psi_1 + pi, cos1 = cos psi_1, sin1 = sin psi_1, 0 <= eps < 1.

    Antiderivative (D = 1 - eps cos psi, beta = sqrt(1 - eps^2), Phi the
    branch-free integral of 1 / D of `_half_film_excess`):

        sin psi (a + b cos psi) / D^2 + k Phi,
        a = (2 + eps^2) / (2 beta^4), b = -eps (1 + 2 eps^2) / (2 beta^4),
        k = 3 eps / (2 beta^4),

    from matching the derivative of sin psi (a + b cos psi) / D^2 + k Phi,
    ((-b - 2 eps a + k) + (a - eps b - 2 eps k) cos psi
     + (2 b + eps a + eps^2 k) cos^2 psi) / D^3, to cos psi / D^3.  Over the
    half (d1, d2 = 1 -+ eps cos1, P = (d1 d2)^2, tau as there) the rational
    part gives -sin1 (2 a (1 + eps^2 cos1^2) + 4 eps b cos1^2) / P and Phi
    grows by (pi + tau) / beta.  I_c = O(eps) and enters the forces multiplied
    by eps, so no excess form is needed."""
    eps2 = eps**2
    beta2 = 1.0 - eps2
    beta = jnp.sqrt(beta2)
    p = (1.0 - eps2 * cos1**2) ** 2
    tau = (-2.0 * jnp.arctan(eps * sin1 / (1.0 + beta + eps * cos1))
           - 2.0 * jnp.arctan(eps * sin1 / (1.0 + beta - eps * cos1)))
    a = (2.0 + eps2) / (2.0 * beta2**2)
    b = -eps * (1.0 + 2.0 * eps2) / (2.0 * beta2**2)
    k = 3.0 * eps / (2.0 * beta2**2)
    return (-sin1 * (2.0 * a * (1.0 + eps2 * cos1**2) + 4.0 * eps * b * cos1**2) / p
            + k * (jnp.pi + tau) / beta)


class LongBearingFilm(AbstractFilm):
    """Long-bearing (Sommerfeld) hydrodynamic film with squeeze and wedge
    action and Gumbel cavitation (the model, its derivation, the choice of the
    cavitated region and its limits are in the module docstring and
    docs/notes/lubricated-joint.md).

    Arguments (each a float64 array leaf, `float_leaf`: sweep or differentiate them):
        viscosity: dynamic viscosity mu of the oil [Pa s] (> 0)
        length: axial length L of the bearing [m] (> 0; long-bearing theory
            wants L / D > ~2)
        clearance: radial clearance c of the round bore [m] (> 0); the film
            uses it, not a worn `BushingProfile`
        max_eccentricity_ratio: eps_max in (0, 1), default 0.95; the film is
            evaluated at the pin's eps up to eps_max - w and saturates towards eps_max
        saturation_width: width w of the saturation below eps_max, in
            (0, eps_max), default 0.01

    Journal radius R: the pin radius of the `PinKinematics` (wedge speed
    U = omega R, film area 2 pi R L; the bore radius differs by c << R).

    References: Flores, Ambrosio, Claro & Lankarani, Mech. Mach. Theory 41
    (2006) 247-261, and Flores et al., Kinematics and dynamics of multibody
    systems with imperfect joints, Springer 2008 (long-bearing forces of a
    dynamically loaded journal bearing in a multibody joint); Daniel, Machado
    & Cavalca, Mech. Mach. Theory 99 (2016) 19-36 (positive-pressure region);
    Hamrock, Schmid & Jacobson, Fundamentals of Fluid Film Lubrication
    (steady half-Sommerfeld load and attitude).
    """

    def steady_peak_pressure(self, eccentricity_ratio, omega, radius):
        """The film's largest pressure [Pa] with the centre at rest: the maximum
        over psi of 6 mu R^2 / c^2 (2 - eps cos psi) eps |omega| |sin psi| /
        ((2 + eps^2) (1 - eps cos psi)^2) (module notes), 2048-point grid."""
        eps = self._saturated(jnp.asarray(eccentricity_ratio, dtype=float))
        psi = jnp.linspace(0.0, jnp.pi, 2048)
        d = 1.0 - eps * jnp.cos(psi)
        shape = jnp.max((2.0 - eps * jnp.cos(psi)) * jnp.sin(psi) / d**2) / (2.0 + eps**2)
        return 6.0 * self.viscosity * radius**2 / self.clearance**2 * eps * jnp.abs(omega) * shape

    def _film_factor(self, radius):
        """K_L = 6 mu R^3 L / c^2 [N s]: the pressure factor 6 mu R^2 / c^2 times
        the area R L dtheta."""
        return 6.0 * self.viscosity * radius**3 * self.length / self.clearance**2

    def _excess_components(self, eps_f, squeeze, wedge, radius):
        """The parts of F_n and F_t (module docstring) [N] beyond their eps = 0
        values -K_L pi/2 A and K_L pi/2 B, from the saturated eps, A = 2 eps_dot
        and B = eps omega - 2 eps gamma_dot [1/s]."""
        # the positive half is centred on V_L, (n, t) components c ((1 + eps^2/2) A, -B):
        # psi_1 = psi_V - pi/2, cos psi_1 = -B / |.|, sin psi_1 = -(1 + eps^2/2) A / |.|.
        # At V_L = 0 the film carries nothing and any half will do.
        v_dir, _ = _safe_unit(jnp.stack([(1.0 + 0.5 * eps_f**2) * squeeze, wedge]))
        cos1, sin1 = -v_dir[1], -v_dir[0]
        excess_cc, integral_cs, excess_ss = _half_film_excess(eps_f, cos1, sin1)
        integral_c = _half_film_cos(eps_f, cos1, sin1)
        eps2 = eps_f**2
        p = (1.0 - eps2 * cos1**2) ** 2
        k = self._film_factor(radius)
        excess_n = k * (wedge * 2.0 * eps_f * cos1 * (3.0 - (2.0 + eps2) * cos1**2)
                        / ((2.0 + eps2) * p)
                        - squeeze * excess_ss)
        excess_t = k * (wedge * (excess_cc - 3.0 * eps_f * integral_c / (2.0 + eps2))
                        + squeeze * integral_cs)
        return excess_n, excess_t
