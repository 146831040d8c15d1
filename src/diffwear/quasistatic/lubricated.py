"""The lubricated joint at equilibrium: film plus asperities, wear of one cycle.

Quasi-static reduction of a `MixedLubrication` joint.  At each sample of the
cycle the pin sits where the film and the asperities together carry the
joint load W (the force the pin exerts on the bushing, bushing frame):

    F_film(e; omega) + F_asperity(e) + W = 0,

with the journal's centre at rest relative to the bushing (e_dot = 0): the
steadily loaded journal bearing at each instant, whose eccentricity follows
the classic relation between eps and the Sommerfeld number (for the short
bearing, W = mu U L^3 eps / (4 c^2 (1 - eps^2)^2) sqrt(16 eps^2 + pi^2 (1 -
eps^2)), U = omega R).  The squeeze film and the whirl of the line of centres
are neglected (both are in the dynamic model); so is the film's response to
a load that turns with the journal.  The asperities carry what the film does
not where h_min falls to lambda_c sigma (`MixedLubrication`), with the
foundation's springs and the dry joint's friction, so a rough or thin-film
joint tends to the dry `QuasiStaticJoint`.

The offset is found by a damped Newton method on the 2 x 2 balance (the film's
cross-coupled force makes it non-symmetric: no energy to minimise, unlike the
dry joint), followed from each of these starts, the best root kept: the
film-only solution of the round bore (exact there: the film's load grows
monotonically with eps, and its direction turns rigidly with e), the dry
equilibrium on the asperity summits, and a warm start when given.
Derivatives by the implicit-function theorem, de = -J^-1 dr/dtheta, as a
custom JVP rule written in terms of the solution itself, so that it can be
differentiated again (the wear response A is a derivative of the wear, and a
life's derivative carries A's) and transposed for reverse mode; no unrolled
iterations.

Wear per cycle: Archard's law on the asperity pressure, summed over the
samples as for the dry joint; its response to the profile by forward-mode
differentiation of that sum (exact, through the implicit derivative).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array, Bool, Float

from ..contact.clearance_joint import ClearanceJoint
from ..contact.finite_bearing import FiniteBearingFilm
from ..contact.kinematics import PinKinematics
from ..contact.mixed import MixedLubrication, asperity_share
from ..contact.profile import BushingProfile
from ..errors import InputError
from ..mechanism.geometry import safe_norm
from .joint import QuasiStaticJoint, _solve_2x2, pin_offset
from .loads import JointLoads

# Newton tolerance on the force balance, relative to the load: 1e-10.
BALANCE_TOL = 1e-10
_NEWTON_STEPS = 60
# eccentricity ratios of the film-only start's table (the film's load grows
# monotonically with eps; the start interpolates it in log-load)
_START_RATIOS = np.concatenate([np.linspace(0.0, 0.9, 19)[1:], np.linspace(0.91, 0.995, 18)])
_LOAD_FLOOR = 1e-9  # N: below it the balance is scaled by this floor


class LubricatedEquilibrium(eqx.Module):
    """The lubricated pin at equilibrium at every sample of a cycle.

    offset: pin centre minus bushing centre, bushing frame [m] (S, 2)
    pressure: asperity pressure p(theta_k) [Pa] (S, n)
    normal_load: asperity normal load [N] (S,)
    film_load: |film force| [N] (S,)
    min_film_thickness: h_min [m] (S,)
    film_ratio: lambda = h_min / sigma (S,)
    interference: how far the asperities are pressed past the mean surfaces [m] (S,)
    ok: every Newton solve converged
    """

    offset: Float[Array, "S 2"]
    pressure: Float[Array, "S n"]
    normal_load: Float[Array, " S"]
    film_load: Float[Array, " S"]
    min_film_thickness: Float[Array, " S"]
    film_ratio: Float[Array, " S"]
    interference: Float[Array, " S"]
    ok: Bool[Array, ""]

    @property
    def asperity_share(self) -> Float[Array, " S"]:
        """Asperity load / (asperity + film load) per sample (`asperity_share`)."""
        return asperity_share(self.normal_load, self.film_load)


class LubricatedQuasiStaticJoint(eqx.Module):
    """A `MixedLubrication` clearance joint with Archard wear, in the
    quasi-static reduction (module notes).  ``dry`` is the same joint with its
    asperities' foundation as the law (it supplies the grid, the sliding rate,
    the contact check and the dry start)."""

    law: MixedLubrication
    dry: QuasiStaticJoint

    @classmethod
    def from_joint(cls, joint: ClearanceJoint) -> "LubricatedQuasiStaticJoint":
        if not isinstance(joint.law, MixedLubrication):
            raise InputError(f"clearance joint {joint.name!r} is not lubricated "
                             f"(law {type(joint.law).__name__})")
        dry = eqx.tree_at(lambda j: j.law, joint, joint.law.asperity)
        law = joint.law
        if isinstance(law.film, FiniteBearingFilm):
            # the centre is at rest in the bushing here: the finite film's steady
            # table (one Reynolds solve per node, not one per Newton step)
            law = eqx.tree_at(lambda m: m.film, law, law.film.steady(joint.pin_radius))
        return cls(law=law, dry=QuasiStaticJoint.from_joint(dry))

    @property
    def n(self) -> int:
        return self.dry.n

    @property
    def clearance(self) -> Float[Array, " n"]:
        """The unworn bore's clearance c0(theta_k) [m]."""
        return self.dry.clearance

    @property
    def directions(self) -> Float[Array, "n 2"]:
        return self.dry.directions

    def _kinematics(self, offset, omega) -> PinKinematics:
        return PinKinematics(offset=offset, offset_rate=jnp.zeros(2), omega=omega,
                             pin_radius=self.dry.pin_radius,
                             bushing_radius=self.dry.bushing_radius)

    def _profile(self, clearance) -> BushingProfile:
        return eqx.tree_at(lambda p: p.clearance, BushingProfile.circular(0.0, self.n),
                           clearance)

    def _parts(self, offset, omega, clearance):
        return self.law.lubrication(self._kinematics(offset, omega), jnp.zeros(0),
                                    self._profile(clearance), self.dry.friction)

    def _balance(self, offset, load, omega, clearance):
        """F_film + F_asperity + W [N]: zero at equilibrium."""
        parts = self._parts(offset, omega, clearance)
        return parts.film.force + parts.asperity.force + load

    def _film_start(self, load, omega):
        """The film-only equilibrium (the film is the unworn round bore's)."""
        film = self.law.saturated_film()
        c = film.clearance
        ratios = jnp.minimum(_START_RATIOS, film.max_eccentricity_ratio)
        forces = jax.vmap(lambda r: film.film(
            self._kinematics(jnp.array([r * c, 0.0]), omega)).force)(ratios)
        sizes = jnp.log(safe_norm(forces) + 1e-300)
        size = jnp.log(jnp.maximum(safe_norm(load), 1e-300))
        ratio = jnp.interp(size, sizes, ratios)
        force = film.film(self._kinematics(jnp.array([ratio * c, 0.0]), omega)).force
        # turn e so that the film's force opposes the load (the steady film of a
        # round bore turns rigidly with e)
        want = -load
        cos_t = force @ want
        sin_t = force[0] * want[1] - force[1] * want[0]
        turn = jnp.arctan2(sin_t, cos_t)
        return ratio * c * jnp.array([jnp.cos(turn), jnp.sin(turn)])

    def _solve(self, load, omega, clearance, guess):
        """Damped Newton on the balance from its starts (module notes): (e [m],
        converged); no derivatives (`_offset` gives them)."""
        scale = jnp.maximum(safe_norm(load), _LOAD_FLOOR)
        c0 = jnp.mean(clearance)

        def residual(x):
            return self._balance(c0 * x, load, omega, clearance) / scale

        dry = self.dry
        kc = dry.foundation.contact_stiffness(dry.bushing_radius)
        summits = clearance - self.law.onset_gap
        dry_start, _ = pin_offset(summits, dry.without_friction(load, omega), kc,
                                  dry.foundation.penetration_width)
        # a guess of NaN (none given) starts at the centre
        starts = jnp.stack([self._film_start(load, omega), dry_start, guess])
        starts = jnp.where(jnp.isfinite(starts), starts, 0.0) / c0

        def unfinished(state):
            x, r, k = state
            return (k < _NEWTON_STEPS) & (jnp.max(jnp.abs(r)) > BALANCE_TOL)

        def step(state):
            x, r, k = state
            jac = jax.jacfwd(residual)(x)
            ridge = 1e-12 * jnp.max(jnp.abs(jac)) * jnp.eye(2)
            dx = -_solve_2x2(jac + ridge, r)
            dx = jnp.where(jnp.all(jnp.isfinite(dx)), dx, -r)

            def too_long(trial):
                a, r_new = trial
                return (r_new @ r_new > (1.0 - 1e-4 * a) * (r @ r)) & (a > 1e-10)

            def shorten(trial):
                a = 0.5 * trial[0]
                return a, residual(x + a * dx)

            a, r_new = lax.while_loop(too_long, shorten, (jnp.ones(()), residual(x + dx)))
            return x + a * dx, r_new, k + 1

        def newton(x0):
            x, r, _ = lax.while_loop(unfinished, step, (x0, residual(x0), 0))
            return x, jnp.max(jnp.abs(r))

        # the starts are followed in the order of their residuals until one
        # reaches the root: a start can stall where the saturated film turns
        # without growing (a pin inside a worn groove, no spring touching)
        sizes = jax.vmap(lambda x: jnp.max(jnp.abs(residual(x))))(starts)
        starts = starts[jnp.argsort(jnp.where(jnp.isfinite(sizes), sizes, jnp.inf))]

        def untried(state):
            k, _, error = state
            return (k < starts.shape[0]) & ~(error <= BALANCE_TOL)

        def try_next(state):
            k, x_best, error_best = state
            x, error = newton(starts[k])
            better = jnp.isfinite(error) & ~(error >= error_best)
            return k + 1, jnp.where(better, x, x_best), jnp.where(better, error, error_best)

        _, x, error = lax.while_loop(untried, try_next, (0, starts[0], jnp.asarray(jnp.inf)))
        return c0 * x, error <= BALANCE_TOL

    def pin_offset(self, load, omega, clearance, guess=None):
        """Offset e [m] at equilibrium under ``load`` [N] at spin ``omega``
        [rad/s] on the bore ``clearance`` [m] (n,), and 1.0 if the solve
        converged (else 0.0); differentiable in every input, to any order
        (module notes)."""
        guess = jnp.full(2, jnp.nan) if guess is None else lax.stop_gradient(guess)
        return _offset(self, load, omega, clearance, guess)

    # ----------------------------------------------------------- the cycle
    def equilibrium(self, depth: Float[Array, " n"], loads: JointLoads,
                    guess: Float[Array, "S 2"] | None = None) -> LubricatedEquilibrium:
        """The pin's offset, the film and the asperities over the cycle at
        wear ``depth`` [m]; ``guess``: starting offsets (e.g. those of a
        nearby profile)."""
        c = self.dry.clearance + depth
        guess = jnp.full_like(loads.force, jnp.nan) if guess is None else guess

        def one(w, omega, g):
            e, ok = self.pin_offset(w, omega, c, g)
            ok = ok > 0.5
            parts = self._parts(e, omega, c)
            return (e, parts.asperity.pressure, parts.asperity_load, parts.film_load,
                    parts.min_film_thickness, parts.film_ratio, parts.interference, ok)

        e, p, load, film_load, h_min, ratio, overlap, ok = jax.vmap(one)(
            loads.force, loads.omega, guess)
        return LubricatedEquilibrium(offset=e, pressure=p, normal_load=load, film_load=film_load,
                                     min_film_thickness=h_min, film_ratio=ratio,
                                     interference=overlap,
                                     ok=jnp.all(ok) & jnp.all(jnp.isfinite(e)))

    def cycle_wear(self, depth: Float[Array, " n"], loads: JointLoads, guess=None):
        """(dh per cycle [m] (n,), integral of asperity load x sliding [N m],
        `LubricatedEquilibrium`) at wear ``depth``."""
        eq = self.equilibrium(depth, loads, guess)
        slide = self.dry.sliding_rate(loads)
        dh = loads.dt * jnp.sum(self.dry.wear.depth_rate(eq.pressure, slide[:, None]), axis=0)
        return dh, loads.dt * jnp.sum(eq.normal_load * slide), eq

    def wear_response(self, depth: Float[Array, " n"], loads: JointLoads,
                      eq: LubricatedEquilibrium | None = None) -> Float[Array, "n n"]:
        """A = -d(dh per cycle)/d(depth) (n, n), by forward-mode differentiation
        (warm-started at ``eq``'s offsets)."""
        guess = None if eq is None else lax.stop_gradient(eq.offset)
        return -jax.jacfwd(lambda h: self.cycle_wear(h, loads, guess)[0])(depth)

    def contact_margin(self, depth, loads, mass):
        """The dry joint's check on the loads (`QuasiStaticJoint.contact_margin`):
        below 1 the load turns too fast for the pin to follow it at equilibrium."""
        return self.dry.contact_margin(depth, loads, mass)


