"""Joint loads over one crank cycle of the mechanism with its clearance joints ideal.

The quasi-static joint model needs, for every wearing joint, the force the pin
exerts on the bushing and the relative rotation over one cycle.  At the
thesis's operating points the pin's contact resonance (kHz) is three orders
above the crank frequency, so these are the loads of the *ideal* mechanism:
the clearance joints replaced by revolute joints at the same points
(`ideal_parent`).  The ideal mechanism is solved once per cycle:

* fully driven (as many independent constraint rows as coordinates, e.g. any
  slider-crank with a driven crank): a kinematic analysis at each sample time
  (Newton on Phi = 0, then velocities and accelerations), exact and cheap;
* otherwise: the Baumgarte DAE integrated with diffrax over ``warmup_cycles``
  settling cycles and the sampled cycle.

The multipliers then give the joint reaction (thesis Eq. 5-2).  Samples are
equally spaced over the period, t_s = t0 + s T / S, s = 0..S-1: the rectangle
rule on them is the trapezoid rule of a periodic integrand (spectrally
accurate for smooth loads).
"""

from __future__ import annotations

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

from ..contact.clearance_joint import ClearanceJoint
from ..dynamics import simulate
from ..dynamics.equations import Baumgarte, accelerations
from ..dynamics.kinematics import assemble, kinematic_accelerations, velocities
from ..dynamics.reactions import reaction_wrench
from ..errors import InputError
from ..mechanism import GROUND, Mechanism
from ..mechanism.geometry import rotation


class JointLoads(eqx.Module):
    """One joint's loads at S equally spaced samples of one cycle.

    force: force the pin exerts on the bushing, in the bushing frame [N] (S, 2)
    omega: relative angular velocity phi_dot_pin - phi_dot_bushing [rad/s] (S,)
    period: cycle period [s]
    """

    force: Float[Array, "S 2"]
    omega: Float[Array, " S"]
    period: Float[Array, ""]

    @property
    def samples(self) -> int:
        return self.omega.shape[0]

    @property
    def dt(self) -> Float[Array, ""]:
        """Quadrature weight of one sample [s]."""
        return self.period / self.samples


def clearance_joints(mech: Mechanism, joints=None) -> tuple[ClearanceJoint, ...]:
    """The clearance joints of ``mech`` named in ``joints`` (default: every one)."""
    found = {f.name: f for f in mech.forces if isinstance(f, ClearanceJoint)}
    if joints is None:
        return tuple(found.values())
    missing = [j for j in joints if j not in found]
    if missing:
        raise InputError(f"no clearance joint named {missing[0]!r}; the mechanism has "
                         f"{sorted(found) or 'none'}")
    return tuple(found[j] for j in joints)


def ideal_parent(mech: Mechanism) -> Mechanism:
    """``mech`` with every `ClearanceJoint` replaced by the ideal revolute joint
    at the same points.  The coordinates are the same, so a state of ``mech``
    with its pins centred is a state of the parent."""
    joints = clearance_joints(mech)
    forces = tuple(f for f in mech.forces if not isinstance(f, ClearanceJoint))
    return Mechanism(mech.bodies, (*mech.constraints, *(j.ideal() for j in joints)), forces)


def fully_driven(mech: Mechanism) -> bool:
    """True when the constraints fix every coordinate (a kinematic analysis
    gives the motion; assumes independent rows, which `consistent_state` checks)."""
    return mech.n_constraints == mech.n_coords


def _joint_sample(ideal: Mechanism, joint: ClearanceJoint, q, qd, lam, t):
    frames = ideal.frames(q, qd)
    if joint.bushing_body != GROUND:
        on_bushing = reaction_wrench(ideal, q, lam, t, joint.name, joint.bushing_body)[:2]
    else:
        on_bushing = -reaction_wrench(ideal, q, lam, t, joint.name, joint.pin_body)[:2]
    phi_b = frames.pose(joint.bushing_body)[2]
    omega = frames.velocity(joint.pin_body)[2] - frames.velocity(joint.bushing_body)[2]
    return rotation(phi_b).T @ on_bushing, omega


class CycleLoads(eqx.Module):
    """`cycle_loads`' result: one `JointLoads` per joint, and ``ok`` (False when
    the ideal mechanism's solve failed: the loads are then not usable)."""

    joints: tuple
    ok: Bool[Array, ""]


def cycle_loads(
    mech: Mechanism,
    joints: tuple[str, ...],
    y0: Float[Array, " s"],
    period,
    *,
    samples: int = 360,
    t0=0.0,
    warmup_cycles: int = 0,
    rtol: float = 1e-8,
    atol: float = 1e-8,
    max_steps: int = 1_000_000,
) -> CycleLoads:
    """Loads of ``joints`` (clearance joints of ``mech``) over the cycle
    [t0 + warmup_cycles T, t0 + (warmup_cycles + 1) T] of the ideal parent,
    started from the positions and velocities of ``y0`` (a state of ``mech``).

    ``rtol``/``atol``: integration tolerances (mechanisms that are not fully
    driven) or the position-solve tolerance (fully driven).  Pure and jit-able.
    """
    elements = clearance_joints(mech, joints)
    ideal = ideal_parent(mech)
    period = jnp.asarray(period, dtype=float)
    t_start = jnp.asarray(t0, dtype=float) + warmup_cycles * period
    ts = t_start + period * jnp.arange(samples) / samples
    q0, qd0, _ = mech.split(y0)
    if fully_driven(ideal):
        def one(q_prev, t):
            q, ok = assemble(ideal, q_prev, t, tol=min(rtol, 1e-10))
            qd = velocities(ideal, q, t)
            return q, (q, qd, kinematic_accelerations(ideal, q, qd, t), ok)

        _, (qs, qds, _, oks) = jax.lax.scan(one, q0, ts)
        ok = jnp.all(oks)
    else:
        y_ideal = ideal.join(q0, qd0, ideal.initial_aux(q0, qd0))
        traj = simulate(ideal, y_ideal, ts[-1] + period / samples, t0=t0, ts=ts,
                        max_steps=max_steps,
                        stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol,
                                                                  pcoeff=0.3, icoeff=0.4))
        qs = traj.ys[:, : ideal.n_coords]
        qds = traj.ys[:, ideal.n_coords : 2 * ideal.n_coords]
        ok = traj.succeeded & jnp.all(jnp.isfinite(traj.ys))

    def sample(q, qd, t):
        aux = ideal.initial_aux(q, qd)
        _, lam, _ = accelerations(ideal, q, qd, aux, t, Baumgarte())
        return tuple(_joint_sample(ideal, j, q, qd, lam, t) for j in elements)

    per_joint = jax.vmap(sample)(qs, qds, ts)
    loads = tuple(JointLoads(force=f, omega=w, period=period) for f, w in per_joint)
    ok = ok & jnp.all(jnp.stack([jnp.all(jnp.isfinite(lo.force)) for lo in loads]))
    return CycleLoads(joints=loads, ok=ok)
