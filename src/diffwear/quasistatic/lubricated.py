"""The lubricated joint at equilibrium: film plus asperities, wear of one cycle.

Quasi-static reduction of a `MixedLubrication` joint (no inertia of the
pin).  The steady balance: at each sample of the cycle the pin sits where the
film and the asperities together carry the joint load W (the force the pin
exerts on the bushing, bushing frame):

    F_film(e; omega) + F_asperity(e) + W = 0,

with the journal's centre at rest relative to the bushing (e_dot = 0): the
steadily loaded journal bearing at each instant, whose eccentricity follows
the classic relation between eps and the Sommerfeld number (for the short
bearing, W = mu U L^3 eps / (4 c^2 (1 - eps^2)^2) sqrt(16 eps^2 + pi^2 (1 -
eps^2)), U = omega R).  It is the limit of slow loads of the orbit below,
which adds the squeeze film and the whirl of the line of centres (the
default; ``squeeze=False`` keeps the steady balance).  The asperities carry what the film does
not as the film thins (Greenwood-Tripp summits in series with the
foundation, `MixedLubrication`), with the dry joint's friction, so a rough or thin-film
joint tends to the dry `QuasiStaticJoint`.

The offset is found by a damped Newton method on the 2 x 2 balance (the film's
cross-coupled force makes it non-symmetric: no energy to minimise, unlike the
dry joint), followed from each of these starts, the best root kept: the
film-only solution of the round bore (exact there: the film's load grows
monotonically with eps, and its direction turns rigidly with e), the dry
equilibrium on the bore less 3 sigma, and a warm start when given.
Derivatives by the implicit-function theorem, de = -J^-1 dr/dtheta, as a
custom JVP rule written in terms of the solution itself, so that it can be
differentiated again (the wear response A is a derivative of the wear, and a
life's derivative carries A's) and transposed for reverse mode; no unrolled
iterations.

**The orbit (squeeze film through the reversals).**  In an oscillating
joint the relative rotation omega reverses twice a cycle; there the wedge
film vanishes and the steady balance above puts the pin on its asperities
whatever the oil.  A real journal keeps a squeeze film through the reversal:
the pin cannot approach the wall faster than the oil is pressed out.  So the
default (``squeeze=True``) solves the balance with the centre's velocity,

    F_film(e, e_dot; omega) + F_asperity(e) + W(t) = 0,

the film law's squeeze and wedge terms together (`AbstractFilm.film`), over
the cycle's equally spaced samples t_i = i T / S, by backward Euler:
e_dot_i = (e_i - e_{i-1}) / dt, dt = T / S, each sample's e_i by the damped
Newton method below (the previous sample's offset one more start), and
periodic: e_{-1} = e_{S-1}.  The periodic orbit is found by shooting on the
starting offset: a sweep over the cycle maps e_{-1} to e_{S-1}; its
derivative, the monodromy Phi = prod_i (-J_i^-1 B_i) (J_i, B_i the balance's
derivatives in e_i and e_{i-1}), gives the Newton update of the start,
(I - Phi)^-1 (e_{S-1} - e_{-1}) (where the film forgets the start within a
cycle, Phi ~ 0 and it is a plain second sweep).  Periodic when |e_{S-1} -
e_{-1}| <= `ORBIT_TOL` c, within `ORBIT_PASSES` sweeps (Newton with
backtracking on the start).  Where it does not close, the steady balance
stands in (``orbit_closed`` False): a pin in a groove deeper than the
clearance, whose saturated film turns without growing, has a nearly
neutral orbit (an eigenvalue of Phi near 1), with no restoring force
across the cycle for the shooting to find.  The asperities see the centre at rest, as in the dry
quasi-static joint (their hysteresis damping and the drift's share of the
slip are left out); only the film sees e_dot.

Backward Euler is L-stable: on samples coarse against the squeeze time
tau = (squeeze damping) / (film or asperity stiffness) it does not ring; it
relaxes each step by 1 / (1 + dt / tau) where the exact film relaxes by
exp(-dt / tau), so it resolves the squeeze's approach where dt < tau and, on
coarser samples, gives the steady balance in the limit (a slowly varying
load: the orbit is the steady solution, with a lag of order tau).  The
reversal of a sample spacing dt is resolved to its first order: the film's
thickness through it is right to O(dt / tau) (tests/test_squeeze_orbit.py
compares the approach with a tight ODE solution).  ``squeeze=False`` keeps
the steady balance of every sample (the limit of slow loads).  A finite
film (`FiniteBearingFilm`) enters as its moving-journal table
(`finite_table.moving_film`: the shipped tables on the default grid), with
its squeeze and wedge, like the short and long films.

Derivatives of the orbit: the implicit-function theorem on the periodic
system, J_i de_i + B_i de_{i-1} = -dr_i, solved as the chain de_i = M_i
de_{i-1} + g_i closed by periodicity, de_{-1} = (I - Phi)^-1 G (G the chain's
end from de_{-1} = 0); written, like the steady offset's, in terms of the
solution itself, so that it can be differentiated again and transposed.

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
from jax.ad_checkpoint import checkpoint_name
from jaxtyping import Array, Bool, Float

from ..contact.clearance_joint import ClearanceJoint
from ..contact.finite_bearing import FiniteBearingFilm
from ..contact.finite_table import moving_film
from ..contact.kinematics import PinKinematics
from ..contact.mixed import MixedLubrication, asperity_share
from ..contact.profile import BushingProfile
from ..errors import InputError
from ..mechanism.geometry import safe_norm
from .joint import EQUILIBRIUM, QuasiStaticJoint, _solve_2x2, pin_offset
from .loads import JointLoads

# Newton tolerance on the force balance, relative to the load: 1e-10.
BALANCE_TOL = 1e-10
_NEWTON_STEPS = 60
# eccentricity ratios of the film-only start's table (the film's load grows
# monotonically with eps; the start interpolates it in log-load)
_START_RATIOS = np.concatenate([np.linspace(0.0, 0.9, 19)[1:], np.linspace(0.91, 0.995, 18)])
_LOAD_FLOOR = 1e-9  # N: below it the balance is scaled by this floor
# The orbit is periodic when the last sample's offset returns to the start's
# within 1e-8 of the clearance (0.5 pm on 50 um: far below the 1e-10-relative
# balance's effect on the film, and on the wear's 1e-6-level derivatives).
ORBIT_TOL = 1e-8
# Shooting sweeps at most: Newton on the start, with the exact monodromy,
# converges quadratically; plain sweeps (the start taken from the end) would
# contract by ~ exp(-T / tau) a cycle, ~ 2.3 tau / T sweeps a decade where
# the squeeze time tau is long against the period T.
ORBIT_PASSES = 20


class LubricatedEquilibrium(eqx.Module):
    """The lubricated pin at equilibrium at every sample of a cycle.

    offset: pin centre minus bushing centre, bushing frame [m] (S, 2)
    pressure: asperity pressure p(theta_k) [Pa] (S, n)
    normal_load: asperity normal load [N] (S,)
    film_load: |film force| [N] (S,) (on the orbit: wedge and squeeze)
    min_film_thickness: h_min [m] (S,)
    film_ratio: lambda = h_min / sigma (S,)
    interference: how far the asperities are pressed past the mean surfaces [m] (S,)
    ok: every Newton solve converged
    orbit_closed: the orbit with the squeeze film closed (False: the steady
        balance at every sample stands in, or ``squeeze=False``)
    """

    offset: Float[Array, "S 2"]
    pressure: Float[Array, "S n"]
    normal_load: Float[Array, " S"]
    film_load: Float[Array, " S"]
    min_film_thickness: Float[Array, " S"]
    film_ratio: Float[Array, " S"]
    interference: Float[Array, " S"]
    ok: Bool[Array, ""]
    orbit_closed: Bool[Array, ""]

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
    squeeze: bool = eqx.field(static=True, default=True)

    @classmethod
    def from_joint(cls, joint: ClearanceJoint,
                   squeeze: bool = True) -> "LubricatedQuasiStaticJoint":
        """``squeeze``: the orbit with the squeeze film (default) or the steady
        balance at every sample (module notes)."""
        if not isinstance(joint.law, MixedLubrication):
            raise InputError(f"clearance joint {joint.name!r} is not lubricated "
                             f"(law {type(joint.law).__name__})")
        dry = eqx.tree_at(lambda j: j.law, joint, joint.law.asperity)
        law = joint.law
        if isinstance(law.film, FiniteBearingFilm):
            # the finite film tabulated for a moving journal (squeeze and
            # wedge; not one Reynolds solve per Newton step), up to the
            # saturation of the mixed law: the shipped tables on the default grid
            saturated = law.saturated_film()
            assert isinstance(saturated, FiniteBearingFilm)  # the same film, its eps_max set
            law = eqx.tree_at(lambda m: m.film, law, moving_film(saturated, joint.pin_radius))
        return cls(law=law, dry=QuasiStaticJoint.from_joint(dry), squeeze=bool(squeeze))

    def steady(self) -> "LubricatedQuasiStaticJoint":
        """This joint with the steady balance at every sample (the orbit's
        limit of slow loads; module notes)."""
        return LubricatedQuasiStaticJoint(law=self.law, dry=self.dry, squeeze=False)

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

    def _kinematics(self, offset, omega, rate=None) -> PinKinematics:
        rate = jnp.zeros(2) if rate is None else rate
        return PinKinematics(offset=offset, offset_rate=rate, omega=omega,
                             pin_radius=self.dry.pin_radius,
                             bushing_radius=self.dry.bushing_radius)

    def _profile(self, clearance) -> BushingProfile:
        return eqx.tree_at(lambda p: p.clearance, BushingProfile.circular(0.0, self.n),
                           clearance)

    def _parts(self, offset, omega, clearance, rate=None):
        """The film and the asperities (`Lubrication`) at ``offset``; the film
        with the centre's velocity ``rate`` [m/s] (default at rest), the
        asperities at rest (module notes)."""
        parts = self.law.lubrication(self._kinematics(offset, omega), jnp.zeros(0),
                                     self._profile(clearance), self.dry.friction)
        if rate is None:
            return parts
        film = self.law.saturated_film().film(self._kinematics(offset, omega, rate))
        return parts._replace(film=film, film_load=safe_norm(film.force))

    def _balance(self, offset, load, omega, clearance, rate=None):
        """F_film + F_asperity + W [N]: zero at equilibrium; the film with the
        centre's velocity ``rate`` [m/s] (default at rest)."""
        film = self.law.saturated_film().film(self._kinematics(offset, omega, rate))
        at_rest, profile = self._kinematics(offset, omega), self._profile(clearance)
        asperity = self.law.asperity.resultant(
            at_rest, profile, self.law.asperity_pressure(at_rest, profile), self.dry.friction)
        return film.force + asperity.force + load

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

    def _solve(self, load, omega, clearance, guess, previous=None, dt=None):
        """Damped Newton on the balance from its starts (module notes): (e [m],
        converged); no derivatives (`_offset`, `_orbit` give them).  With
        ``previous`` [m] and ``dt`` [s]: the backward-Euler step of the orbit,
        the film's centre velocity (e - previous) / dt, ``previous`` one more
        start."""
        scale = jnp.maximum(safe_norm(load), _LOAD_FLOOR)
        c0 = jnp.mean(clearance)

        def residual(x):
            rate = None if previous is None else (c0 * x - previous) / dt
            return self._balance(c0 * x, load, omega, clearance, rate) / scale

        dry = self.dry
        kc = dry.foundation.contact_stiffness(dry.bushing_radius)
        summits = clearance - self.law.onset_gap
        dry_start, _ = pin_offset(summits, dry.without_friction(load, omega), kc,
                                  dry.foundation.penetration_width)
        # a guess of NaN (none given) starts at the centre
        starts = [self._film_start(load, omega), dry_start, guess]
        starts = jnp.stack(starts if previous is None else [*starts, previous])
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

    # ----------------------------------------------------------- the orbit
    def _step_jacobians(self, offsets, previous, force, omega, dt, clearance):
        """(J_i, B_i) (S, 2, 2): the backward-Euler balance's derivatives in
        e_i and in e_{i-1} at every sample."""
        def balance(e, prev, w, om):
            return self._balance(e, w, om, clearance, (e - prev) / dt)

        return jax.vmap(jax.jacfwd(balance, argnums=(0, 1)))(offsets, previous, force, omega)

    def _sweep(self, force, omega, dt, clearance, guess, start):
        """Backward Euler over the samples from the offset ``start`` [m] one
        step before the first: (e [m] (S, 2), every step converged)."""
        def step(prev, sample):
            w, om, g = sample
            e, ok = self._solve(w, om, clearance, g, prev, dt)
            return e, (e, ok)

        _, (es, oks) = lax.scan(step, start, (force, omega, guess))
        return es, jnp.all(oks)

    def march(self, loads: JointLoads, clearance: Float[Array, " n"], start):
        """The journal's motion from the offset ``start`` [m] under the
        samples of ``loads``, by the orbit's backward-Euler steps without
        closing the cycle: offsets [m] (S, 2), e_i at time (i + 1) dt after
        the start, and 1.0 if every step converged (else 0.0).  A transient
        (e.g. a squeeze from the centre) for checks; not differentiated
        (`orbit` is)."""
        nan = jnp.full_like(loads.force, jnp.nan)
        es, ok = self._sweep(loads.force, loads.omega, loads.dt, clearance, nan,
                             jnp.asarray(start, dtype=float))
        return es, ok.astype(es.dtype)

    def _orbit_solve(self, force, omega, dt, clearance, guess):
        """The periodic backward-Euler orbit by shooting (module notes): (e [m]
        (S, 2), converged); no derivatives (`_orbit` gives them)."""
        c0 = jnp.mean(clearance)
        # no guess: from the centre (the first sweep's steps carry the pin to
        # its loads; the shooting then closes the orbit)
        start = jnp.where(jnp.all(jnp.isfinite(guess[-1])), guess[-1], 0.0)

        def sweep(start):
            return self._sweep(force, omega, dt, clearance, guess, start)

        def unfinished(state):
            k, _, best = state[0], state[1], state[2]
            return (k < ORBIT_PASSES) & ~(best[3] <= ORBIT_TOL)

        def one_pass(state):
            # Newton on the start with backtracking: a start whose sweep misses
            # by more than the best one's is replaced by half the step from the
            # best (near a neutral orbit, a pin in a worn groove whose film
            # turns without growing, I - Phi is nearly singular)
            k, (start, length), best = state
            es, ok = sweep(start)
            miss = es[-1] - start
            defect = jnp.where(jnp.all(jnp.isfinite(miss)), safe_norm(miss) / c0, jnp.inf)
            better = defect < best[3]
            previous = jnp.concatenate([start[None], es[:-1]])
            jac, back = self._step_jacobians(es, previous, force, omega, dt, clearance)
            phi = _monodromy(_chain_matrices(jac, back))
            jump = _solve_2x2(jnp.eye(2) - phi, miss)
            # a Newton jump kept within half the clearance; a plain sweep where
            # it is not finite
            size = safe_norm(jump)
            jump = jnp.where(size > 0.5 * c0, 0.5 * c0 / jnp.maximum(size, 1e-300), 1.0) * jump
            jump = jnp.where(jnp.all(jnp.isfinite(jump)), jump, miss)
            best = jax.tree.map(lambda new, old: jnp.where(better, new, old),
                                (start, es, ok, defect, jump), best)
            length = jnp.where(better, 1.0, 0.5 * length)
            return k + 1, (best[0] + length * best[4], length), best

        best = (start, jnp.zeros_like(force), jnp.asarray(False), jnp.asarray(jnp.inf),
                jnp.zeros(2))
        _, _, best = lax.while_loop(unfinished, one_pass, (0, (start, jnp.ones(())), best))
        _, es, ok, defect, _ = best
        return es, ok & (defect <= ORBIT_TOL)

    def orbit(self, loads: JointLoads, clearance: Float[Array, " n"],
              guess: Float[Array, "S 2"] | None = None):
        """The journal's periodic orbit over the cycle of ``loads`` on the bore
        ``clearance`` [m] (n,), with the squeeze film (module notes): offsets
        e [m] (S, 2), and 1.0 if every step converged and the orbit closed
        (else 0.0); differentiable in every input, to any order.  ``guess``:
        starting offsets (e.g. a nearby profile's orbit)."""
        guess = (jnp.full_like(loads.force, jnp.nan) if guess is None
                 else lax.stop_gradient(guess))
        return _orbit(self, loads.force, loads.omega, loads.dt, clearance, guess)

    # ----------------------------------------------------------- the cycle
    def equilibrium(self, depth: Float[Array, " n"], loads: JointLoads,
                    guess: Float[Array, "S 2"] | None = None) -> LubricatedEquilibrium:
        """The pin's offset, the film and the asperities over the cycle at
        wear ``depth`` [m]: the orbit with the squeeze film, or the steady
        balance at every sample with ``squeeze=False`` (module notes);
        ``guess``: starting offsets (e.g. those of a nearby profile)."""
        c = self.dry.clearance + depth
        start = jnp.full_like(loads.force, jnp.nan) if guess is None else guess

        def steady():
            e, ok = jax.vmap(lambda w, om, g: self.pin_offset(w, om, c, g))(
                loads.force, loads.omega, start)
            return e, jnp.zeros_like(e), jnp.all(ok > 0.5)

        if self.squeeze:
            orbit, closed = self.orbit(loads, c, guess)
            closed = (closed > 0.5) & jnp.all(jnp.isfinite(orbit))

            def periodic():
                rates = (orbit - jnp.roll(orbit, 1, axis=0)) / loads.dt
                return orbit, rates, jnp.asarray(True)

            # where the orbit does not close (a pin in a groove deeper than the
            # clearance, its saturated film turning without growing: the orbit
            # is nearly neutral), the steady balance stands in; a branch, so
            # that a closed orbit does not pay for the steady solves (their
            # Newton loops, batched over the samples, run as long as the
            # slowest sample's)
            offsets, rates, ok = lax.cond(closed, periodic, steady)
        else:
            (offsets, rates, ok), closed = steady(), jnp.asarray(False)

        def one(e, omega, rate):
            parts = self._parts(e, omega, c, rate)
            return (parts.asperity.pressure, parts.asperity_load, parts.film_load,
                    parts.min_film_thickness, parts.film_ratio, parts.interference)

        p, load, film_load, h_min, ratio, overlap = jax.vmap(one)(offsets, loads.omega, rates)
        return LubricatedEquilibrium(offset=offsets, pressure=p, normal_load=load,
                                     film_load=film_load, min_film_thickness=h_min,
                                     film_ratio=ratio, interference=overlap,
                                     ok=ok & jnp.all(jnp.isfinite(offsets)),
                                     orbit_closed=closed)

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
    e = checkpoint_name(e, EQUILIBRIUM)

    def balance(j, w, om, c):
        return j._balance(e, w, om, c)

    _, dr = jax.jvp(balance, primals[:4], tangents[:4])
    jac = jax.jacfwd(lambda x: joint._balance(x, load, omega, clearance))(e)
    return (e, ok), (-_solve_2x2(jac, dr), jnp.zeros_like(ok))


