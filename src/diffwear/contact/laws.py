"""Contact laws for a pin in a bushing: Lankarani-Nikravesh, Kelvin-Voigt and the
elastic foundation model (EFM).

All three share one interface, `AbstractContactLaw.evaluate`, and return a
`ContactResult` in the bushing frame; the `ClearanceJoint` turns it into
generalised forces.  Point laws (LN, KV) place one normal force along the
eccentricity; the EFM integrates a pressure distribution over the bushing grid.
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_positive, check_range
from ..mechanism.geometry import dot2, perp
from . import smoothing
from .friction import CoulombFriction
from .kinematics import ContactResult, PinKinematics
from .materials import Material
from .profile import BushingProfile

# Width of the smoothed contact onset (penetration) for the point laws, 1e-8 m:
# about 1/1000 of the penetration of the thesis joints at their working load
# (LN: (1 kN / 7e10 N/m^1.5)^(2/3) ~ 6e-6 m).  The EFM uses its own width.
POINT_PENETRATION_WIDTH = 1e-8  # m
# Floor of the radius difference in the Hertz stiffness (see LankaraniNikravesh).
MIN_RADIUS_DIFFERENCE = 1e-7  # m
# Smooth norm width for the eccentricity: 1e-12 m (no NaN at e = 0).
OFFSET_NORM_WIDTH = 1e-12  # m


def _restitution(value, what):
    check_range(f"{what}: coefficient of restitution", value, 0.0, 1.0, low_open=True)
    return jnp.asarray(value, dtype=float)


def _interp_periodic(values: Float[Array, " n"], angle: Float[Array, ""]) -> Float[Array, ""]:
    """Linear interpolation of a periodic grid (theta_k = 2 pi k / n) at ``angle``."""
    n = values.shape[0]
    x = jnp.mod(angle, 2.0 * jnp.pi) * n / (2.0 * jnp.pi)
    k = jnp.floor(x)
    w = x - k
    k = k.astype(int) % n
    return (1.0 - w) * values[k] + w * values[(k + 1) % n]


class AbstractContactLaw(eqx.Module):
    """Normal (and friction) force of a pin in a bushing."""

    @property
    def n_memory(self) -> int:
        """Internal ODE states of the law (e.g. impact-velocity memory)."""
        return 0

    def initial_memory(self) -> Float[Array, " m"]:
        return jnp.zeros(self.n_memory)

    @property
    def solid_contact(self) -> "ElasticFoundation | None":
        """The elastic foundation whose pressure on the bushing grid wears it
        (Archard), or None: a point law has no pressure distribution and a
        film alone does not touch the bushing."""
        return None

    @abc.abstractmethod
    def evaluate(
        self,
        kin: PinKinematics,
        memory: Float[Array, " m"],
        profile: BushingProfile,
        friction: CoulombFriction,
    ) -> ContactResult:
        """Contact force, friction torque, normal load and pressure."""


class AbstractPointLaw(AbstractContactLaw):
    """A law with one contact point along n = e / |e| (thesis Ch. 3).

    Penetration delta = |e| - c(theta_e) with the clearance of the (possibly
    worn) profile interpolated at the direction of e; normal speed
    delta_dot = e_dot . n; slip speed v_t = e_dot . t + R_pin omega.
    """

    @abc.abstractmethod
    def normal_force(self, delta, delta_dot, memory) -> Float[Array, ""]:
        """F_N >= 0 [N] from penetration [m], its rate [m/s] and memory."""

    def memory_rate(self, delta, delta_dot, memory) -> Float[Array, " m"]:
        return jnp.zeros(self.n_memory)

    def evaluate(self, kin, memory, profile, friction):
        e = kin.offset
        dist = jnp.sqrt(e @ e + OFFSET_NORM_WIDTH**2)
        n = e / dist
        # direction of e on the bushing, with a safe atan2 at e = 0 ("double where")
        is_zero = jnp.all(e == 0.0)
        e_safe = jnp.where(is_zero, jnp.array([1.0, 0.0]), e)
        angle = jnp.arctan2(e_safe[1], e_safe[0])
        delta = dist - _interp_periodic(profile.clearance, angle)
        delta_dot = kin.offset_rate @ n
        f_n = self.normal_force(delta, delta_dot, memory)
        t = perp(n)
        slip = kin.offset_rate @ t + kin.pin_radius * kin.omega
        f_t = -friction.factor(slip) * f_n
        force = -f_n * n + f_t * t
        torque = kin.pin_radius * f_t  # (R_pin n) x (f_t t)
        return ContactResult(
            force=force,
            torque=torque,
            normal_load=f_n,
            pressure=jnp.zeros(profile.n),
            memory_rate=self.memory_rate(delta, delta_dot, memory),
        )


class LankaraniNikravesh(AbstractPointLaw):
    """Hertz contact with hysteresis damping (thesis Eq. 3-7):

        F_N = K delta^1.5 [1 + 3 (1 - e_r^2) / 4 * delta_dot / v_impact]

    **Stiffness** (`from_materials`): K = 4 / (3 (h_i + h_j)) sqrt(R_i R_j / (R_j - R_i)),
    h = (1 - nu^2) / (pi E).  We use the radius *difference*: a pin inside a
    hole is a conformal (concave-convex) contact whose relative curvature is
    1/R_i - 1/R_j (Flores et al.); the thesis prints the sphere form with R_i + R_j,
    which would make the stiffness independent of clearance.  The difference is
    floored at `MIN_RADIUS_DIFFERENCE` = 0.1 um (below the smallest thesis
    clearance, 0.5 um) so that a clearance of exactly 0 gives a finite K.

    **Impact-velocity memory** (a state, smoothed): v_impact relaxes towards the
    current normal speed while out of contact and freezes in contact:
        d v_impact / dt = (1 - H_w(delta)) (delta_dot - v_impact) / memory_time,
    with H_w the smoothed step of `POINT_PENETRATION_WIDTH`.  The denominator uses
    max(v_impact, min_impact_velocity) (smooth): in lasting contact the LN damping
    coefficient 3 (1 - e^2) K delta^1.5 / (4 v) would otherwise diverge as
    v -> 0.  The damping factor is clipped at 0 (no adhesion on rebound).
    """

    stiffness: Float[Array, ""]
    restitution: Float[Array, ""]
    memory_time: Float[Array, ""]
    min_impact_velocity: Float[Array, ""]
    penetration_width: Float[Array, ""]

    def __init__(self, stiffness, restitution=0.8, memory_time=1e-3,
                 min_impact_velocity=0.01, penetration_width=POINT_PENETRATION_WIDTH):
        check_positive("Lankarani-Nikravesh stiffness K [N/m^1.5]", stiffness)
        check_positive("Lankarani-Nikravesh memory_time [s]", memory_time)
        check_positive("Lankarani-Nikravesh min_impact_velocity [m/s]", min_impact_velocity)
        check_positive("penetration_width [m]", penetration_width)
        self.stiffness = jnp.asarray(stiffness, dtype=float)
        self.restitution = _restitution(restitution, "Lankarani-Nikravesh")
        self.memory_time = jnp.asarray(memory_time, dtype=float)
        self.min_impact_velocity = jnp.asarray(min_impact_velocity, dtype=float)
        self.penetration_width = jnp.asarray(penetration_width, dtype=float)

    @staticmethod
    def hertz_stiffness(pin: Material, bushing: Material, pin_radius, bushing_radius):
        """K [N/m^1.5] for a pin of radius R_i in a hole of radius R_j (see class doc)."""
        dr = bushing_radius - pin_radius
        dr = MIN_RADIUS_DIFFERENCE + smoothing.ramp(dr - MIN_RADIUS_DIFFERENCE, 1e-9)
        r_eff = pin_radius * bushing_radius / dr
        return 4.0 / (3.0 * (pin.compliance_h + bushing.compliance_h)) * jnp.sqrt(r_eff)

    @classmethod
    def from_materials(cls, pin: Material, bushing: Material, pin_radius, bushing_radius,
                       restitution=0.8, **kwargs) -> "LankaraniNikravesh":
        k = cls.hertz_stiffness(pin, bushing, pin_radius, bushing_radius)
        return cls(k, restitution, **kwargs)

    @property
    def n_memory(self) -> int:
        return 1

    def initial_memory(self):
        return jnp.atleast_1d(self.min_impact_velocity)

    def normal_force(self, delta, delta_dot, memory):
        v_ref = self.min_impact_velocity
        v_imp = v_ref + smoothing.ramp(memory[0] - v_ref, 0.1 * v_ref)
        hysteresis = 1.0 + 0.75 * (1.0 - self.restitution**2) * delta_dot / v_imp
        elastic = self.stiffness * smoothing.ramp(delta, self.penetration_width) ** 1.5
        return elastic * smoothing.ramp(hysteresis, 1e-3)

    def memory_rate(self, delta, delta_dot, memory):
        free = 1.0 - smoothing.step(delta, self.penetration_width)
        return jnp.atleast_1d(free * (delta_dot - memory[0]) / self.memory_time)


class KelvinVoigt(AbstractPointLaw):
    """Linear contact with restitution-scaled rebound (thesis Eq. 3-1, after Ravn):

        F_N = K delta            while loading   (delta_dot > 0)
        F_N = e_r K delta        while unloading (delta_dot < 0)

    The switch is smoothed over ``rebound_width`` [m/s] of normal speed.  The
    thesis quotes no K for a joint simulation (its only KV number, 5e6 N/m, is an
    illustration); `matched_to` picks the K that gives the same penetration as a
    Lankarani-Nikravesh law at a reference load.
    """

    stiffness: Float[Array, ""]
    restitution: Float[Array, ""]
    rebound_width: Float[Array, ""]
    penetration_width: Float[Array, ""]

    def __init__(self, stiffness, restitution=0.8, rebound_width=1e-3,
                 penetration_width=POINT_PENETRATION_WIDTH):
        check_positive("Kelvin-Voigt stiffness K [N/m]", stiffness)
        check_positive("Kelvin-Voigt rebound_width [m/s]", rebound_width)
        check_positive("penetration_width [m]", penetration_width)
        self.stiffness = jnp.asarray(stiffness, dtype=float)
        self.restitution = _restitution(restitution, "Kelvin-Voigt")
        self.rebound_width = jnp.asarray(rebound_width, dtype=float)
        self.penetration_width = jnp.asarray(penetration_width, dtype=float)

    @classmethod
    def matched_to(cls, ln: LankaraniNikravesh, reference_load=1000.0, **kwargs) -> "KelvinVoigt":
        """Secant stiffness K = F / delta(F) of the LN law at ``reference_load`` [N]:
        K = K_LN^(2/3) F^(1/3)."""
        k = ln.stiffness ** (2.0 / 3.0) * jnp.asarray(reference_load, dtype=float) ** (1.0 / 3.0)
        return cls(k, ln.restitution, **kwargs)

    def normal_force(self, delta, delta_dot, memory):
        loading = 0.5 * (1.0 + smoothing.sign(delta_dot, self.rebound_width))
        factor = self.restitution + (1.0 - self.restitution) * loading
        return self.stiffness * smoothing.ramp(delta, self.penetration_width) * factor


class ElasticFoundation(AbstractContactLaw):
    """Elastic foundation (Winkler) model of the bushing (thesis Ch. 6).

    Independent springs on the bushing grid theta_k (see `BushingProfile`):

        delta_k = e . u_k - c(theta_k),     u_k = (cos theta_k, sin theta_k)
        p_k     = k_f ramp_w(delta_k) + k_f tau delta_dot_k H_w(delta_k),  then >= 0

    with foundation stiffness k_f = E_W / L [Pa/m] (E_W the constrained modulus of
    the bushing material, L the layer thickness, thesis Eq. 6-1..6-3) and a
    Kelvin-Voigt relaxation time ``damping_time`` tau [s] per spring (see
    `damping_time_for_restitution`).  Force on the pin
    F = -sum p_k u_k R_b d dtheta - friction, with d the bushing depth; each
    spring's friction opposes its own slip v_k = e_dot . t_k + R_pin omega.
    """

    stiffness: Float[Array, ""]
    depth: Float[Array, ""]
    damping_time: Float[Array, ""]
    penetration_width: Float[Array, ""]

    def __init__(self, stiffness, depth, damping_time=0.0, penetration_width=1e-8):
        check_positive("elastic foundation stiffness k_f = E_W / L [Pa/m]", stiffness)
        check_positive("bushing depth [m]", depth)
        check_positive("elastic foundation damping_time [s]", damping_time, allow_zero=True)
        check_positive("penetration_width [m]", penetration_width)
        self.stiffness = jnp.asarray(stiffness, dtype=float)
        self.depth = jnp.asarray(depth, dtype=float)
        self.damping_time = jnp.asarray(damping_time, dtype=float)
        self.penetration_width = jnp.asarray(penetration_width, dtype=float)

    @classmethod
    def from_material(cls, bushing: Material, layer_thickness, depth, **kwargs):
        """k_f = E_W / L with L the bushing wall (outer minus inner radius) [m]."""
        check_positive("elastic layer thickness L [m]", layer_thickness)
        return cls(bushing.foundation_modulus / layer_thickness, depth, **kwargs)

    @staticmethod
    def damping_time_for_restitution(restitution, contact_stiffness, mass):
        """tau = c / k for a linear spring-dashpot with coefficient of restitution e:
        zeta = -ln e / sqrt(pi^2 + ln^2 e), c = 2 zeta sqrt(k m), so
        tau = 2 zeta / omega_n with omega_n = sqrt(k / m) [s]."""
        ln_e = jnp.log(restitution)
        zeta = -ln_e / jnp.sqrt(jnp.pi**2 + ln_e**2)
        return 2.0 * zeta / jnp.sqrt(contact_stiffness / mass)

    @property
    def solid_contact(self) -> "ElasticFoundation":
        return self

    def contact_stiffness(self, radius) -> Float[Array, ""]:
        """Small-penetration radial stiffness of a full half-circle contact,
        k_f R d * integral of cos^2 over (-pi/2, pi/2) = k_f R d pi / 2 [N/m]."""
        return self.stiffness * radius * self.depth * jnp.pi / 2.0

    def pressure(self, kin: PinKinematics, profile: BushingProfile) -> Float[Array, " n"]:
        u = profile.normals
        w = self.penetration_width
        delta = dot2(u, kin.offset) - profile.clearance
        rate = dot2(u, kin.offset_rate)
        p = self.stiffness * (smoothing.ramp(delta, w)
                              + self.damping_time * rate * smoothing.step(delta, w))
        return smoothing.ramp(p, self.stiffness * w)

    def evaluate(self, kin, memory, profile, friction):
        return self.resultant(kin, profile, self.pressure(kin, profile), friction)

    def resultant(self, kin: PinKinematics, profile: BushingProfile,
                  p: Float[Array, " n"], friction: CoulombFriction) -> ContactResult:
        """Force, friction torque and normal load of the pressure ``p`` [Pa] on
        the bushing grid, each node's friction opposing its own slip."""
        u, t = profile.normals, profile.tangents
        area = kin.bushing_radius * self.depth * profile.dtheta  # per grid point [m^2]
        load = p * area
        slip = jnp.asarray(dot2(t, kin.offset_rate) + kin.pin_radius * kin.omega)
        f_t = -friction.factor(slip) * load
        # the four sums over the grid as one product with [t, u, 1]: one kernel
        # on XLA's CPU backend, not four reductions (docs/notes/cpu-kernels.md)
        sums = jnp.stack([f_t, load]) @ jnp.concatenate([t, u, jnp.ones_like(t[:, :1])], axis=1)
        return ContactResult(
            force=sums[0, :2] - sums[1, 2:4],
            torque=kin.pin_radius * sums[0, 4],
            normal_load=sums[1, 4],
            pressure=p,
            memory_rate=jnp.zeros(0),
        )
