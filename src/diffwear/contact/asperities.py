"""Rough-surface asperity contact: the Greenwood-Tripp pressure of two rough
surfaces, alone and in series with the bushing's elastic foundation.

**Greenwood-Tripp** (Greenwood & Tripp, Proc. Instn Mech. Engrs 185 (1970-71)
625): two nominally flat rough surfaces whose summits have Gaussian heights
(combined RMS roughness sigma), areal density eta [1/m^2] and radius beta [m]
press each other with the mean pressure

    p_a(h) = K E' F_{5/2}(h / sigma),
    K = (16 sqrt(2) pi / 15) (eta beta sigma)^2 sqrt(sigma / beta),
    F_n(lambda) = (1 / sqrt(2 pi)) int_lambda^inf (s - lambda)^n exp(-s^2 / 2) ds,

h the separation of the mean surfaces (the local film).  E' is the composite
modulus of Hertz contact, 1 / E' = (1 - nu_1^2) / E_1 + (1 - nu_2^2) / E_2
(Johnson, Contact Mechanics, Ch. 4: E*): the constant 16 sqrt(2) pi / 15
belongs to that convention.  Derivation (GT's, without the summits' tilt): two
summits of radius beta whose heights overlap by s at lateral offset r touch
with interference w = s - r^2 / (4 beta) and, Hertz with radius beta / 2,
carry (4/3) E' sqrt(beta / 2) w^(3/2); over the offsets, int 2 pi r ... dr =
(16 sqrt(2) pi / 15) E' beta^(3/2) s^(5/2); eta^2 pairs per unit area and the
Gaussian of the summed heights (RMS sigma) give p_a above.  (Authors who
write 8 sqrt(2) pi / 15 use Hamrock's E' = 2 E*, the same pressure.)  The
pressure is smooth in h, rises from ~ 0 at h = 4 sigma (p_a(4 sigma) / p_a(0)
= 4e-6) and is defined below h = 0 too (the mean surfaces interfering), where
it grows like |h / sigma|^(5/2).

F_{5/2} is computed by Gauss-Legendre quadrature (`GT_QUADRATURE_NODES`
nodes) after the substitution s - lambda = v^2, which makes the integrand
2 v^6 exp(-(v^2 + lambda)^2 / 2) smooth; the nodes span the Gaussian's mass
(v^2 + lambda within +-`GT_TAIL`).  Relative error <= 1e-10 for every lambda
>= -40 (tests/test_greenwood_tripp.py: against the closed form by the
parabolic cylinder function, F_n(lambda) = Gamma(n + 1) exp(-lambda^2 / 4)
D_{-n-1}(lambda) / sqrt(2 pi), and against adaptive quadrature).  It is smooth
to every order, so derivatives are exact too (dF_n / dlambda = -n F_{n-1}).

**On the foundation** (`GreenwoodTripp.on_foundation`): the asperities sit on
the bushing's bulk, the Winkler layer of the elastic foundation (stiffness
k_f [Pa/m], `ElasticFoundation`), and the two carry the same pressure in
series.  Where the rigid-body gap between the mean surfaces is g (the local
film if nothing deformed, negative where the mean surfaces would overlap),
the bulk compressed by p / k_f opens the mean surfaces' separation to h =
g + p / k_f, and the asperities carry p = p_a(h).  In units of sigma, x = h /
sigma solves

    x - a F_{5/2}(x) = g / sigma,     a = K E' / (k_f sigma),

one root (the left side rises strictly with x), found by Newton's method
from below (the left side is concave: the iterates rise monotonically to the
root) from max(g / sigma, -(-g / (a sigma))^(2/5)), both below the root
(F_{5/2}(x) >= (-x)^(5/2), Jensen); at most `FOUNDATION_NEWTON_STEPS` steps, in the
bulk's compression y = x - g / sigma (p = k_f sigma y keeps its precision
where the bulk hardly gives).  Its
derivative is that of the implicit function, written in terms of the root
itself (differentiable again).  So the contact starts smoothly as the film
thins and, pressed past the mean surfaces, stiffens to the foundation's
k_f with the asperity layer's compliance in series.
"""

from __future__ import annotations