def _chain_matrices(jac, back):
    """M_i = -J_i^-1 B_i (S, 2, 2): de_i = M_i de_{i-1} + g_i."""
    return -jax.vmap(_solve_2x2)(jac, back)


def _monodromy(chain):
    """Phi = M_{S-1} ... M_1 M_0: the cycle's map of a change of the start."""
    phi, _ = lax.scan(lambda p, m: (m @ p, None), jnp.eye(2), chain)
    return phi


@jax.custom_jvp
def _orbit(joint, force, omega, dt, clearance, guess):
    e, ok = joint._orbit_solve(force, omega, dt, clearance, guess)
    return e, ok.astype(e.dtype)


@_orbit.defjvp
def _orbit_jvp(primals, tangents):
    """The implicit-function theorem on the periodic backward-Euler system
    r_i(e_i, e_{i-1}, theta) = 0, e_{-1} = e_{S-1} (module notes): J_i de_i +
    B_i de_{i-1} = -dr_i, the chain de_i = M_i de_{i-1} + g_i (M_i = -J_i^-1
    B_i, g_i = -J_i^-1 dr_i) closed by de_{-1} = (I - Phi)^-1 G.  ``e`` is the
    primal output of `_orbit` itself, so the rule differentiates again."""
    joint, force, omega, dt, clearance, _ = primals
    e, ok = _orbit(*primals)
    e = checkpoint_name(e, EQUILIBRIUM)
    previous = jnp.roll(e, 1, axis=0)

    def residuals(j, w, om, step, c):
        return jax.vmap(lambda ei, pi, wi, oi: j._balance(ei, wi, oi, c, (ei - pi) / step))(
            e, previous, w, om)

    _, dr = jax.jvp(residuals, primals[:5], tangents[:5])
    jac, back = joint._step_jacobians(e, previous, force, omega, dt, clearance)
    chain = _chain_matrices(jac, back)
    forcing = -jax.vmap(_solve_2x2)(jac, dr)

    def link(de, mg):
        m, g = mg
        de = m @ de + g
        return de, de

    end, _ = lax.scan(link, jnp.zeros(2), (chain, forcing))
    start = _solve_2x2(jnp.eye(2) - _monodromy(chain), end)
    _, de = lax.scan(link, start, (chain, forcing))
    return (e, ok), (de, jnp.zeros_like(ok))


def joint_model(joint: ClearanceJoint):
    """The quasi-static model of a clearance joint: lubricated or dry."""
    if isinstance(joint.law, MixedLubrication):
        return LubricatedQuasiStaticJoint.from_joint(joint)
    return QuasiStaticJoint.from_joint(joint)
