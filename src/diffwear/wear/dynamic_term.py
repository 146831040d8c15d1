"""The dynamic model's wear term: each evaluation integrates one crank cycle
of the mechanism with its clearance joints (`wear_cycle_joints`).

`CycleSettings` holds how a dynamic cycle is integrated (tolerances,
integrator, adjoint, step budget), written once for every route.
`DynamicWear` is the engine's term (`diffwear.wear._engine`): the bushing
profiles enter the joints' clearance c0 + h, the mechanism state and time
carry from the end of one cycle into the next (no restart transient), and
the response A of the linearly implicit step is `wear_operator`.
"""

from __future__ import annotations

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, Float

from ..contact import contact_history
from ..mechanism import Mechanism
from ._engine import AbstractWearTerm, CycleWear
from .cycle import CYCLE_ATOL, CYCLE_RTOL, clearance_element, wear_cycle_joints, wear_parts
from .modifier import AbstractWearModifier, JointGeometry, modulated

# Ridge added to M = U^T D U (units: grid nodes in contact) in `wear_operator`.
# Without it M^-1 is singular in free flight and its derivative (through the
# contact indicator D) swamps the gradient; 0.01 of a node changes the
# projection by < 0.1 % for a contact arc of >= 10 nodes.
OPERATOR_RIDGE = 1e-2


class CycleSettings(eqx.Module):
    """How each dynamic cycle is integrated: ``rtol``/``atol`` on the whole
    state (SI units), the integrator ``solver`` (default Tsit5;
    `diffwear.wear.cycle.CYCLE_INTEGRATORS`), the ``adjoint`` (default
    diffrax's checkpointed reverse mode; ``diffrax.ForwardMode()`` for
    ``jax.jacfwd``) and ``max_steps``."""

    rtol: float = eqx.field(static=True, default=CYCLE_RTOL)
    atol: float = eqx.field(static=True, default=CYCLE_ATOL)
    solver: diffrax.AbstractSolver | None = None
    adjoint: diffrax.AbstractAdjoint | None = eqx.field(static=True, default=None)
    max_steps: int = eqx.field(static=True, default=200_000)

    def options(self) -> dict:
        """The keywords of `wear_cycle` / `wear_cycle_joints`."""
        return dict(rtol=self.rtol, atol=self.atol, solver=self.solver, adjoint=self.adjoint,
                    max_steps=self.max_steps)


def with_profiles(mech: Mechanism, joints: tuple[str, ...], depths) -> Mechanism:
    """``mech`` with the bushings of ``joints`` worn by ``depths`` [m] (one
    profile per joint, on its grid)."""
    for joint, h in zip(joints, depths):
        index, el = clearance_element(mech, joint)
        mech = eqx.tree_at(lambda m: m.forces[index].profile.clearance, mech,
                           el.profile.clearance + h)
    return mech


def wear_operator(mech: Mechanism, joint: str, ys: Float[Array, "T s"], period,
                  width=1e-6) -> Float[Array, "n n"]:
    """The cycle-integrated linear response A of the wear increment to the
    profile, d(dh)/dh ~ -A, of an elastic-foundation joint.

    At every saved state (``ys``, equally spaced over one cycle, both ends
    included) the nodes in contact, D = diag(step(delta_k, width)), respond to a
    deeper profile with a pressure drop k_f (I - U M^-1 U^T D) dh, where the
    pin translation U M^-1 U^T D dh (M = U^T D U, U = [cos, sin]) keeps the
    contact resultant, i.e. the joint force, unchanged.  Weighted by the
    sliding increment ds and by k, and summed over the cycle (trapezoid rule).
    A lubricated joint's wearing contact is its asperities' (Greenwood-Tripp
    in series with the foundation): their contact band is taken as the nodes
    past the mean surfaces, and their stiffness as the foundation's (the
    series pair is softer: the response is an upper bound there, which only
    makes the implicit wear step more cautious).
    """
    from ..contact import smoothing

    _, el = clearance_element(mech, joint)
    profile = el.profile
    theta = el.profile.theta
    u = jnp.stack([jnp.cos(theta), jnp.sin(theta)], axis=-1)  # (n, 2)
    n = theta.shape[0]

    def sample(y):
        q, qd, _ = mech.split(y)
        kin = el.kinematics(mech.frames(q, qd))
        d = smoothing.step(u @ kin.offset - profile.clearance, width)
        m = u.T @ (d[:, None] * u) + OPERATOR_RIDGE * jnp.eye(2)
        follow = u @ jnp.linalg.solve(m, u.T * d[None, :])  # (n, n) pin translation
        response = d[:, None] * (jnp.eye(n) - follow)
        return response, el.sliding_rate(kin)

    responses, rates = jax.vmap(sample)(ys)
    w = period * jnp.ones(ys.shape[0]).at[0].set(0.5).at[-1].set(0.5) / (ys.shape[0] - 1)
    law, wear = wear_parts(el)
    return wear.coefficient * law.stiffness * jnp.einsum("t,tij->ij", w * rates, responses)