from functools import partial

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._checks import check_positive, check_range, concrete, float_leaf
from ..errors import InputError
from . import smoothing
from .materials import PTFE, STEEL, Material

# Gauss-Legendre nodes of the F_n quadrature: 48 give a relative error below
# 1e-10 for lambda >= -40 (tests/test_greenwood_tripp.py; 3e-15 at -60; 40
# nodes: 4e-8 at lambda = -10).
GT_QUADRATURE_NODES = 48
# Half-width of the quadrature's span in v^2 + lambda = s: the Gaussian
# weight exp(-s^2 / 2) beyond s = 10 is below e^-50 ~ 2e-22.
GT_TAIL = 10.0
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(GT_QUADRATURE_NODES)
# GT's constant for E' = E* (module notes).
GT_CONSTANT = 16.0 * np.sqrt(2.0) * np.pi / 15.0

# Summit parameters.  Measured surfaces give eta beta sigma between 0.03 and
# 0.05 (Greenwood & Williamson, Proc. R. Soc. A 295 (1966) 300) and sigma /
# beta between 1e-4 and 1e-2 (the usual ranges of the Greenwood-Tripp
# parameters: Gohar & Rahnejat, Fundamentals of Tribology).  Defaults:
# the middle of each, 0.04 and the geometric mean 1e-3 (for the ground steel
# pin on a bored polymer bushing of the shipped files, sigma = 0.65 um, that
# is beta = 0.65 mm and eta = 9.5e7 1/m^2).
DEFAULT_SUMMIT_PRODUCT = 0.04  # eta beta sigma
DEFAULT_SLOPE_RATIO = 1e-3  # sigma / beta
# Allowed: eta beta sigma within a factor 2-3 of the measured range, and
# sigma / beta up to 0.1 (beyond it the summits are not the shallow caps of
# Hertz contact) and down to 1e-6 (two decades below the usual range).
SUMMIT_PRODUCT_RANGE = (0.01, 0.1)
SLOPE_RATIO_RANGE = (1e-6, 0.1)
# Newton steps of the series solve: from the start of the module notes the
# root's residual is below 1e-11 sigma after 10 steps (2e-5 sigma after 8) over
# a in [1e-3, 1e3] and g / sigma in [-500, 8] (tests/test_greenwood_tripp.py);
# at most 16, stopped once every step is below FOUNDATION_TOL of the root
# (Newton's quadratic convergence: the next step is ~ 1e-26 of it).
FOUNDATION_NEWTON_STEPS = 16
FOUNDATION_TOL = 1e-13


def composite_modulus(pin: Material, bushing: Material) -> Float[Array, ""]:
    """E' = 1 / ((1 - nu_pin^2) / E_pin + (1 - nu_bushing^2) / E_bushing) [Pa]
    (module notes; `Material.compliance_h` is (1 - nu^2) / (pi E))."""
    return jnp.asarray(1.0 / (jnp.pi * (pin.compliance_h + bushing.compliance_h)))


def _tail_moments(film_ratio, powers):
    """sqrt(2 pi) F_n(lambda) for n = (k - 1) / 2 for each k in ``powers``
    (odd integers: the substituted integrand's power of v), sharing the nodes
    and the exponentials; quadrature of the module notes."""
    lam = jnp.asarray(film_ratio, dtype=float)[..., None]
    # the span of v^2 = s - lambda: s from max(lambda, -GT_TAIL) to
    # max(lambda, 0) + GT_TAIL, its ends smoothed (the weight there is < e^-45)
    hi = jnp.sqrt(GT_TAIL + smoothing.ramp(-lam, 1.0))
    lo2 = smoothing.ramp(-lam - GT_TAIL, 1.0)
    positive = lo2 > 0.0
    lo = jnp.where(positive, jnp.sqrt(jnp.where(positive, lo2, 1.0)), 0.0)
    half = 0.5 * (hi - lo)
    v = lo + half * (1.0 + _NODES)
    v2 = v * v
    weight = 2.0 * half * jnp.exp(-0.5 * (v2 + lam) ** 2) * _WEIGHTS
    return tuple(jnp.sum(weight * v ** k, axis=-1) for k in powers)


