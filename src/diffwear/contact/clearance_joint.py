"""`ClearanceJoint`: an imperfect revolute joint as a force element (thesis Ch. 3).

The pin (on body i) moves freely inside the bushing (on body j): the joint
adds two degrees of freedom and no constraint rows.  A contact law gives the
force; it acts at the pin centre with the friction moment, on the pin, and with
opposite sign on the bushing (action and reaction at one point, so linear and
angular momentum are conserved).

Auxiliary states, in this order: the contact law's memory; with wear enabled,
the bushing wear depth h(theta_k) [m] on the profile grid and the Archard
bookkeeping integral of (normal load x sliding distance) [N m].
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_positive, concrete
from ..errors import InputError
from ..mechanism import AbstractForceElement, Frames, Mechanism, RevoluteJoint
from ..mechanism.constraints import _vec2
from ..mechanism.geometry import dot2, perp, safe_angle, safe_norm
from . import smoothing
from .archard import SLIP_RATE_WIDTH, ArchardWear
from .friction import CoulombFriction
from .kinematics import ContactResult, PinKinematics
from .laws import AbstractContactLaw
from .linearised import LinearisedLaw
from .profile import BushingProfile


class ClearanceJoint(AbstractForceElement):
    """Pin of radius ``pin_radius`` on ``pin_body`` (at ``pin_point``) inside the
    bushing profile ``profile`` on ``bushing_body`` (centre at ``bushing_point``).

    ``bushing_radius`` is the unworn bore radius: pin_radius + initial clearance.
    """

    name: str = eqx.field(static=True)
    pin_body: str = eqx.field(static=True)
    bushing_body: str = eqx.field(static=True)
    pin_point: Float[Array, "2"]
    bushing_point: Float[Array, "2"]
    pin_radius: Float[Array, ""]
    bushing_radius: Float[Array, ""]
    profile: BushingProfile
    law: AbstractContactLaw
    friction: CoulombFriction
    wear: ArchardWear | None

    def __init__(self, name, pin_body, pin_point, bushing_body, bushing_point, pin_radius,
                 bushing_radius, law, friction=None, profile=None, wear=None, n_theta=360):
        self.name, self.pin_body, self.bushing_body = name, pin_body, bushing_body
        self.pin_point = _vec2(f"clearance joint {name!r}: pin_point", pin_point)
        self.bushing_point = _vec2(f"clearance joint {name!r}: bushing_point", bushing_point)
        check_positive(f"clearance joint {name!r}: pin radius [m]", pin_radius)
        check_positive(f"clearance joint {name!r}: bushing radius [m]", bushing_radius)
        rp, rb = concrete(pin_radius), concrete(bushing_radius)
        if rp is not None and rb is not None and rp > rb:
            raise InputError(
                f"clearance joint {name!r}: pin radius {float(rp)} m is larger than the bushing "
                f"radius {float(rb)} m (clearance must be >= 0)"
            )
        if not isinstance(law, AbstractContactLaw):
            raise InputError(f"clearance joint {name!r}: law must be a contact law, got {law!r}")
        if wear is not None and law.solid_contact is None:
            raise InputError(
                f"clearance joint {name!r}: wear needs a pressure distribution: use the "
                "ElasticFoundation contact law (or MixedLubrication, whose asperities "
                "carry one)"
            )
        self.pin_radius = jnp.asarray(pin_radius, dtype=float)
        self.bushing_radius = jnp.asarray(bushing_radius, dtype=float)
        if profile is None:
            profile = BushingProfile.circular(self.bushing_radius - self.pin_radius, n_theta)
        self.profile = profile
        self.law = law
        self.friction = CoulombFriction() if friction is None else friction
        self.wear = wear

    @property
    def bodies(self):
        return (self.pin_body, self.bushing_body)

    @property
    def n_aux(self) -> int:
        return self.law.n_memory + (self.profile.n + 1 if self.wear is not None else 0)

    @property
    def feedback_aux(self) -> tuple[int, ...]:
        # the law's memory feeds back; the wear depth and load x sliding
        # accumulators are integrals of the contact (the profile is fixed within
        # a simulation)
        return tuple(range(self.law.n_memory))

    def for_state_jacobian(self) -> "ClearanceJoint":
        if isinstance(self.law, LinearisedLaw):
            return self
        return eqx.tree_at(lambda j: j.law, self, LinearisedLaw(self.law))

    def initial_aux(self, frames):
        parts = [self.law.initial_memory()]
        if self.wear is not None:
            parts.append(jnp.zeros(self.profile.n + 1))
        return jnp.concatenate(parts)

    def ideal(self) -> RevoluteJoint:
        """The ideal revolute joint at the same points (pin centred, no clearance)."""
        return RevoluteJoint(self.name, self.pin_body, self.bushing_body, self.pin_point,
                             self.bushing_point)

    # ----------------------------------------------------------------- physics
    def kinematics(self, frames: Frames) -> PinKinematics:
        """Pin offset and its rate in the bushing frame."""
        vj = frames.velocity(self.bushing_body)
        e = frames.point(self.pin_body, self.pin_point) - frames.point(self.bushing_body,
                                                                        self.bushing_point)
        e_dot = (frames.point_velocity(self.pin_body, self.pin_point)
                 - frames.point_velocity(self.bushing_body, self.bushing_point))
        omega = frames.velocity(self.pin_body)[2] - vj[2]
        return PinKinematics(
            offset=frames.to_body(self.bushing_body, e),
            offset_rate=frames.to_body(self.bushing_body, e_dot - vj[2] * perp(e)),
            omega=omega,
            pin_radius=self.pin_radius,
            bushing_radius=self.bushing_radius,
        )

    def contact(self, frames: Frames, aux) -> tuple[PinKinematics, ContactResult]:
        kin = self.kinematics(frames)
        memory = aux[: self.law.n_memory]
        return kin, self.law.evaluate(kin, memory, self.profile, self.friction)

    def sliding_rate(self, kin: PinKinematics) -> Float[Array, ""]:
        """ds/dt = R_b |omega_rel| [m/s] (thesis Eq. 5-3), |.| smoothed."""
        return kin.bushing_radius * smoothing.magnitude(kin.omega, SLIP_RATE_WIDTH)

    def forces(self, frames, aux, t):
        kin, res = self.contact(frames, aux)
        force = frames.to_global(self.bushing_body, res.force)
        at = frames.point(self.pin_body, self.pin_point)
        q = frames.wrench(self.pin_body, force, at=at, torque=res.torque)
        q = q + frames.wrench(self.bushing_body, -force, at=at, torque=-res.torque)
        rates = [res.memory_rate]
        if self.wear is not None:
            slide = self.sliding_rate(kin)
            rates.append(self.wear.depth_rate(res.pressure, slide))
            rates.append(jnp.atleast_1d(res.normal_load * slide))
        return q, jnp.concatenate(rates)

    def diagnose(self, frames: Frames, aux) -> str:
        """One line on the joint's state, for failure messages."""
        kin, res = self.contact(frames, aux)
        e = float(jnp.sqrt(kin.offset @ kin.offset))
        c = float(jnp.min(self.profile.clearance))
        return (f"clearance joint {self.name!r}: eccentricity {e * 1e6:.4g} um vs clearance "
                f"{c * 1e6:.4g} um, normal load {float(res.normal_load):.4g} N")

    # ------------------------------------------------------------- accessors
    def wear_depth(self, aux) -> Float[Array, " n"]:
        """Bushing wear depth on the grid [m] accumulated in the aux states."""
        start = self.law.n_memory
        return aux[start : start + self.profile.n]

    def load_sliding_integral(self, aux) -> Float[Array, ""]:
        """Integral of normal load x sliding distance [N m] (Archard bookkeeping)."""
        return aux[self.law.n_memory + self.profile.n]


