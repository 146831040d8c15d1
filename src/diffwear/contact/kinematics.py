"""Relative kinematics of a pin in a bushing, in the bushing frame."""

from __future__ import annotations

from typing import NamedTuple

from jaxtyping import Array, Float


class PinKinematics(NamedTuple):
    """Pin relative to bushing, expressed in the bushing body's frame.

    offset: pin centre minus bushing centre (the eccentricity vector e) [m]
    offset_rate: d(offset)/dt as seen from the bushing [m/s]
    omega: relative angular velocity phi_dot_pin - phi_dot_bushing [rad/s]
    pin_radius, bushing_radius: [m]
    """

    offset: Float[Array, "2"]
    offset_rate: Float[Array, "2"]
    omega: Float[Array, ""]
    pin_radius: Float[Array, ""]
    bushing_radius: Float[Array, ""]


class ContactResult(NamedTuple):
    """What a contact law returns, in the bushing frame.

    force: force on the pin [N] (the bushing receives its opposite)
    torque: moment on the pin about its centre [N m] (friction)
    normal_load: total normal load [N]: the integral of the pressure over the
        contact area (EFM) or |F_N| (point laws).  In a conformal contact it
        exceeds |force| (up to 4/pi for a cosine pressure over a half circle).
    pressure: p(theta_k) on the bushing grid [Pa] (zeros for point laws)
    memory_rate: time derivative of the law's internal states
    """

    force: Float[Array, "2"]
    torque: Float[Array, ""]
    normal_load: Float[Array, ""]
    pressure: Float[Array, " n"]
    memory_rate: Float[Array, " m"]