@partial(jax.custom_jvp, nondiff_argnums=(1,))
def _tail_moment(film_ratio, power: int):
    """sqrt(2 pi) F_n, n = (power - 1) / 2 >= 1/2, with the derivative
    dF_n/dlambda = -n F_{n-1} as its rule: a tangent then costs one
    quadrature of the primal, not one per tangent and node (forward mode
    through a wear response carries hundreds of tangents)."""
    return _tail_moments(film_ratio, (power,))[0]


@_tail_moment.defjvp
def _tail_moment_jvp(power, primals, tangents):
    (lam,), (d_lam,) = primals, tangents
    lower = (_tail_moment(lam, power - 2) if power >= 4
             else _tail_moments(lam, (power - 2,))[0])
    return _tail_moment(lam, power), -0.5 * (power - 1) * lower * d_lam


def gaussian_tail_integral(film_ratio, order: float = 2.5) -> Float[Array, "..."]:
    """F_n(lambda) = (1 / sqrt(2 pi)) int_lambda^inf (s - lambda)^n
    exp(-s^2 / 2) ds for a half-integer n = ``order`` >= 1/2, at
    ``film_ratio`` lambda (any shape); quadrature of the module notes."""
    power = 2.0 * order + 1.0
    if power != round(power) or power < 2:
        raise InputError(f"order of the Gaussian tail integral must be a half-integer >= 1/2, "
                         f"got {order}")
    return _tail_moment(jnp.asarray(film_ratio, dtype=float), int(power)) / np.sqrt(2.0 * np.pi)


def _tail_pair(film_ratio):
    """(F_{5/2}, F_{3/2}) at ``film_ratio``, from one set of exponentials."""
    f52, f32 = _tail_moments(film_ratio, (6, 4))
    return f52 / np.sqrt(2.0 * np.pi), f32 / np.sqrt(2.0 * np.pi)


@jax.custom_jvp
def _series_root(gamma, a):
    """y = (h - g) / sigma, the bulk's compression in units of sigma, with
    y = a F_{5/2}(gamma + y) (module notes: x = gamma + y); elementwise.
    Solved for y, not x, so that p = k_f sigma y keeps its relative
    precision where y << |gamma|."""
    gamma, a = jax.lax.stop_gradient((gamma, a))
    y = jnp.maximum(0.0, -(smoothing.ramp(-gamma, 1e-12) / a) ** 0.4 - gamma)

    def unfinished(state):
        y, step, k = state
        return (k < FOUNDATION_NEWTON_STEPS) & jnp.any(step > FOUNDATION_TOL * y)

    def newton(state):
        y, _, k = state
        f52, f32 = _tail_pair(gamma + y)
        step = (a * f52 - y) / (1.0 + 2.5 * a * f32)
        return y + step, jnp.abs(step), k + 1

    y, _, _ = jax.lax.while_loop(unfinished, newton, (y, jnp.full_like(y, jnp.inf), 0))
    return y


@_series_root.defjvp
def _series_root_jvp(primals, tangents):
    """dy = (F_{5/2}(x) da - (5/2) a F_{3/2}(x) dgamma) / (1 + (5/2) a
    F_{3/2}(x)) at the root, x = gamma + y, y itself from `_series_root` (so
    that the rule can be differentiated again)."""
    gamma, a = primals
    d_gamma, d_a = tangents
    y = _series_root(gamma, a)
    x = gamma + y
    push = 2.5 * a * gaussian_tail_integral(x, 1.5)
    return y, (gaussian_tail_integral(x) * d_a - push * d_gamma) / (1.0 + push)