def centred_state(ideal: Mechanism, y_ideal, mech: Mechanism):
    """The state of ``mech`` (``ideal`` with revolute joints swapped for clearance
    joints, `with_clearance`) that starts where ``ideal`` is: same positions and
    velocities, so every pin sits centred in its bushing, and the contact-law and
    wear states at their initial values (the thesis's start-up)."""
    q, qd, _ = ideal.split(y_ideal)
    return mech.join(q, qd, mech.initial_aux(q, qd))


def with_clearance(mech: Mechanism, joint: str, *, bushing_body: str | None = None,
                   **kwargs) -> Mechanism:
    """Replace the ideal `RevoluteJoint` ``joint`` of ``mech`` by a `ClearanceJoint`.

    By default the first body of the revolute joint carries the pin and the
    second the bushing; ``bushing_body`` (either of the two) chooses the body
    that carries the bushing.  Points are taken over.  ``kwargs`` go to
    `ClearanceJoint` (pin_radius, bushing_radius, law, friction, profile, wear,
    n_theta).  The state layout of q and qd is unchanged, so a consistent state
    of the ideal mechanism (pin centred, same velocities) starts the clearance one.
    """
    old = mech.element(joint)
    if not isinstance(old, RevoluteJoint):
        raise InputError(f"{joint!r} is a {type(old).__name__}, not a RevoluteJoint")
    ends = [(old.body_i, old.point_i), (old.body_j, old.point_j)]
    if bushing_body is not None:
        if bushing_body not in (old.body_i, old.body_j):
            raise InputError(f"joint {joint!r} connects {old.body_i!r} and {old.body_j!r}; "
                             f"bushing_body {bushing_body!r} is neither")
        if bushing_body == old.body_i:
            ends.reverse()
    (pin_b, pin_p), (bush_b, bush_p) = ends
    new = ClearanceJoint(joint, pin_b, pin_p, bush_b, bush_p, **kwargs)
    constraints = tuple(c for c in mech.constraints if c.name != joint)
    return Mechanism(mech.bodies, constraints, (*mech.forces, new))


