"""`RingMesh`: a structured mesh of 9-node quadratic quadrilaterals (Q9) on a
bushing ring, optionally worn on its inner surface.

Geometry.  The ring occupies a <= r <= b (inner radius a, outer radius b) in the
bushing frame; theta is measured counter-clockwise from the bushing x axis, the
convention of `diffwear.contact.BushingProfile`.  A wear profile ``depth`` [m]
moves the inner boundary outward: node j of the inner surface sits at radius
r_in(theta_j) = a + depth_j, theta_j = 2 pi j / n_theta.  Every node of the same
angle lies on the ray theta_j, with radii spaced evenly from r_in(theta_j) to b
(linear interpolation through the wall), so wear compresses the elements of
that angle and never moves the outer boundary.

Elements.  Q9 (biquadratic Lagrange) elements, ``n_theta / 2`` around and
``n_r`` through the wall, so the mesh has ``n_theta`` nodes on every one of
its ``2 n_r + 1`` node rings.  Q9 was chosen over linear elements because the
contact compliance is needed at the inner surface of a thick, curved wall:
the quadratic isoparametric map follows the circle (over a 30 degree element
the straight chord is off the arc by up to 3.4e-2 a, the quadratic arc by
1.5e-4 a; over 15 degrees 8.6e-3 a vs 9.1e-6 a: computed by sampling the
maps) and the field u = A r + B / r of a pressurised ring converges fast
(tests/test_fem.py: Lame convergence).  Isoparametric elements contain every
linear field, so the mesh passes the patch test on any (also worn) geometry.

Numbering (used by `diffwear.fem.condense` to eliminate the wall ring by ring):
node ``i * n_theta + j`` is on ring i (0 = inner surface, 2 n_r = outer,
held fixed) at angle theta_j.  Element ``k * (n_theta // 2) + m`` is in layer k
(0 = innermost) and spans angles theta_{2m} .. theta_{2m+2}; its local node
``3 * i_eta + i_xi`` (i_xi, i_eta in 0, 1, 2) is on ring 2k + i_xi at angle
index 2m + i_eta (mod n_theta): the element coordinate xi points radially
outward and eta counter-clockwise, which makes det J > 0.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from .._checks import check_finite, check_int_option, check_positive, concrete
from ..errors import InputError
from ..mechanism.geometry import grid_angles

#: Smallest number of nodes around: 4 elements of 90 degrees.  A quadratic arc
#: over 90 degrees is within 1.1 % of the circle (sampled); with fewer elements
#: the map cannot represent a ring (2 elements of 180 degrees collapse the wall).
MIN_THETA_NODES = 8

#: A worn wall must keep this fraction of its unworn thickness b - a.  Below it
#: the bushing is worn through for any engineering purpose, and the elements of
#: that angle are over 10x flatter (radial size / tangential size) than those of
#: the unworn mesh, where Q9 accuracy degrades (a choice, not a material limit).
MIN_WALL_FRACTION = 0.1


class RingMesh(eqx.Module):
    """Nodes and Q9 connectivity of a (worn) ring; see the module docstring."""

    nodes: Float[Array, "n_nodes 2"]
    elements: Int[Array, "n_el 9"]
    inner_radius: Float[Array, ""]
    outer_radius: Float[Array, ""]
    depth: Float[Array, " n_theta"]
    n_theta: int = eqx.field(static=True)
    n_r: int = eqx.field(static=True)

    @property
    def theta(self) -> Float[Array, " n_theta"]:
        return grid_angles(self.n_theta)

    @property
    def n_nodes(self) -> int:
        return self.n_theta * (2 * self.n_r + 1)

    @property
    def inner_nodes(self) -> np.ndarray:
        return np.arange(self.n_theta)

    @property
    def outer_nodes(self) -> np.ndarray:
        return 2 * self.n_r * self.n_theta + np.arange(self.n_theta)

    @property
    def boundary_radius(self) -> Float[Array, " n_theta"]:
        """r_in(theta_j) = a + depth_j [m]: the (worn) inner surface at its nodes."""
        return self.inner_radius + self.depth


def connectivity(n_theta: int, n_r: int) -> np.ndarray:
    """Q9 connectivity (n_r * n_theta // 2, 9) in the numbering of the module docstring."""
    m = np.arange(n_theta // 2)
    layers = []
    for k in range(n_r):
        cols = []
        for i_eta in range(3):
            for i_xi in range(3):
                cols.append((2 * k + i_xi) * n_theta + (2 * m + i_eta) % n_theta)
        layers.append(np.stack(cols, axis=-1))
    return np.concatenate(layers, axis=0)


def check_theta_nodes(what: str, n_theta) -> None:
    """Nodes around a Q9 ring or disc: an even integer >= `MIN_THETA_NODES`
    (two nodes per element), else `InputError` naming ``what`` and the value."""
    if (not isinstance(n_theta, (int, np.integer)) or isinstance(n_theta, bool)
            or n_theta < MIN_THETA_NODES or n_theta % 2):
        raise InputError(f"{what} must be an even integer >= {MIN_THETA_NODES}, "
                         f"got {n_theta!r}")


def ring_mesh(inner_radius, outer_radius, n_theta: int, n_r: int, depth=None) -> RingMesh:
    """A Q9 mesh of the ring a <= r <= b, inner surface worn by ``depth`` [m].

    ``n_theta``: nodes around (even, >= 8); ``n_r``: element layers through the
    wall (>= 1); ``depth``: None (unworn) or ``n_theta`` values >= 0 at theta_j.
    Radii and depth may be JAX tracers (the mesh is differentiable in them);
    concrete values are validated and raise `InputError`.
    """
    check_theta_nodes("ring mesh: n_theta (nodes around the ring)", n_theta)
    check_int_option("ring mesh: n_r (element layers through the wall)", n_r, 1)
    n_theta, n_r = int(n_theta), int(n_r)
    check_positive("ring mesh: inner radius a [m]", inner_radius)
    check_positive("ring mesh: outer radius b [m]", outer_radius)
    a_c, b_c = concrete(inner_radius), concrete(outer_radius)
    if a_c is not None and b_c is not None and not b_c > a_c:
        raise InputError(f"ring mesh: outer radius b = {float(b_c)!r} m must exceed "
                         f"inner radius a = {float(a_c)!r} m")
    a = jnp.asarray(inner_radius, dtype=float)
    b = jnp.asarray(outer_radius, dtype=float)
    if depth is None:
        depth = jnp.zeros(n_theta)
    depth = jnp.asarray(depth, dtype=float)
    if depth.shape != (n_theta,):
        raise InputError(f"ring mesh: wear depth needs one value per inner-surface node, "
                         f"shape ({n_theta},), got {depth.shape}")
    check_finite("ring mesh: wear depth [m]", depth)
    d_c = concrete(depth)
    if d_c is not None and np.any(d_c < 0):
        j = int(np.argmin(d_c))
        raise InputError(f"ring mesh: wear depth must be >= 0 (material removed), got "
                         f"{d_c[j]!r} m at node {j}")
    if d_c is not None and a_c is not None and b_c is not None:
        wall = b_c - a_c - d_c.max()
        if wall <= 0:
            raise InputError(f"ring mesh: worn profile pierces the wall: a + max depth = "
                             f"{float(a_c + d_c.max())!r} m >= outer radius b = {float(b_c)!r} m")
        if wall < MIN_WALL_FRACTION * (b_c - a_c):
            raise InputError(f"ring mesh: worn wall too thin: {float(wall)!r} m left of "
                             f"{float(b_c - a_c)!r} m (minimum {MIN_WALL_FRACTION:.0%} of the "
                             f"unworn wall) at node {int(np.argmax(d_c))}")
    theta = grid_angles(n_theta)
    s = jnp.arange(2 * n_r + 1) / (2 * n_r)  # 0 at the inner surface, 1 at r = b
    r_in = a + depth
    r = r_in[None, :] + s[:, None] * (b - r_in)[None, :]  # (2 n_r + 1, n_theta)
    nodes = jnp.stack([r * jnp.cos(theta), r * jnp.sin(theta)], axis=-1).reshape(-1, 2)
    return RingMesh(nodes=nodes, elements=jnp.asarray(connectivity(n_theta, n_r)),
                    inner_radius=a, outer_radius=b, depth=depth, n_theta=n_theta, n_r=n_r)