class DynamicWear(AbstractWearTerm):
    """The wear of ``joints`` over one dynamic cycle of ``mech`` (period
    ``period`` [s]) at their current profiles; memory: the mechanism state
    ``y`` and the time ``t``.

    ``saves``: states saved per cycle (``extra``: the cycle's `JointsCycleResult`
    with ``ts``/``ys``); ``response``: with `wear_operator` from ``saves``
    states (contact band ``operator_width`` [m]); ``fresh_state``: each cycle
    starts from its inherited state without its derivative
    (`lax.stop_gradient`: the life's derivative, `diffwear.wear.life`);
    ``force_trace``: the memory keeps the first joint's |joint force| at the
    ``saves`` states of each cycle (``memory["force"]``); ``modifier``: a
    `diffwear.wear.modifier.AbstractWearModifier` of one joint's wear
    (its growth on the profile each cycle sees, its rate factor over each
    step), reading ``geometry``."""

    mech: Mechanism
    joints: tuple[str, ...] = eqx.field(static=True)
    period: Float[Array, ""]
    settings: CycleSettings = CycleSettings()
    saves: int | None = eqx.field(static=True, default=None)
    response: bool = eqx.field(static=True, default=False)
    operator_width: float = 1e-6
    fresh_state: bool = eqx.field(static=True, default=False)
    force_trace: bool = eqx.field(static=True, default=False)
    modifier: AbstractWearModifier | None = None
    geometry: JointGeometry | None = None

    def zeros(self) -> tuple:
        """Unworn profiles, one per joint."""
        return tuple(jnp.zeros_like(clearance_element(self.mech, j)[1].profile.clearance)
                     for j in self.joints)

    def worn(self, h) -> Mechanism:
        return with_profiles(self.mech, self.joints, h)

    def run(self, h, memory, saves: int | None, step_to_saves: bool = False):
        """One dynamic cycle at profiles ``h`` from ``memory`` (``saves``
        states saved; ``step_to_saves``: as `wear_cycle`, the saved states
        are ends of steps): (`JointsCycleResult`, the memory after it, the
        worn mechanism)."""
        y = lax.stop_gradient(memory["y"]) if self.fresh_state else memory["y"]
        worn = self.worn(h)
        r = wear_cycle_joints(worn, self.joints, y, memory["t"], self.period, n_save=saves,
                              step_to_saves=step_to_saves, **self.settings.options())
        return r, dict(memory, y=r.y_end, t=memory["t"] + self.period), worn

    def cycle(self, h, memory) -> CycleWear:
        if self.modifier is not None:
            h = tuple(self.modifier.growth() * x for x in h)
        r, memory, worn = self.run(h, memory, self.saves)
        response = None
        if self.response:
            response = tuple(wear_operator(worn, j, r.ys, self.period, self.operator_width)
                             for j in self.joints)
        if self.force_trace:
            assert r.ys is not None  # saved: ``saves`` states
            memory = dict(memory, force=contact_history(worn, self.joints[0], r.ys)
                          .force_magnitude)
        return CycleWear(rate=tuple(r.depth_increment), ok=r.ok, memory=memory,
                         load_sliding=jnp.stack(r.load_sliding), response=response, extra=r)

    def modulate(self, cw: CycleWear, h, n, dn) -> CycleWear:
        """The rate over [n, n + dn]: the modifier's factor (none: unchanged)."""
        if self.modifier is None:
            return cw
        assert self.geometry is not None, "a modifier reads the joint's geometry"
        return modulated(cw, h, n, dn, self.modifier, self.geometry)

    def warm_up(self, y0, cycles: int):
        """``cycles`` dynamic cycles of the unworn joints from ``y0`` at t = 0,
        their wear discarded (the pin's start-up transient): (memory, ok)."""
        memory, ok = dict(y=y0, t=jnp.zeros(())), jnp.array(True)
        h0 = self.zeros()
        for _ in range(int(cycles)):
            r, memory, _ = self.run(h0, memory, None)
            ok = ok & r.ok
        if self.force_trace:
            assert self.saves is not None, "a force trace needs saves="
            memory = dict(memory, force=jnp.zeros(self.saves))
        return memory, ok

    def bushing(self, index: int = 0):
        """(bushing radius [m], bushing depth [m], wear coefficient) of a joint."""
        el = clearance_element(self.mech, self.joints[index])[1]
        law, wear = wear_parts(el)
        return el.bushing_radius, law.depth, wear.coefficient


__all__ = ["CycleSettings", "DynamicWear", "wear_operator", "with_profiles", "OPERATOR_RIDGE"]
