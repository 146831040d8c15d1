"""Archard wear with the contact pressure of a finite-element ring: the thesis's
FEM route (Ch. 5).

The dynamics still run with the elastic-foundation (EFM) clearance joint: it
supplies the joint force and the pin's relative rotation.  The wear pressure
is not the EFM's: for each dynamic cycle the joint force at ``n_samples + 1``
equally spaced times (each the end of an integrator step: the cycle steps
onto them, see "Integrator") is applied to the rigid pin in the plane-strain bushing
ring (`diffwear.fem.RingContact`, given-force, frictionless contact), and the
depth increment on the profile grid theta_k is

    dh_k = k integral p_k(t) R_b |omega_rel(t)| dt
         ~ k sum_i w_i p_k(t_i) R_b |omega_rel(t_i)|,       (trapezoid weights w_i)

the quadrature of the integral that the EFM route integrates exactly as ODE
states (`wear.cycle`).  The thesis did the same with ANSYS: the joint reaction
of each dynamic analysis, at discrete crank positions, loaded the FE bushing,
and the element pressures gave the Archard increments (Ch. 5, "Wear
prediction procedure").  The profile then evolves by A x dh (constant A) with
the EFM route's bookkeeping (`Evolver`), and the worn profile feeds back into
both the dynamics' EFM clearance c0 + h and the FE mesh's inner surface a + h.

Friction.  The FE contact is frictionless; the dynamics' joint force contains
the Coulomb friction of the pin (mu = 0.13: tangential part ~ mu x normal).
``force="resultant"`` (default) applies the whole joint force, as the thesis
applied the dynamics' joint reaction to its frictionless ANSYS contact (Ch. 5);
its direction is then rotated from the normal resultant by up to
atan(mu) = 7.4 deg and its magnitude is larger by up to sqrt(1 + mu^2) - 1 =
0.8 %.  ``force="normal"`` applies only the normal part of the joint force as
the EFM splits it (sum of the spring loads p_k R_b d dtheta along u_k), the
choice for comparing pressure models at equal normal load (the Winkler-limit
test).

Pressure for wear.  The FE nodal forces f_j [N/m] are turned into pressures
with the tributary lengths w0_j of the *unworn* round ring (R_b dtheta in
Simpson weights): the EFM route's convention (pressure per unworn arc
R_b dtheta, sliding R_b |omega|, volume d R_b integral h dtheta), so that the
worn volume equals k x sum(total normal load x sliding) up to the quadrature of
the nodal pressures (Simpson in the loads, rectangle rule in the volume).
With the worn surface's lengths (a + h) dtheta the volume would fall short of
the Archard volume by ~h / a (5 % at the rig's peak) for bookkeeping alone.

Stiffness of the wear step: a linearly implicit update.  The EFM route adds
A x dh(h) (explicit Euler in the cycle count).  A wear step is stable while
A k s K < 2 for every profile mode (s = 2 pi R_b sliding per cycle, K the
pressure per unit depth of the mode).  The EFM's springs have one K = E_W / L
(rig: A k s K = 428 x 5.05e-13 x 0.060 x 1.48e11 = 1.9, just stable); the
elastic ring is stiffer for short modes, K ~ E* pi / lambda for a wavelength
lambda below the wall thickness (E* = E / (1 - nu^2)): ~20 x the EFM's at
lambda = 2 node spacings, so the explicit step turns the worn pocket into a
node-to-node zigzag (docs, "FEM contact and the FEM wear route").
The FEM route therefore takes the linearly implicit (Rosenbrock-Euler) step

    (I - A J) Delta h = A dh(h),     J = d(dh)/dh at h,

with J from the contact's implicit derivative (in closed form at each
sample's solution, by default at every sample: the derivative of the
increment's own quadrature; ``jacobian_samples`` a subset; compliance held,
`depth_jacobian`), which damps every
mode instead of amplifying it and equals A dh where the wear is uniform;
Delta h is floored at 0 (material is only removed).  J holds the contact set
of the step's start: a node that leaves or enters contact during a step is
not anticipated, and the worn profile keeps a node-to-node roughness of about
one wear step's depth, so that its maximum depth scatters between runs that
differ at round-off; `diffwear.wear.arc_peak_depth` and the volume scatter
less (the docs' FEM page gives the figures).

Integrator.  The cycle steps exactly onto the sample times (`wear_cycle`'s
``step_to_saves``), so the samples are step ends, never the integrator's
interpolant: between the long steps of a linearly implicit solver (Rodas4)
an interpolant misses the stiff contact.  The Rosenbrock dense output is then
never read and is dropped (`sampling_solver`).

FE solves.  The samples are solved in order, each from the previous sample's
solution (a few semismooth Newton steps each), on the half ring around
the joint force first (`contact_window`; accepted only if it solves the
whole ring's problem), with the Newton Jacobian in closed form and without
the final polishing step (`diffwear.fem.contact`); J's derivative of each
sample is one LU at its solution (the cost of each part of a cycle:
benchmarks/experiments/fem_route_cycle_profile.py).

Geometry refresh.  The condensed compliance C of the worn ring is rebuilt from
the current profile every ``refresh_interval`` = M wear cycles (mesh and
condensation); in between, wear enters only through the
initial gap (boundary radius a + h) with the last C kept.  M = 1 rebuilds every
cycle; the default, 3, every third.  The FE grid is the profile grid (same
n_theta nodes, theta_j = 2 pi j / n): no interpolation.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array, Float

from .._checks import check_int_option, check_positive, check_range, concrete, require_float64
from ..dynamics.projection import replace_inner
from ..dynamics.rosenbrock import AbstractRosenbrock
from ..errors import InputError
from ..fem import RingContact, ring_mesh
from ..fem.condense import inner_compliance, tributary_lengths
from ..fem.contact import CONTACT_FRACTION, TOL
from ..mechanism import Mechanism
from ..mechanism.geometry import grid_angles, safe_norm
from ._engine import CycleWear
from .cycle import clearance_element, wear_parts
from .dynamic_term import DynamicWear
from .evolution import Evolver
from .extrapolation import AbstractExtrapolation, Constant
from .solution import WearSolution

FORCE_MODES = ("resultant", "normal")

# Joint forces below this are treated as no contact (pressure 0): the given-force
# problem is undetermined at F = 0 (`RingContact.solve_force`).  1e-6 N is 1e-8
# of the rig's ~140 N mean joint force; a free-flying pin in the EFM dynamics
# carries ~1e-12 N (smoothed spring onset).
MIN_JOINT_FORCE = 1e-6  # N

# A sample's FE solve counts as failed (SolverError via the evolution status) when
# its dimensionless residual max |Phi| exceeds this.  The solve aims at
# `fem.contact.TOL` = 1e-12 and may stop at its round-off floor just above it
# (seen once in a rig run with M = 5); 1e-9 of the gap scale (~0.1 mm) is a
# gap error of 1e-13 m and a force error of 1e-9 of the load: nothing for wear.
ACCEPT_RESIDUAL = 1e-9

# Defaults, chosen by convergence checks on the rig (docs, "FEM contact and the
# FEM wear route"; benchmarks/records/fem_route_scatter.json): n_samples, the
# cycle increment within 1e-3 of 256 samples; n_layers, the peak pressure
# within 1e-3 of 8 Q9 layers; refresh_interval, the compliance rebuilt every
# 3rd wear cycle, rig-21400's means over eight runs at M = 1, 2, 3 within their
# scatter; jacobian_samples (None: all), J as the derivative of the increment's
# own quadrature (from every 8th sample the profile is rougher).
DEFAULT_SAMPLES = 64
DEFAULT_LAYERS = 4
DEFAULT_REFRESH = 3
DEFAULT_JACOBIAN_SAMPLES = None


class FemWearModel(eqx.Module):
    """Settings of the FEM route.  Numbers a user may sweep are arrays.

    youngs_modulus E [Pa], poisson_ratio nu: the bushing ring's material;
    outer_radius b [m]: the ring is held at r = b; refresh_interval M: wear
    cycles between rebuilds of the condensed compliance (integer >= 1; an array,
    so that one compiled evolution serves every M); n_samples: quadrature
    intervals per dynamic cycle (FE solves: n_samples + 1); n_layers: Q9 element
    layers through the wall; force: "resultant" or "normal" (module docstring);
    jacobian_samples: intervals of the samples that form the implicit step's J
    (None: all n_samples).
    """

    youngs_modulus: Float[Array, ""]
    poisson_ratio: Float[Array, ""]
    outer_radius: Float[Array, ""]
    refresh_interval: Float[Array, ""]
    n_samples: int = eqx.field(static=True)
    n_layers: int = eqx.field(static=True)
    force: str = eqx.field(static=True)
    jacobian_samples: int = eqx.field(static=True)

    def __init__(self, youngs_modulus, poisson_ratio, outer_radius, *,
                 refresh_interval=DEFAULT_REFRESH, n_samples: int = DEFAULT_SAMPLES,
                 n_layers: int = DEFAULT_LAYERS, force: str = "resultant",
                 jacobian_samples: int | None = DEFAULT_JACOBIAN_SAMPLES):
        check_positive("FEM route: Young's modulus E [Pa]", youngs_modulus)
        check_range("FEM route: Poisson ratio nu", poisson_ratio, -1.0, 0.5,
                    low_open=True, high_open=True)
        check_positive("FEM route: bushing outer radius b [m]", outer_radius)
        m = concrete(refresh_interval)
        if m is not None and (m.shape != () or not np.isfinite(m) or m < 1 or m != np.round(m)):
            raise InputError(f"FEM route: refresh_interval (wear cycles between rebuilds of "
                             f"the ring compliance) must be an integer >= 1, got "
                             f"{np.asarray(refresh_interval).tolist()!r}")
        for name, v, low in (("n_samples (quadrature intervals per cycle)", n_samples, 2),
                             ("n_layers (element layers through the wall)", n_layers, 1),
                             ("jacobian_samples (intervals of the implicit step's J)",
                              n_samples if jacobian_samples is None else jacobian_samples, 1)):
            check_int_option(f"FEM route: {name}", v, low)
        if force not in FORCE_MODES:
            raise InputError(f"FEM route: force must be one of {FORCE_MODES}, got {force!r}")
        f = lambda v: jnp.asarray(v, dtype=float)  # noqa: E731
        self.youngs_modulus, self.poisson_ratio = f(youngs_modulus), f(poisson_ratio)
        self.outer_radius, self.refresh_interval = f(outer_radius), f(refresh_interval)
        if jacobian_samples is None:
            jacobian_samples = n_samples
        if jacobian_samples > n_samples:
            raise InputError(f"FEM route: jacobian_samples ({jacobian_samples}) must not exceed "
                             f"n_samples ({n_samples})")
        self.n_samples, self.n_layers, self.force = int(n_samples), int(n_layers), force
        self.jacobian_samples = int(jacobian_samples)


class JointSamples(eqx.Module):
    """The joint along a saved trajectory: FE load [N] (pin on bushing, bushing
    frame), sliding speed R_b |omega_rel| [m/s], EFM total normal load [N]."""

    force: Float[Array, "T 2"]
    sliding_rate: Float[Array, " T"]
    efm_normal_load: Float[Array, " T"]


def joint_samples(mech: Mechanism, joint: str, ys: Float[Array, "T s"], force: str = "resultant"
                  ) -> JointSamples:
    """Evaluate the clearance joint ``joint`` at every saved state ``ys``."""
    index, el = clearance_element(mech, joint)
    sl = mech.aux_slice(joint)
    u = el.profile.normals

    def one(y):
        q, qd, aux = mech.split(y)
        kin, res = el.contact(mech.frames(q, qd), aux[sl])
        if force == "resultant":
            f = -res.force  # ContactResult.force acts on the pin; the ring gets -F
        else:  # the springs' loads along u_k: the normal part of the pin's push
            load = res.pressure * kin.bushing_radius * el.law.depth * el.profile.dtheta
            f = load @ u
        return f, el.sliding_rate(kin), res.normal_load

    return JointSamples(*jax.vmap(one)(ys))


def unworn_tributary(model: FemWearModel, bushing_radius, n_theta: int) -> Float[Array, " n"]:
    """w0_j [m]: tributary lengths of the unworn ring (the wear pressure's arc)."""
    return tributary_lengths(ring_mesh(bushing_radius, model.outer_radius, n_theta,
                                       model.n_layers))


def ring_compliance(model: FemWearModel, bushing_radius, depth) -> Float[Array, "n n"]:
    """C of the ring worn by ``depth`` [m] (mesh + condensation)."""
    mesh = ring_mesh(bushing_radius, model.outer_radius, depth.shape[0], model.n_layers, depth)
    return inner_compliance(mesh, model.youngs_modulus, model.poisson_ratio)


def ring_contact(compliance, tributary, bushing_radius, pin_radius, depth, length) -> RingContact:
    """The pin contact with compliance ``compliance`` (possibly of an older
    profile) and the inner surface at a + ``depth`` (the current profile)."""
    n = depth.shape[0]
    return RingContact(compliance=compliance, tributary=tributary,
                       boundary_radius=bushing_radius + depth,
                       theta=grid_angles(n),
                       pin_radius=jnp.asarray(pin_radius, dtype=float),
                       length=jnp.asarray(length, dtype=float))


class FemIncrement(eqx.Module):
    """One cycle's FE wear: depth increment [m], k-free load x sliding [N m],
    pressures [Pa] and FE total normal loads [N] at the samples (zero where
    unloaded), whether every FE solve converged, the pin offsets [m] at the
    samples (where unloaded: the last loaded sample's)."""

    depth_increment: Float[Array, " n"]
    load_sliding: Float[Array, ""]
    pressure: Float[Array, "T n"]
    normal_load: Float[Array, " T"]
    ok: Array
    offset: Float[Array, "T 2"] | None = None


def trapezoid_weights(ts: Float[Array, " T"]) -> Float[Array, " T"]:
    """w_i with sum_i w_i g(t_i) the trapezoid rule on the (ordered) times ``ts``."""
    dt = jnp.diff(ts)
    return 0.5 * (jnp.concatenate([dt, jnp.zeros(1)]) + jnp.concatenate([jnp.zeros(1), dt]))


def contact_window(n: int) -> int:
    """Nodes of the FE solves' first try (`RingContact.solve_force`'s ``window``):
    the half ring centred on the joint force, where a pin pressed along F
    touches (the rig's contact: 30-37 of 180 nodes unworn, 15-20 worn); checked
    on the whole ring, else solved there."""
    return n // 2


def fem_increment(contact: RingContact, samples: JointSamples, ts, k,
                  starts: tuple | None = None) -> FemIncrement:
    """dh_k = k sum_i w_i p_k(t_i) s_i and sum_i w_i N_i s_i (s = R_b |omega|, N
    the FE total normal load L sum_j f_j) for the loads ``samples`` at ``ts``.

    The samples are solved in order, each from the last loaded one's solution
    (consecutive loads differ little: fewer Newton steps than from the pin
    touching the wall along F; the docs' FEM page); ``starts``: (pin offsets
    [m], pressures [Pa]) of a solution at these loads (`FemIncrement.offset`,
    ``.pressure``), each sample's start instead (no Newton step where they
    solve it)."""
    f = samples.force
    n = contact.theta.shape[0]
    mag = safe_norm(f)
    loaded = mag > MIN_JOINT_FORCE
    f_safe = jnp.where(loaded[:, None], f, jnp.array([1.0, 0.0]))  # any valid load; result dropped
    window = contact_window(n)

    def solve(x, guess):
        """(nodal forces, residual, offset) of sample load ``x`` from ``guess``."""
        # traced: no raise; unpolished: the loop's solution (within TOL) and its derivative
        s = contact.solve_force(x, tol=TOL, guess=guess, window=window, polish=False)

        def retry(_):
            # Semismooth Newton from the default start (pin touching the least worn
            # point along F) can stall on a deep pocket (the docs' FEM page);
            # start at the worn wall along F.
            return out(contact.solve_force(x, tol=TOL, offset_guess=contact.wall_offset(x)))

        return lax.cond(s.info.residual <= ACCEPT_RESIDUAL, lambda _: out(s), retry, None)

    def out(s):  # only what the increment reads (the rest of a solution is never formed)
        return s.nodal_force, s.info.residual, s.offset

    def unloaded(guess):
        return jnp.zeros(n), jnp.zeros(()), guess[0]

    if starts is None:
        def step(prev, xs):
            x, on = xs

            def go(prev):
                r = solve(x, prev)
                return (r[2], r[0]), r

            return lax.cond(on, go, lambda prev: (prev, unloaded(prev)), prev)

        # the first sample starts as `solve_force` does: touching the wall along F
        first = f_safe[0] / safe_norm(f_safe[0]) * (jnp.min(contact.boundary_radius)
                                                    - contact.pin_radius)
        _, (nodal, res, offset) = lax.scan(step, (first, jnp.zeros(n)), (f_safe, loaded))
    else:
        e_start, p_start = jax.lax.stop_gradient(starts)

        def one(xs):
            x, on, e0, f0 = xs
            return lax.cond(on, lambda g: solve(x, g), unloaded, (e0, f0))

        nodal, res, offset = lax.map(
            one, (f_safe, loaded, e_start, p_start * jax.lax.stop_gradient(contact.tributary)))
    p = nodal / contact.tributary
    load = contact.length * jnp.sum(nodal, axis=1)
    conv = res <= ACCEPT_RESIDUAL
    p = jnp.where(loaded[:, None], p, 0.0)
    load = jnp.where(loaded, load, 0.0)
    w = trapezoid_weights(ts) * samples.sliding_rate
    dh = jnp.asarray(k, dtype=float) * (w @ p)
    ok = jnp.all(conv | ~loaded) & jnp.all(jnp.isfinite(dh))
    return FemIncrement(depth_increment=dh, load_sliding=w @ load, pressure=p,
                        normal_load=load, ok=ok, offset=offset)


def jacobian_sample_indices(n_t: int, jacobian_samples: int) -> np.ndarray:
    """The samples (of ``n_t``) that form the implicit step's J: ``jacobian_samples``
    intervals, evenly spread (all of them when it is ``n_t - 1``)."""
    return np.unique(np.round(np.linspace(0, n_t - 1, jacobian_samples + 1)).astype(int))


def depth_jacobian(contact: RingContact, samples: JointSamples, ts, inc: FemIncrement, k,
                   jacobian_samples: int) -> tuple[Float[Array, "n n"], Float[Array, " n"]]:
    """(J, d ls / d depth): the derivatives of the increment ``inc`` (its depth
    increment and k-free load x sliding) w.r.t. the depth, compliance and
    loads held, from ``jacobian_samples`` + 1 of the samples (trapezoid over
    the cycle; all of them: the increment's own quadrature).  Each sample's
    nodal forces are differentiated at its solution in ``inc`` by the implicit
    function theorem (`RingContact.force_depth_derivative`), on the nodes of
    its first-try window (`contact_window`) where all its loaded nodes lie
    there, else on the whole ring."""
    n = inc.depth_increment.shape[0]
    idx = jacobian_sample_indices(ts.shape[0], jacobian_samples)
    force = samples.force[idx]
    loaded = safe_norm(force) > MIN_JOINT_FORCE
    force = jnp.where(loaded[:, None], force, jnp.array([1.0, 0.0]))
    weights = trapezoid_weights(ts[idx]) * samples.sliding_rate[idx]
    window = contact_window(n)
    frozen = jax.lax.stop_gradient(contact)
    trib = frozen.tributary
    assert inc.offset is not None  # `fem_increment` returns the samples' offsets
    offsets, nodal = jax.lax.stop_gradient((inc.offset[idx], inc.pressure[idx] * trib))

    def one(acc, xs):
        x, on, weight, e, f = xs

        def add(nodes, acc):
            jac, d_ls = acc
            d = frozen.force_depth_derivative(x, e, f, nodes)  # (m, m)
            return (jac.at[nodes[:, None], nodes[None, :]].add(weight * d / trib[nodes, None]),
                    d_ls.at[nodes].add(weight * frozen.length * jnp.sum(d, axis=0)))

        nodes = frozen.window_nodes(x, window)
        # no load outside the window (a node below CONTACT_FRACTION of the peak is open)
        inside = jnp.max(jnp.abs(f.at[nodes].set(0.0))) <= CONTACT_FRACTION * jnp.max(f)
        acc = lax.cond(on & inside, lambda acc: add(nodes, acc), lambda acc: acc, acc)
        acc = lax.cond(on & ~inside, lambda acc: add(jnp.arange(n), acc), lambda acc: acc, acc)
        return acc, None

    (jac, d_ls), _ = lax.scan(one, (jnp.zeros((n, n)), jnp.zeros(n)),
                              (force, loaded, weights, offsets, nodal))
    return jnp.asarray(k, dtype=float) * jac, d_ls


def implicit_step(contact: RingContact, samples: JointSamples, ts, inc: FemIncrement, k, a,
                  jacobian_samples: int) -> tuple[Float[Array, " n"], Float[Array, ""], Array]:
    """(Delta h, load x sliding of the step, explicit fallback used): Delta h solves
    (I - a J) Delta h = a dh (dh = ``inc.depth_increment``), J = d(dh)/d(depth)
    from ``jacobian_samples`` + 1 of the samples (`depth_jacobian`), compliance
    held; floored at 0.  The load x sliding is linearised the same way,
    a (ls + (d ls / d depth) . Delta h), so that k x it stays the step's
    volume (the Archard bookkeeping of an implicit step: the loads at the end of
    the step).  See the module docstring."""
    n = inc.depth_increment.shape[0]
    jac, d_ls = depth_jacobian(contact, samples, ts, inc, k, jacobian_samples)
    step = jnp.linalg.solve(jnp.eye(n) - a * jac, a * inc.depth_increment)
    step = jnp.maximum(step, 0.0)
    ls = a * (inc.load_sliding + d_ls @ step)
    # A non-finite J (a degenerate contact node at a J sample: the implicit
    # derivative does not exist there; seen on the rig with M = 5) falls back to
    # the explicit step for this cycle, counted in the evolution state.
    good = jnp.all(jnp.isfinite(step)) & jnp.isfinite(ls)
    return (jnp.where(good, step, a * inc.depth_increment),
            jnp.where(good, ls, a * inc.load_sliding), ~good)


def sampling_solver(solver):
    """The cycle integrator ``solver`` as the FEM route runs it: the cycle steps
    onto the sample times (`wear_cycle`'s ``step_to_saves``), so the samples
    are ends of steps and a Rosenbrock solver's dense output (one more
    evaluation of the right-hand side per step) is never read: dropped."""
    def configure(s):
        if isinstance(s, AbstractRosenbrock) and s.dense_output:
            return dataclasses.replace(s, dense_output=False)
        return s

    return None if solver is None else replace_inner(solver, configure)


class FemWear(DynamicWear):
    """The FEM route's wear term: the dynamic cycle (EFM dynamics) sampled at
    ``n_samples + 1`` times, its wear from the FE ring's contact pressure
    (`fem_increment`), and the profile step of `implicit_step` (`advance`).
    Its memory adds the compliance ``fem_C``, the wear cycles since it was
    built, ``fem_age``, and the cycles that fell back to the explicit step,
    ``fem_explicit``."""

    fem: FemWearModel | None = None
    tributary: Float[Array, " n"] | None = None

    def element(self):
        return clearance_element(self.mech, self.joints[0])[1]

    def compliance(self, h):
        return ring_compliance(self.fem, self.element().bushing_radius, h)

    def warm_up(self, y0, cycles: int):
        """EFM warm-up cycles (`DynamicWear.warm_up`), then the unworn ring's
        compliance."""
        memory, ok = super().warm_up(y0, cycles)
        h0 = self.zeros()[0]
        return dict(memory, fem_C=self.compliance(h0), fem_age=jnp.zeros(()),
                    fem_explicit=jnp.zeros(())), ok

    def cycle(self, h, memory) -> CycleWear:
        fem, el = self.fem, self.element()
        assert fem is not None and self.tributary is not None
        (depth,) = h
        stale = memory["fem_age"] >= fem.refresh_interval
        # a lambda, not the bound method: lax.cond hashes its branches, and a
        # Module with concrete array leaves is not hashable
        cmat = lax.cond(stale, lambda h: self.compliance(h), lambda h: memory["fem_C"], depth)
        age = jnp.where(stale, 0.0, memory["fem_age"]) + 1.0
        r, after, worn = self.run(h, memory, fem.n_samples + 1, step_to_saves=True)
        assert r.ys is not None and r.ts is not None  # saved: n_save is given
        samples = joint_samples(worn, self.joints[0], r.ys, fem.force)
        contact = ring_contact(cmat, self.tributary, el.bushing_radius, el.pin_radius, depth,
                               wear_parts(el)[0].depth)
        inc = fem_increment(contact, samples, r.ts, self.bushing()[2])
        return CycleWear(
            rate=(inc.depth_increment,), ok=r.ok & inc.ok,
            memory=dict(after, fem_C=cmat, fem_age=age),
            load_sliding=inc.load_sliding[None], extra=(contact, samples, r.ts, inc))

    def advance(self, h, cw: CycleWear, dn):
        """The FE increment's linearly implicit profile step for A = ``dn``
        (`implicit_step`)."""
        assert self.fem is not None
        contact, samples, ts, inc = cw.extra
        step, ls, fallback = implicit_step(contact, samples, ts, inc, self.bushing()[2], dn,
                                           self.fem.jacobian_samples)
        memory = dict(cw.memory, fem_explicit=cw.memory["fem_explicit"] + fallback)
        return (h[0] + step,), ls[None], memory, cw.ok & jnp.all(jnp.isfinite(step))


class FemEvolver(Evolver):
    """`Evolver` (`Constant(A)` only) whose wear term is the FE ring's
    (`FemWear`)."""

    def __init__(self, mech: Mechanism, joint: str, cycles, *, fem: FemWearModel,
                 method: AbstractExtrapolation = Constant(), **kw):
        if not isinstance(method, Constant):
            raise InputError(f"the FEM wear route extrapolates with Constant(A) only (as the "
                             f"thesis's FEM runs), got {method!r}")
        if not isinstance(fem, FemWearModel):
            raise InputError(f"fem must be a FemWearModel, got {type(fem).__name__}")
        _, el = clearance_element(mech, joint)
        rb, b = concrete(el.bushing_radius), concrete(fem.outer_radius)
        if rb is not None and b is not None and not b > rb:
            raise InputError(f"FEM route: bushing outer radius {float(b)!r} m must exceed the "
                             f"bore radius {float(rb)!r} m")
        self.fem = fem
        self.tributary = unworn_tributary(fem, el.bushing_radius, el.profile.n)
        super().__init__(mech, joint, cycles, method=method, **kw)

    def make_term(self, mech, joint, period, settings) -> FemWear:
        settings = dataclasses.replace(settings, solver=sampling_solver(settings.solver))
        return FemWear(mech, (joint,), period, settings, fem=self.fem, tributary=self.tributary)


def evolve_fem(mech: Mechanism, joint: str, y0, cycles, *, period, fem: FemWearModel,
               extrapolation=1.0, **kw) -> WearSolution:
    """`evolve` with constant A = ``extrapolation`` and the FE wear pressure;
    ``kw`` as `evolve` (wall_thickness, warmup_cycles, cycle, ...)."""
    require_float64("evolve_fem")
    ev = FemEvolver(mech, joint, cycles, fem=fem, period=period,
                    method=Constant(float(extrapolation)), **kw)
    return ev.solve(y0)


def default_model(design, *, refresh_interval=DEFAULT_REFRESH, n_samples=DEFAULT_SAMPLES,
                  n_layers=DEFAULT_LAYERS, force="resultant",
                  jacobian_samples=DEFAULT_JACOBIAN_SAMPLES) -> FemWearModel:
    """The FEM route for a `presets.WearJointDesign`: PTFE ring (Table 3-2:
    E 0.5 GPa, nu 0.38, the EFM's material), outer radius bore + wall."""
    from ..contact import PTFE

    return FemWearModel(PTFE.youngs_modulus, PTFE.poisson_ratio,
                        design.bushing_radius + design.wall, refresh_interval=refresh_interval,
                        n_samples=n_samples, n_layers=n_layers, force=force,
                        jacobian_samples=jacobian_samples)


__all__ = ["FORCE_MODES", "MIN_JOINT_FORCE", "FemWearModel", "JointSamples", "joint_samples",
           "FemIncrement", "fem_increment", "depth_jacobian", "implicit_step", "FemEvolver",
           "FemWear", "evolve_fem", "default_model", "ring_compliance", "ring_contact",
           "unworn_tributary", "trapezoid_weights", "sampling_solver", "contact_window"]