@jax.custom_jvp
def _offset(joint, load, omega, clearance, guess):
    e, ok = joint._solve(load, omega, clearance, guess)
    return e, ok.astype(e.dtype)


@_offset.defjvp
def _offset_jvp(primals, tangents):
    """de = -J^-1 (dr/dtheta . dtheta) at the root of the balance r(e, theta),
    J = dr/de (2 x 2, closed form).  ``e`` here is the primal output of
    `_offset` itself, so derivatives of this rule (second derivatives of the
    offset, e.g. of the wear response in a life's tangent) are exact too."""
    joint, load, omega, clearance, _ = primals
    e, ok = _offset(*primals)

    def balance(j, w, om, c):
        return j._balance(e, w, om, c)

    _, dr = jax.jvp(balance, primals[:4], tangents[:4])
    jac = jax.jacfwd(lambda x: joint._balance(x, load, omega, clearance))(e)
    return (e, ok), (-_solve_2x2(jac, dr), jnp.zeros_like(ok))


def joint_model(joint: ClearanceJoint):
    """The quasi-static model of a clearance joint: lubricated or dry."""
    if isinstance(joint.law, MixedLubrication):
        return LubricatedQuasiStaticJoint.from_joint(joint)
    return QuasiStaticJoint.from_joint(joint)
