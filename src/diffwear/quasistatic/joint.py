"""The elastic-foundation joint at equilibrium: pin offset, pressure, wear of one cycle.

Quasi-static reduction of the EFM clearance joint (thesis Ch. 6).  At each
sample of the cycle the pin sits where the foundation springs carry the joint
load W (the force the pin exerts on the bushing, bushing frame):

    sum_k kk ramp(u_k . e - c_k) (u_k + f t_k) = W,     kk = k_f R_b d dtheta,

u_k = (cos, sin) theta_k, t_k = perp(u_k), ramp the EFM's smoothed contact
onset, f = mu sign(R_pin omega) (smoothed as in `CoulombFriction`) the
friction traction of every spring, opposing the sliding.  The slip of spring k
in the dynamic EFM law is t_k . e_dot + R_pin omega; at equilibrium the pin
drifts at |e_dot| ~ 1e-4 m/s against R_pin |omega| ~ 1e-2..1e-1 m/s, so the
drift is neglected and f is the same for every spring.  Then, with
P = perp (rotation by +90 degrees), u_k + f t_k = (I + f P) u_k and the balance
is (I + f P) g(e) = W with g the gradient of the *convex* foundation energy

    E(e) = sum_k kk R(u_k . e - c_k) - W' . e,    R' = ramp,
    W' = (I + f P)^-1 W = (W - f P W) / (1 + f^2).

So friction only turns and shortens the load (by atan(mu), 7.4 degrees at
mu = 0.13); the offset is the unique minimiser of a strictly convex energy
once a spring is compressed, for any worn profile c_k = c0 + h_k, and it is
continuous in the design, the profile and the load.  It is found by a damped
Newton method (`pin_offset`), from the guess "pin on the worn wall along W',
pressed in by |W'| / (k_f R_b d pi / 2)" (the half-circle contact
stiffness); derivatives by the implicit-function theorem (no unrolled
iterations).

The wear of one cycle is Archard's law summed over the samples,
dh_k = sum_s dt rate(p_ks, R_b |omega_s|), with the same smoothed |omega| as the
dynamic route (`ClearanceJoint.sliding_rate`).  Its response to the profile,
A = -d(dh)/dh, is exact and symmetric positive semi-definite: at fixed W' a
deeper profile moves the pin by de = M^-1 U^T D dh (M = U^T D U, D the
contact indicators ramp'(delta)), so dp = -k_f (D - D U M^-1 U^T D) dh.

Where the reduction does not hold: when the pin leaves the wall (impacts,
free flight across the clearance).  `contact_margin` estimates it per sample:
the pin, dragged around a wall of clearance c by a load turning at omega_W,
needs m c omega_W^2 of inward force; a load smaller than that lets it fly.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import lax
from jax.ad_checkpoint import checkpoint_name
from jaxtyping import Array, Bool, Float

from ..contact import smoothing
from ..contact.archard import SLIP_RATE_WIDTH, ArchardWear
from ..contact.clearance_joint import ClearanceJoint
from ..contact.friction import CoulombFriction
from ..contact.laws import ElasticFoundation, _interp_periodic
from ..errors import InputError
from ..mechanism.geometry import grid_angles, safe_angle, safe_norm
from .loads import JointLoads

# Newton tolerance on the offset in units of the starting guess (|e| ~ c + the
# penetration): 1e-10 relative, i.e. ~1e-15 m on the rig's 33 um clearance.
EQUILIBRIUM_TOL = 1e-10
_NEWTON_STEPS = 60
# The name of an equilibrium's pin offsets inside the derivative rules of its
# solves: a reverse pass through the wear integration keeps these and
# recomputes the rest of each cycle, never the solves' iterations
# (`diffwear.models.quasi_static`, `_JointWear.cycle`).
EQUILIBRIUM = "pin_equilibrium"
# Below this load [N] the equilibrium is not defined (no spring compressed);
# such a sample is flagged by `contact_margin` and solved with this floor.
_LOAD_FLOOR = 1e-9


def _damped_newton(x0, u, c, scale, width, ratio, pull, direction):
    """Newton's method with a backtracking line search on the scaled energy
    (module notes), from ``x0``: (x, converged).  The line search matters:
    plain Newton from the wall guess fails when the load points away from a
    deep groove (the pin slides along the groove's flank, 60+ degrees off the
    load: no spring compressed at the guess).  Sufficient decrease (Armijo,
    1e-4) or a smaller residual accepts a step (near the root the energy's
    change is below rounding); a ridge of 1e-3 of one spring's stiffness keeps
    the Newton matrix regular with a single spring in contact.  Measured on
    worn Ch. 8 profiles: 4.7 iterations on average, 13 at most."""

    def parts(x):
        delta = u @ (scale * x) - c
        # the energy is a merit function for the line search only: that of the
        # single ramp (exact outside the onset band, where all but a few springs are)
        energy = (ratio * jnp.sum(smoothing.ramp_integral(delta, width)) / scale**2
                  - pull * (direction @ x))
        grad = ratio * spring(delta, width) @ u / scale - pull * direction
        hess = ratio * (u.T * spring_slope(delta, width)) @ u
        return energy, grad, hess

    def converged(grad):
        return jnp.max(jnp.abs(grad)) <= EQUILIBRIUM_TOL * pull

    def unfinished(state):
        _, _, grad, _, k = state
        return (k < _NEWTON_STEPS) & ~converged(grad)

    def newton_step(state):
        x, energy, grad, hess, k = state
        step = -_solve_2x2(hess + 1e-3 * ratio * jnp.eye(2), grad)

        def too_long(trial):
            a, e_new, g_new = trial
            return ((e_new > energy + 1e-4 * a * (grad @ step))
                    & (g_new @ g_new >= grad @ grad) & (a > 1e-12))

        def shorten(trial):
            a = 0.5 * trial[0]
            e_new, g_new, _ = parts(x + a * step)
            return a, e_new, g_new

        e1, g1, _ = parts(x + step)
        a, _, _ = lax.while_loop(too_long, shorten, (jnp.ones(()), e1, g1))
        x = x + a * step
        return (x, *parts(x), k + 1)

    x, _, grad, _, _ = lax.while_loop(unfinished, newton_step, (x0, *parts(x0), 0))
    return x, converged(grad)


def _solve_2x2(m, r):
    """m^-1 r for a 2 x 2 matrix in closed form (NaN if m is singular)."""
    det = m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]
    adj = jnp.array([[m[1, 1], -m[0, 1]], [-m[1, 0], m[0, 0]]])
    ok = det != 0.0
    return jnp.where(ok, adj @ r / jnp.where(ok, det, 1.0), jnp.nan)


def spring(delta, width):
    """Pressure / k_f of an EFM spring at rest: the dynamic law's
    ramp(k_f ramp(delta)) / k_f (`ElasticFoundation.pressure` with no
    penetration rate: its contact onset, then its no-tension clamp, each
    smoothed over ``width``), so that both models load the springs alike."""
    return smoothing.ramp(smoothing.ramp(delta, width), width)


def spring_slope(delta, width):
    """d spring / d delta: the contact indicator D of the module notes."""
    return smoothing.step(smoothing.ramp(delta, width), width) * smoothing.step(delta, width)


def _directions(n: int) -> Float[Array, "n 2"]:
    theta = grid_angles(n)
    return jnp.stack([jnp.cos(theta), jnp.sin(theta)], axis=-1)


def pin_offset(clearance: Float[Array, " n"], load: Float[Array, "2"], contact_stiffness,
               width, guess=None):
    """Pin offset e [m] at equilibrium under the effective load ``load`` [N]
    (W', module notes) on the springs of profile ``clearance`` [m], and 1.0 if
    the solve converged (else 0.0).  ``contact_stiffness`` = k_f R_b d pi / 2
    [N/m] (the springs are kk = contact_stiffness dtheta / (pi / 2) each);
    ``width`` [m]: the contact-onset band of `spring`; ``guess`` [m]: a
    starting offset (e.g. the solution at a nearby profile; default and where
    not finite: the pin on the worn wall along the load).

    Solved in units of the scale of the wall guess (a well-scaled 2 x 2
    problem) by `_damped_newton`.  The derivative is the implicit-function
    theorem in closed form (`_pin_offset_jvp`): no unrolled iteration, and
    no dependence on the starting point."""
    guess = jnp.full(2, jnp.nan) if guess is None else lax.stop_gradient(guess)
    return _pin_offset(clearance, load, contact_stiffness, width, guess)


@jax.custom_jvp
def _pin_offset(clearance, load, contact_stiffness, width, guess):
    c, kc = clearance, contact_stiffness
    n = c.shape[0]
    u = _directions(n)
    size = safe_norm(load)
    safe = jnp.maximum(size, _LOAD_FLOOR)
    direction = jnp.where(size > _LOAD_FLOOR, load / safe, jnp.array([1.0, 0.0]))
    wall = _interp_periodic(c, jnp.arctan2(direction[1], direction[0]))
    scale = jnp.maximum(wall + safe / kc, 1e-12)
    pull = safe / (kc * scale)
    ratio = 4.0 / n  # kk / kc = dtheta / (pi / 2)

    start = jnp.where(jnp.all(jnp.isfinite(guess)), guess / scale, direction)
    x, ok = _damped_newton(start, u, c, scale, width, ratio, pull, direction)
    return scale * x, ok.astype(c.dtype)


@_pin_offset.defjvp
def _pin_offset_jvp(primals, tangents):
    """de = -H^-1 (dr/dtheta . dtheta) at the root of r(e) = sum_k kk ramp(u_k . e -
    c_k) u_k - W' (in units of kc), H = dr/de = (4/n) sum_k ramp'(delta_k) u_k u_k^T:
    the 2 x 2 solve in closed form."""
    c, load, kc, width, guess = primals
    e, ok = _pin_offset(*primals)
    e = checkpoint_name(e, EQUILIBRIUM)
    primals, tangents = primals[:4], tangents[:4]  # the guess does not move the root
    n = c.shape[0]
    u = _directions(n)
    ratio = 4.0 / n

    def force(c, load, kc, width):
        return ratio * spring(u @ e - c, width) @ u - load / kc

    _, dr = jax.jvp(force, primals, tangents)
    h = ratio * (u.T * spring_slope(u @ e - c, width)) @ u
    return (e, ok), (-_solve_2x2(h, dr), jnp.zeros_like(ok))


class Equilibrium(eqx.Module):
    """The pin at equilibrium at every sample of a cycle.

    offset: pin centre minus bushing centre, bushing frame [m] (S, 2)
    pressure: p(theta_k) [Pa] (S, n)
    normal_load: integral of p over the contact area [N] (S,)
    ok: every Newton solve converged
    """

    offset: Float[Array, "S 2"]
    pressure: Float[Array, "S n"]
    normal_load: Float[Array, " S"]
    ok: Bool[Array, ""]


class QuasiStaticJoint(eqx.Module):
    """An EFM clearance joint with Archard wear, in the quasi-static reduction.

    Built from a `ClearanceJoint` (`from_joint`); every number is an array, so
    the results differentiate with respect to the joint's dimensions,
    stiffness, friction and wear coefficient.
    """

    clearance: Float[Array, " n"]        # unworn profile c0(theta_k) [m]
    pin_radius: Float[Array, ""]
    bushing_radius: Float[Array, ""]
    foundation: ElasticFoundation
    friction: CoulombFriction
    wear: ArchardWear

    @classmethod
    def from_joint(cls, joint: ClearanceJoint) -> "QuasiStaticJoint":
        if not isinstance(joint.law, ElasticFoundation):
            raise InputError(
                f"clearance joint {joint.name!r}: the quasi-static model needs the elastic "
                f"foundation law (a pressure distribution), not {type(joint.law).__name__}")
        if joint.wear is None:
            raise InputError(f"clearance joint {joint.name!r} has no wear law "
                             "(wear=ArchardWear(k))")
        return cls(clearance=joint.profile.clearance,
                   pin_radius=joint.pin_radius, bushing_radius=joint.bushing_radius,
                   foundation=joint.law, friction=joint.friction, wear=joint.wear)

    # ------------------------------------------------------------ geometry
    @property
    def n(self) -> int:
        return self.clearance.shape[0]

    @property
    def directions(self) -> Float[Array, "n 2"]:
        return _directions(self.n)

    @property
    def spring_area(self) -> Float[Array, ""]:
        """Bushing surface per grid point, R_b d dtheta [m^2]."""
        return self.bushing_radius * self.foundation.depth * (2.0 * jnp.pi / self.n)

    # ------------------------------------------------------------ statics
    def effective_load(self, loads: JointLoads) -> Float[Array, "S 2"]:
        """W' = (I + f P)^-1 W: the load with the friction traction taken out."""
        return self.without_friction(loads.force, loads.omega)

    def without_friction(self, force: Float[Array, "... 2"], omega) -> Float[Array, "... 2"]:
        """W' = (I + f P)^-1 W of loads ``force`` [N] at spins ``omega`` [rad/s]
        (any leading shape): the springs' friction traction taken out (module
        notes)."""
        f = self.friction.factor(self.pin_radius * omega)[..., None]
        turned = jnp.stack([-force[..., 1], force[..., 0]], axis=-1)  # P W
        return (force - f * turned) / (1.0 + f * f)

    def equilibrium(self, depth: Float[Array, " n"], loads: JointLoads,
                    guess: Float[Array, "S 2"] | None = None) -> Equilibrium:
        """Pin offsets, pressures and normal loads over the cycle for wear
        ``depth`` [m]; ``guess``: starting offsets (e.g. those of a nearby
        profile: fewer Newton iterations, the same answer)."""
        c = self.clearance + depth
        kc = self.foundation.contact_stiffness(self.bushing_radius)
        width = self.foundation.penetration_width
        w_eff = self.effective_load(loads)
        guess = jnp.full_like(w_eff, jnp.nan) if guess is None else guess
        offset, ok = jax.vmap(lambda w, g: pin_offset(c, w, kc, width, g))(w_eff, guess)
        delta = offset @ self.directions.T - c
        pressure = self.foundation.stiffness * spring(delta, self.foundation.penetration_width)
        normal_load = self.spring_area * jnp.sum(pressure, axis=-1)
        return Equilibrium(offset=offset, pressure=pressure, normal_load=normal_load,
                           ok=jnp.all(ok > 0.5) & jnp.all(jnp.isfinite(offset)))

    # ------------------------------------------------------------ wear
    def sliding_rate(self, loads: JointLoads) -> Float[Array, " S"]:
        """ds/dt = R_b |omega| [m/s] (thesis Eq. 5-3), |.| smoothed as in the dynamic route."""
        return self.bushing_radius * smoothing.magnitude(loads.omega, SLIP_RATE_WIDTH)

    def cycle_wear(self, depth: Float[Array, " n"], loads: JointLoads, guess=None):
        """(dh per cycle [m] (n,), integral of normal load x sliding [N m],
        `Equilibrium`) at wear ``depth``; ``guess``: see `equilibrium`."""
        eq = self.equilibrium(depth, loads, guess)
        slide = self.sliding_rate(loads)
        dh = loads.dt * jnp.sum(self.wear.depth_rate(eq.pressure, slide[:, None]), axis=0)
        load_sliding = loads.dt * jnp.sum(eq.normal_load * slide)
        return dh, load_sliding, eq

    def wear_response(self, depth: Float[Array, " n"], loads: JointLoads,
                      eq: Equilibrium | None = None) -> Float[Array, "n n"]:
        """A = -d(dh per cycle)/d(depth) (n, n), exact (module notes)."""
        eq = self.equilibrium(depth, loads) if eq is None else eq
        u = self.directions
        c = self.clearance + depth
        width = self.foundation.penetration_width
        slide = self.sliding_rate(loads)
        delta = eq.offset @ u.T - c                               # (S, n)
        contact = spring_slope(delta, width)                      # D, (S, n)
        # d rate / d p per node (the law may be nonlinear in p)
        dp = jax.jvp(lambda p: self.wear.depth_rate(p, slide[:, None]), (eq.pressure,),
                     (jnp.ones_like(eq.pressure),))[1]
        weight = loads.dt * self.foundation.stiffness * dp        # (S, n)
        du = contact[:, :, None] * u[None]                        # D U, (S, n, 2)
        # M = U^T D U (units: nodes in contact); the ridge keeps M regular with no
        # node in contact (D = 0 there, so it changes nothing else)
        m = jnp.einsum("sna,nb->sab", du, u) + 1e-9 * jnp.eye(2)
        follow = jnp.linalg.solve(m, jnp.swapaxes(du, 1, 2))      # M^-1 U^T D, (S, 2, n)
        diag = jnp.sum(weight * contact, axis=0)
        coupling = jnp.einsum("sn,sna,sam->nm", weight, du, follow)
        return jnp.diag(diag) - coupling

    def contact_margin(self, depth: Float[Array, " n"], loads: JointLoads,
                       mass) -> Float[Array, " S"]:
        """|W| / (m c omega_W^2) per sample: below 1 the load cannot hold the pin
        on the wall as the load turns (free flight; module notes).  ``mass``:
        the effective mass of the relative motion [kg]."""
        w = loads.force
        angle = safe_angle(w)
        turn = (jnp.roll(angle, -1) - jnp.roll(angle, 1))
        turn = turn - 2 * jnp.pi * jnp.round(turn / (2 * jnp.pi))
        rate = turn / (2.0 * loads.dt)
        c = self.clearance + depth
        wall = jax.vmap(lambda a: _interp_periodic(c, a))(angle)
        need = mass * wall * rate**2
        size = safe_norm(w)
        return size / jnp.maximum(need, 1e-300)
