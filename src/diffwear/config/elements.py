"""Element types of a mechanism file: ``type = "..."`` -> fields + builder.

``[[joints]]`` entries dispatch through `JOINT_TYPES`, ``[[forces]]`` entries
through `FORCE_TYPES`.  A module adding an element (e.g. a clearance joint)
registers it here before a file is loaded::

    from diffwear.config import JOINT_TYPES, ElementType, schema
    JOINT_TYPES["clearance"] = ElementType(
        fields={"name": schema.Text(name=True), ...},
        build=lambda v: ClearanceJoint(**v),
        doc="revolute joint with radial clearance")

The ``type`` key itself is handled by the loader; ``fields`` lists the others.
``build`` receives the converted values (SI floats, tuples for vectors) and
returns the `AbstractConstraint` / `AbstractForceElement`; an `InputError`
it raises is reported with the entry's key path, a `FieldError` with the path
of the key it names.  With ``bodies=True`` it also receives ``{name: Body}``
(e.g. for a default damping mass).

A ``[[joints]]`` type may build a *force element* (a clearance joint: the pin
floats in the bushing).  It then needs ``assembly``: element -> the ideal
constraint that stands in for it when the mechanism is assembled at t = 0
(a clearance joint starts centred, with the ideal joint's velocities).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, NamedTuple

from ..errors import InputError
from ..mechanism import (
    STANDARD_GRAVITY,
    Driver,
    Gravity,
    LinearSpring,
    RevoluteJoint,
    TranslationalJoint,
)
from .schema import BodyRef, Direction, Field, Quantity, Text, Vector


class ElementType(NamedTuple):
    fields: Mapping[str, Field]
    build: Callable[..., Any]
    doc: str
    bodies: bool = False
    assembly: Callable[[Any], Any] | None = None


class FieldError(InputError):
    """A build-time problem with one key of the entry (reported as ``<entry>.<key>``)."""

    def __init__(self, key: str, what: str, allowed: str | None = None):
        self.key, self.what, self.allowed = key, what, allowed
        super().__init__(f"{key}: {what}" + (f"; allowed: {allowed}" if allowed else ""))


NAME = Text(name=True, doc="unique among joints and forces")

JOINT_TYPES: dict[str, ElementType] = {
    "revolute": ElementType(
        fields={
            "name": NAME,
            "body_i": BodyRef(), "body_j": BodyRef(),
            "point_i": Vector(dimension="length", doc="joint point, body i frame"),
            "point_j": Vector(dimension="length", doc="joint point, body j frame"),
        },
        build=lambda v: RevoluteJoint(v["name"], v["body_i"], v["body_j"], v["point_i"],
                                      v["point_j"]),
        doc="ideal pin: point_i of body_i coincides with point_j of body_j",
    ),
    "translational": ElementType(
        fields={
            "name": NAME,
            "body_i": BodyRef(), "body_j": BodyRef(),
            "point_i": Vector(dimension="length", default=(0.0, 0.0)),
            "point_j": Vector(dimension="length", default=(0.0, 0.0)),
            "axis_j": Direction(default=(1.0, 0.0), doc="sliding axis, body j frame"),
            "angle": Quantity(dimension="angle", default=0.0, doc="phi_i - phi_j"),
        },
        build=lambda v: TranslationalJoint(v["name"], v["body_i"], v["body_j"], v["point_i"],
                                           v["point_j"], v["axis_j"], v["angle"]),
        doc="prismatic: body_i slides along axis_j of body_j at a fixed relative angle",
    ),
    "driver": ElementType(
        fields={
            "name": NAME,
            "body": BodyRef(ground=False),
            "omega": Quantity(dimension="angular speed"),
            "angle0": Quantity(dimension="angle", default=0.0),
        },
        build=lambda v: Driver(v["name"], v["body"], v["omega"], v["angle0"]),
        doc="constant speed: phi_body = angle0 + omega t",
    ),
}
"""Joint (constraint) types by their ``type`` key."""

FORCE_TYPES: dict[str, ElementType] = {
    "gravity": ElementType(
        fields={
            "name": Text(name=True, default="gravity"),
            "g": Vector(dimension="acceleration", default=(0.0, -STANDARD_GRAVITY)),
        },
        build=lambda v: Gravity(v["g"], name=v["name"]),
        doc="uniform gravity on every body (default g = (0, -9.80665) m/s^2)",
    ),
    "spring": ElementType(
        fields={
            "name": NAME,
            "body_i": BodyRef(), "point_i": Vector(dimension="length"),
            "body_j": BodyRef(), "point_j": Vector(dimension="length"),
            "stiffness": Quantity(dimension="stiffness", low=0.0),
            "free_length": Quantity(dimension="length", low=0.0),
            "damping": Quantity(dimension="damping", default=0.0, low=0.0),
        },
        build=lambda v: LinearSpring(v["name"], v["body_i"], v["point_i"], v["body_j"],
                                     v["point_j"], v["stiffness"], v["free_length"], v["damping"]),
        doc="linear spring-damper between two body points",
    ),
}
"""Force-element types by their ``type`` key."""