class ContactHistory(eqx.Module):
    """A clearance joint's contact along a trajectory (arrays over saved times).

    force: force on the bushing body from the pin, global frame [N]
    normal_load: total normal load [N]
    offset: pin offset in the bushing frame [m]
    penetration: max_k (e . u_k - c_k) [m] (> 0: in contact)
    contact_angle: bushing angle of the offset direction [rad, 0..2 pi)
    pressure: p(theta_k) [Pa] (EFM; zeros for point laws)
    """

    force: Float[Array, "T 2"]
    normal_load: Float[Array, " T"]
    offset: Float[Array, "T 2"]
    penetration: Float[Array, " T"]
    contact_angle: Float[Array, " T"]
    pressure: Float[Array, "T n"]

    @property
    def force_magnitude(self) -> Float[Array, " T"]:
        return safe_norm(self.force)


def contact_history(mech: Mechanism, joint: str, ys: Float[Array, "T s"]) -> ContactHistory:
    """Evaluate the contact of clearance joint ``joint`` at every saved state."""
    import jax

    element = mech.element(joint)
    if not isinstance(element, ClearanceJoint):
        raise InputError(f"{joint!r} is not a ClearanceJoint")
    aux_slice = mech.aux_slice(joint)

    def one(y):
        q, qd, aux = mech.split(y)
        frames = mech.frames(q, qd)
        kin, res = element.contact(frames, aux[aux_slice])
        gap = dot2(element.profile.normals, kin.offset) - element.profile.clearance
        angle = jnp.mod(safe_angle(kin.offset), 2 * jnp.pi)
        force = -frames.to_global(element.bushing_body, res.force)
        return force, res.normal_load, kin.offset, jnp.max(gap), angle, res.pressure

    return ContactHistory(*jax.vmap(one)(ys))