class GreenwoodTripp(eqx.Module):
    """Greenwood-Tripp asperity contact of two rough surfaces (module notes).

    Arguments:
        roughness: combined RMS roughness sigma [m] (> 0)
        summit_density: eta [1/m^2]; default: eta beta sigma =
            `DEFAULT_SUMMIT_PRODUCT`
        summit_radius: beta [m]; default: sigma / beta = `DEFAULT_SLOPE_RATIO`
        modulus: composite modulus E' [Pa] (`composite_modulus`); default:
            a steel pin on a PTFE bushing (thesis Table 3-2), 0.58 GPa

    eta beta sigma must lie in `SUMMIT_PRODUCT_RANGE` and sigma / beta in
    `SLOPE_RATIO_RANGE` (module constants: their sources).
    """

    roughness: Float[Array, ""]
    summit_density: Float[Array, ""]
    summit_radius: Float[Array, ""]
    modulus: Float[Array, ""]

    def __init__(self, roughness, summit_density=None, summit_radius=None, modulus=None):
        check_positive("combined RMS roughness sigma [m]", roughness)
        if summit_radius is None:
            summit_radius = roughness / DEFAULT_SLOPE_RATIO
        check_positive("summit radius beta [m]", summit_radius)
        if summit_density is None:
            summit_density = DEFAULT_SUMMIT_PRODUCT / (summit_radius * roughness)
        check_positive("summit density eta [1/m^2]", summit_density)
        if modulus is None:
            modulus = composite_modulus(STEEL, PTFE)
        check_positive("composite modulus E' [Pa]", modulus)
        sigma, eta, beta = (concrete(v) for v in (roughness, summit_density, summit_radius))
        if sigma is not None and eta is not None and beta is not None:
            product, slope = float(eta * beta * sigma), float(sigma / beta)
            low, high = SUMMIT_PRODUCT_RANGE
            if not low <= product <= high:
                raise InputError(
                    f"summit density x summit radius x roughness eta beta sigma = {product:.4g} "
                    f"(eta = {float(eta):.4g} 1/m^2, beta = {float(beta):.4g} m, sigma = "
                    f"{float(sigma):.4g} m) must lie in [{low}, {high}] (measured surfaces: "
                    "0.03-0.05)")
            check_range(f"roughness / summit radius sigma / beta (beta = {float(beta):.4g} m)",
                        slope, *SLOPE_RATIO_RANGE)
        self.roughness = float_leaf(roughness)
        self.summit_density = float_leaf(summit_density)
        self.summit_radius = float_leaf(summit_radius)
        self.modulus = float_leaf(modulus)

    @classmethod
    def from_materials(cls, pin: Material, bushing: Material, roughness, summit_density=None,
                       summit_radius=None) -> "GreenwoodTripp":
        """The law of a ``pin`` on a ``bushing`` (their `composite_modulus`)."""
        return cls(roughness, summit_density, summit_radius, composite_modulus(pin, bushing))

    @property
    def coefficient(self) -> Float[Array, ""]:
        """K = (16 sqrt(2) pi / 15) (eta beta sigma)^2 sqrt(sigma / beta) [-]."""
        sigma, beta = self.roughness, self.summit_radius
        return GT_CONSTANT * (self.summit_density * beta * sigma) ** 2 * jnp.sqrt(sigma / beta)

    @property
    def contact_modulus(self) -> Float[Array, ""]:
        """K E' [Pa]: p_a = K E' F_{5/2}(h / sigma)."""
        return self.coefficient * self.modulus

    def pressure(self, film) -> Float[Array, "..."]:
        """p_a(h) = K E' F_{5/2}(h / sigma) [Pa] at mean-surface separation
        ``film`` h [m] (any shape; h < 0: interference)."""
        return self.contact_modulus * gaussian_tail_integral(jnp.asarray(film) / self.roughness)

    def stiffness(self, film) -> Float[Array, "..."]:
        """-dp_a/dh = (5/2) K E' F_{3/2}(h / sigma) / sigma [Pa/m]."""
        lam = jnp.asarray(film) / self.roughness
        return 2.5 * self.contact_modulus * gaussian_tail_integral(lam, 1.5) / self.roughness

    def on_foundation(self, gap, foundation_stiffness):
        """(p [Pa], k_s [Pa/m]) of the asperities in series with a Winkler
        layer of ``foundation_stiffness`` k_f [Pa/m] at rigid-body gap ``gap``
        g [m] (any shape; module notes): the common pressure p = p_a(h) =
        k_f (h - g) and the pair's stiffness k_s = dp / d(-g) = k_f q, q =
        k_a / (k_a + k_f) with k_a = `stiffness`(h)."""
        sigma, k_f = self.roughness, foundation_stiffness
        a = self.contact_modulus / (k_f * sigma)
        gamma = jnp.asarray(gap) / sigma
        y = _series_root(gamma, a)
        k_a = self.stiffness(sigma * (gamma + y))
        return k_f * sigma * y, k_f * k_a / (k_a + k_f)
