"""The elastic pin: a Q9 mesh of the pin cross-section and its surface compliance.

Model.  A solid pin of radius R, held along a small central bore r0 (u = 0 at
r = r0), loaded by a radial pressure on its outer surface r = R.  The bore is
how the 2-D model is held against rigid motion: in the plane a body carrying
a net force has no finite displacement without a reference (the 2-D Kelvin
solution grows like log r), and the pin of a pin joint is held by its ends.
The bore changes only the n = 1 (cos theta, sin theta) part of the surface
displacement much; a radial displacement A cos(theta - theta0) is, to first
order in the pin offset, a rigid translation of the surface, and the contact
solve (`diffwear.fem.contact.RingContact.solve_force`) absorbs it into the pin
offset e, which it solves for.  On the other modes the bore's effect is
small: measured against the solid disc's closed form (`solid_disc_compliance`)
at n_theta = 120, n_r = 16, it is 1.4 (r0/R)^2 for n = 0 and 3.7 (r0/R)^2
for n = 2 (3.6e-3 and 9.6e-3 at r0 = R/20; 1.4e-2 and 3.7e-2 at R/10), and
below the discretisation error (<= 1e-3) for n = 3, 4; n = 8 is 4e-3..8e-3
off from the discretisation (tests/test_pin_pivot.py).

Mesh.  `PinMesh` uses the numbering of `diffwear.fem.mesh.RingMesh` with the
radii reversed: node ``i * n_theta + j`` is on ring i at angle theta_j, ring
0 is the pin *surface* (the contact surface, where the compliance is
condensed) and ring 2 n_r the held bore.  So `diffwear.fem.condense` (which
keeps ring 0 and holds ring 2 n_r) condenses the pin unchanged.  Because the
element coordinate xi now points inward, the element's eta runs clockwise
(local node ``3 i_eta + i_xi`` at angle index 2m + 2 - i_eta), which keeps
det J > 0.  The layer boundaries are spaced geometrically from R to r0, so the
elements keep their aspect ratio (radial / tangential size) from the surface
to the bore: a uniform spacing would make the bore's elements ~R / r0 times
longer radially than wide.

Sign.  The contact pressure pushes the pin surface inward; the condensed
compliance C (radial displacement per outward radial nodal force, as for the
ring) therefore gives the inward displacement as C f for the inward nodal
force f >= 0: the pin's compliance adds to the pivot's (`pin_pivot_compliance`).
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from .._checks import check_int_option, check_positive, concrete
from ..errors import InputError
from ..mechanism.geometry import grid_angles
from .condense import inner_compliance
from .mesh import check_theta_nodes, connectivity


class PinMesh(eqx.Module):
    """Nodes and Q9 connectivity of the pin r0 <= r <= R (see the module docstring)."""

    nodes: Float[Array, "n_nodes 2"]
    elements: Int[Array, "n_el 9"]
    radius: Float[Array, ""]  # R [m]: the contact surface, ring 0
    bore_radius: Float[Array, ""]  # r0 [m]: held, ring 2 n_r
    n_theta: int = eqx.field(static=True)
    n_r: int = eqx.field(static=True)

    @property
    def theta(self) -> Float[Array, " n_theta"]:
        return grid_angles(self.n_theta)


def pin_connectivity(n_theta: int, n_r: int) -> np.ndarray:
    """`mesh.connectivity` with eta reversed (clockwise): det J > 0 when ring
    index increases inward."""
    perm = [3 * (2 - i_eta) + i_xi for i_eta in range(3) for i_xi in range(3)]
    return connectivity(n_theta, n_r)[:, perm]


def pin_mesh(radius, bore_radius, n_theta: int, n_r: int) -> PinMesh:
    """Q9 mesh of the pin cross-section r0 <= r <= R, ``n_theta`` nodes around
    (even, >= 8), ``n_r`` element layers spaced geometrically from R to r0
    (mid-layer nodes halfway through each layer)."""
    check_theta_nodes("pin mesh: n_theta (nodes around the pin)", n_theta)
    check_int_option("pin mesh: n_r (element layers)", n_r, 1)
    check_positive("pin mesh: pin radius R [m]", radius)
    check_positive("pin mesh: held bore radius r0 [m]", bore_radius)
    r_c, r0_c = concrete(radius), concrete(bore_radius)
    if r_c is not None and r0_c is not None and not r0_c < r_c:
        raise InputError(f"pin mesh: held bore radius r0 = {float(r0_c)!r} m must be below the "
                         f"pin radius R = {float(r_c)!r} m")
    n_theta, n_r = int(n_theta), int(n_r)
    big = jnp.asarray(radius, dtype=float)
    r0 = jnp.asarray(bore_radius, dtype=float)
    layer = big * (r0 / big) ** (jnp.arange(n_r + 1) / n_r)  # R ... r0, geometric
    mid = 0.5 * (layer[:-1] + layer[1:])
    radii = jnp.stack([layer[:-1], mid], axis=-1).reshape(-1)
    radii = jnp.concatenate([radii, layer[-1:]])  # (2 n_r + 1,): ring 0 = surface
    theta = grid_angles(n_theta)
    nodes = jnp.stack([radii[:, None] * jnp.cos(theta), radii[:, None] * jnp.sin(theta)],
                      axis=-1).reshape(-1, 2)
    return PinMesh(nodes=nodes, elements=jnp.asarray(pin_connectivity(n_theta, n_r)),
                   radius=big, bore_radius=r0, n_theta=n_theta, n_r=n_r)


def pin_compliance(mesh: PinMesh, youngs_modulus, poisson_ratio) -> Float[Array, "n n"]:
    """C_pin [m per N/m]: inward radial displacement of the pin's surface nodes
    per inward radial nodal force (bore held).  Same condensation as the ring
    (`condense.inner_compliance`): ring 0 is the kept surface either way."""
    return inner_compliance(mesh, youngs_modulus, poisson_ratio)


def solid_disc_compliance(n: int, radius, youngs_modulus, poisson_ratio):
    """Closed form, plane strain: inward surface displacement u_n [m] of a solid
    disc of radius R under the radial surface pressure p cos(n theta), per unit
    p [Pa], for n = 0 or n >= 2 (n = 1 carries a net force: no finite answer
    in 2-D without a support; see the module docstring).

    n = 0 (Lame, solid): u = p R (1 + nu)(1 - 2 nu) / E.
    n >= 2 (Michell, Airy phi = (A r^n + B r^(n+2)) cos n theta, regular at
    r = 0; sigma_rr(R) = -p cos n theta, sigma_r theta(R) = 0 give
    B = -p / (2 (n+1) R^n), A = p R^(2-n) / (2 (n-1)); u_r from
    eps_rr = (1 + nu)/E ((1 - nu) sigma_rr - nu sigma_theta theta)):

        u = p R (1 + nu) / (2 E) [n / (n - 1) + (n + 2 - n^2 - 4 nu (n + 1)) / (n + 1)^2],

    which tends to the half-plane value 2 (1 - nu^2) p / (E n / R) for large n.
    """
    e, nu, r = float(youngs_modulus), float(poisson_ratio), float(radius)
    if n == 0:
        return r * (1 + nu) * (1 - 2 * nu) / e
    if n < 2:
        raise InputError(f"solid disc compliance: mode n must be 0 or >= 2, got {n!r}")
    return r * (1 + nu) / (2 * e) * (
        n / (n - 1) + (n + 2 - n * n - 4 * nu * (n + 1)) / (n + 1) ** 2
    )
