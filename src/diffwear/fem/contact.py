"""Frictionless unilateral contact of a rigid round pin in an elastic (worn) ring.

Unknowns: the radial nodal forces f_j >= 0 [N per metre of axial length] on
the ring's inner-surface nodes (`diffwear.fem.condense`), and for the
given-force problem also the pin-centre offset e [m] from the ring centre.

Gap.  The pin (radius R = a - clearance) is centred at e.  Along the ray theta_j
from the ring centre its surface is at rho_j = e . u_j + sqrt(R^2 - (e x u_j)^2)
(u_j = (cos theta_j, sin theta_j); exact, not the small-offset form
e . u_j + R, which differs by up to |e x u_j|^2 / (2R) = 5e-7 a at
|e| = 1e-3 a: the error this avoids), so the undeformed gap is
g0_j = r_b(theta_j) - rho_j with r_b = a + depth_j the worn surface, and after
deformation g = g0 + u_r = g0 + C f.  The pin's pressure is taken to act
radially and the gap to be measured radially: both neglect the pin surface's
tilt to the ray, of order |e| / R (conformal contact: |e| ~ clearance << R).

Complementarity (an LCP with the SPD matrix C): f >= 0, g >= 0, f g = 0,
solved by semismooth Newton on the Fischer-Burmeister function (`ncp`).  In
the given-force problem, two equations more: the force of the pin on the ring,
L sum_j f_j u_j (L the axial length of the bushing), equals F.

Pressure.  Reported at the nodes as p_j = f_j / w_j [Pa], w_j the tributary
length of node j (`condense.tributary_lengths`): exact for a uniform pressure;
for a varying one it is the nodal value of the lumped (row-sum) load.

The cost of the solves and of building the problem is on the docs' FEM page.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float

from .._checks import check_finite, check_positive, concrete
from ..errors import InputError, SolverError
from . import ncp
from .condense import inner_compliance, tributary_lengths
from .mesh import RingMesh

#: Newton tolerance on max |Phi|, Phi made dimensionless (see `_scales`):
#: near the float64 round-off of a 100-node LCP (1e-16 x condition ~1e3).
TOL = 1e-12
#: A node counts as in contact when its force exceeds this fraction of the
#: largest nodal force (the FB solution leaves |f| ~ 1e-16 max f off contact).
CONTACT_FRACTION = 1e-9


class ContactSolution(eqx.Module):
    """The solved contact; pressures and forces at the inner-surface nodes."""

    offset: Float[Array, "2"]  # pin centre e [m]
    nodal_force: Float[Array, " n"]  # f_j [N/m], radial, on the ring
    pressure: Float[Array, " n"]  # p_j = f_j / w_j [Pa]
    gap: Float[Array, " n"]  # g_j after deformation [m]
    resultant: Float[Array, "2"]  # L sum f_j u_j [N]: the pin's force on the ring
    theta: Float[Array, " n"]
    info: ncp.NewtonInfo

    @property
    def in_contact(self) -> Bool[Array, " n"]:
        return self.nodal_force > CONTACT_FRACTION * jnp.max(self.nodal_force)

    @property
    def contact_arc(self) -> Float[Array, ""]:
        """Angular extent of the contact [rad]: (nodes in contact) x 2 pi / n,
        resolution one node spacing (the edge lies between two nodes)."""
        n = self.theta.shape[0]
        return jnp.sum(self.in_contact) * 2.0 * jnp.pi / n

    @property
    def peak_pressure(self) -> Float[Array, ""]:
        return jnp.max(self.pressure)

    def raise_if_failed(self, what: str = "FEM pin contact") -> "ContactSolution":
        """`SolverError` if Newton did not converge or a value is not finite (outside jit)."""
        ok = bool(self.info.converged) and all(
            np.all(np.isfinite(np.asarray(x)))
            for x in (self.offset, self.nodal_force, self.gap))
        if not ok:
            raise SolverError(
                f"{what}: the complementarity solve did not converge: max |residual| "
                f"{float(self.info.residual):.3g} (tolerance {self.info.tol:g}) after "
                f"{int(self.info.steps)} Newton steps.  Check the load (a force far "
                "beyond the elastic range of the bushing) and the mesh.")
        return self


class RingContact(eqx.Module):
    """The condensed ring (compliance C, tributary lengths w) and the pin."""

    compliance: Float[Array, "n n"]  # [m per N/m]
    tributary: Float[Array, " n"]  # w_j [m]
    boundary_radius: Float[Array, " n"]  # r_b(theta_j) = a + depth_j [m]
    theta: Float[Array, " n"]
    pin_radius: Float[Array, ""]
    length: Float[Array, ""]  # axial length L of the bushing [m]

    @classmethod
    def build(cls, mesh: RingMesh, youngs_modulus, poisson_ratio, clearance, length
              ) -> "RingContact":
        """Condense ``mesh`` (E [Pa], nu) for a pin of radius a - clearance [m]."""
        check_positive("ring contact: Young's modulus E [Pa]", youngs_modulus)
        nu = concrete(poisson_ratio)
        if nu is not None and not (-1.0 < float(nu) < 0.5):
            raise InputError(
                f"ring contact: Poisson ratio nu must lie in (-1, 0.5), got {float(nu)!r}"
            )
        check_positive("ring contact: radial clearance a - R_pin [m]", clearance, allow_zero=True)
        check_positive("ring contact: bushing axial length L [m]", length)
        c, a = concrete(clearance), concrete(mesh.inner_radius)
        if c is not None and a is not None and not c < a:
            raise InputError(f"ring contact: clearance {float(c)!r} m leaves no pin in a "
                             f"ring of inner radius {float(a)!r} m")
        compliance, tributary = _condense(mesh, youngs_modulus, poisson_ratio)
        return cls(
            compliance=compliance,
            tributary=tributary,
            boundary_radius=mesh.boundary_radius,
            theta=mesh.theta,
            pin_radius=mesh.inner_radius - jnp.asarray(clearance, dtype=float),
            length=jnp.asarray(length, dtype=float),
        )

    @property
    def directions(self) -> Float[Array, "n 2"]:
        return jnp.stack([jnp.cos(self.theta), jnp.sin(self.theta)], axis=-1)

    def initial_gap(self, offset: Float[Array, "2"]) -> Float[Array, " n"]:
        """g0_j = r_b(theta_j) - (e . u_j + sqrt(R^2 - (e x u_j)^2)) [m] (exact ray form)."""
        u = self.directions
        along = u @ offset
        across = u[:, 0] * offset[1] - u[:, 1] * offset[0]
        return self.boundary_radius - along - jnp.sqrt(self.pin_radius**2 - across**2)

    def wall_offset(self, force) -> Float[Array, "2"]:
        """The pin offset e [m] along F that touches the (worn) wall at the node
        nearest F's direction: a `solve_force` start for a worn ring, where the
        pin sits in the pocket rather than at the least worn point."""
        unit = force / jnp.sqrt(jnp.sum(force * force))
        n = self.theta.shape[0]
        ang = jnp.mod(jnp.arctan2(unit[1], unit[0]), 2 * jnp.pi) * n / (2 * jnp.pi)
        j = jnp.round(ang).astype(int) % n
        return unit * (self.boundary_radius[j] - self.pin_radius)

    def _scales(self, length_scale):
        """(gap scale l [m], force scale l / mean C_jj [N/m]): Phi in O(1) units."""
        return length_scale, length_scale / jnp.mean(jnp.diag(self.compliance))

    def _solution(self, e, f, info) -> ContactSolution:
        return ContactSolution(
            offset=e, nodal_force=f, pressure=f / self.tributary,
            gap=self.initial_gap(e) + self.compliance @ f,
            resultant=self.length * (f @ self.directions), theta=self.theta, info=info)

    @staticmethod
    def _checked(sol: ContactSolution) -> ContactSolution:
        """Outside jit (concrete values) the solution is checked at once, so a
        failure raises `SolverError`; under jit call ``raise_if_failed``."""
        if concrete(sol.info.residual) is not None:
            sol.raise_if_failed()
        return sol

    def solve_offset(self, offset, *, tol: float = TOL) -> ContactSolution:
        """Contact for a prescribed pin offset e [m] (|e| < R); ``tol``: Newton
        tolerance on the dimensionless max |Phi|."""
        e = jnp.asarray(offset, dtype=float)
        _check_vector("pin offset e [m]", e)
        ev, radius = concrete(e), concrete(self.pin_radius)
        if ev is not None and radius is not None and np.hypot(*ev) >= float(radius):
            raise InputError(f"ring contact: pin offset |e| = {np.hypot(*ev)!r} m must be "
                             f"below the pin radius {float(radius)!r} m")
        return self._checked(_solve_offset(self, e, tol))

    def _solve_offset(self, e, tol):
        ell = jnp.maximum(jnp.sqrt(jnp.sum(e * e)),
                          jnp.max(self.boundary_radius) - self.pin_radius)
        ell = jax.lax.stop_gradient(jnp.where(ell > 0, ell, 1.0))
        l_g, f_s = self._scales(ell)

        def residual(x, args):
            prob, e_arg = args
            f = x * f_s
            g = prob.initial_gap(e_arg) + prob.compliance @ f
            return ncp.fischer_burmeister(x, g / l_g)

        x, info = ncp.solve(residual, jnp.zeros_like(self.theta), (self, e), tol=tol)
        return self._solution(e, x * f_s, info)

    def solve_force(self, force, *, tol: float = TOL, offset_guess=None, guess=None,
                    window: int | None = None, polish: bool = True) -> ContactSolution:
        """Contact for a prescribed force F [N] of the pin on the ring (F != 0):
        unknowns f and e, with L sum_j f_j u_j = F.  ``offset_guess`` [m]: the
        Newton start for e (default: the pin touching the nearest wall point
        along F); in a deeply worn ring the nearest wall point can lie far from
        the solution (the pin sits in the pocket), and a start there (e.g. the
        previous solution of a sequence of solves) saves many damped steps.
        ``guess``: a whole start, (offset e [m], nodal forces f [N/m]), e.g. the
        solution for a nearby force (it replaces ``offset_guess``).

        ``window``: solve first on the ``window`` nodes centred on F's direction
        (the others held at f = 0), then accept that solution only if it solves
        the whole ring's problem to ``tol`` (every node outside open, g >= 0),
        else solve the whole ring from it.  The same solution either way (to
        ``tol``), for a Newton system of window + 2 instead of n + 2 unknowns
        where the contact arc is known to be short (a pin pressed along F
        touches within +-90 deg of F: ``window = n // 2`` serves any such
        contact).  ``polish``: as `ncp.solve` (False: the solution as the
        Newton loop leaves it, within ``tol``, one LU less)."""
        force = jnp.asarray(force, dtype=float)
        _check_vector("joint force F [N]", force)
        fv = concrete(force)
        if fv is not None and np.hypot(*fv) == 0.0:
            raise InputError("ring contact: joint force F must be nonzero (at F = 0 the pin "
                             "position inside the clearance is not determined)")
        if offset_guess is not None:
            offset_guess = jnp.asarray(offset_guess, dtype=float)
            _check_vector("offset guess e [m]", offset_guess)
        n = self.theta.shape[0]
        if window is not None and not (isinstance(window, int) and 1 <= window):
            raise InputError(f"ring contact: window must be a positive number of nodes, "
                             f"got {window!r}")
        if window is not None and window >= n:
            window = None
        if guess is not None:
            e_g, f_g = (jnp.asarray(v, dtype=float) for v in guess)
            _check_vector("guess offset e [m]", e_g)
            if f_g.shape != (n,):
                raise InputError(f"ring contact: guess nodal forces need shape ({n},), got "
                                 f"{f_g.shape}")
            guess = (e_g, f_g)
        return self._checked(_solve_force(self, force, tol, offset_guess, guess, window,
                                          polish))

    def window_nodes(self, force, size: int):
        """Indices of the ``size`` nodes centred on the node nearest F's direction."""
        n = self.theta.shape[0]
        ang = jnp.mod(jnp.arctan2(force[1], force[0]), 2 * jnp.pi) * n / (2 * jnp.pi)
        j = jnp.round(ang).astype(int)
        return (j - size // 2 + jnp.arange(size)) % n

    def restricted(self, nodes) -> "RingContact":
        """The contact on the inner-surface nodes ``nodes`` only (the others
        unloaded): compliance, tributary lengths, surface and angles taken there."""
        return RingContact(compliance=self.compliance[nodes[:, None], nodes[None, :]],
                           tributary=self.tributary[nodes],
                           boundary_radius=self.boundary_radius[nodes], theta=self.theta[nodes],
                           pin_radius=self.pin_radius, length=self.length)

    def _force_scales(self, force):
        """(gap scale l [m], force scale [N/m], |F| [N]) of the given-force
        residual: constants of its units (the solution does not depend on them)."""
        mag = jnp.sqrt(jnp.sum(force * force))
        gap0 = jnp.max(self.boundary_radius) - self.pin_radius
        # Scale: the clearance plus the wall's deflection under F spread on ~n/4 nodes.
        ell = gap0 + (mag / self.length * jnp.mean(jnp.diag(self.compliance)) * 4.0
                      / self.theta.shape[0])
        return jax.lax.stop_gradient((*self._scales(ell), mag))

    def force_depth_derivative(self, force, offset, nodal_force, nodes) -> Float[Array, "m m"]:
        """D[i, j] = d f(nodes_i) / d r_b(nodes_j) [N/m per m]: how the nodal
        forces of the given-force solution (``offset`` e [m], ``nodal_force``
        f [N/m], for ``force``) change with the surface radius (a + depth) of
        the nodes ``nodes``, load and compliance held, by the implicit function
        theorem: the derivative of `solve_force`'s result, in closed form.
        Exact where every loaded node is among ``nodes`` (the others open:
        f = 0, g > 0); one LU of size m + 2."""
        l_g, f_s, mag = self._force_scales(force)
        sub = self.restricted(nodes)
        args = (sub, force, (l_g, f_s, mag))
        x = nodal_force[nodes] / f_s
        z = jnp.concatenate([x, offset / l_g])
        jac = _force_jacobian(z, args)
        g = (sub.initial_gap(offset) + sub.compliance @ nodal_force[nodes]) / l_g
        _, db = ncp.fischer_burmeister_partials(x, g)
        m = nodes.shape[0]
        # d Phi / d r_b: the complementarity rows through g / l_g (d g_j / d r_b,j = 1)
        rhs = jnp.concatenate([jnp.diag(db / l_g), jnp.zeros((2, m))], axis=0)
        return -f_s * jnp.linalg.solve(jac, rhs)[:m]

    def _solve_force(self, force, tol, offset_guess=None, guess=None, window=None,
                     polish=True):
        n = self.theta.shape[0]
        l_g, f_s, mag = scales = self._force_scales(force)
        unit = force / mag
        if guess is not None:
            e0, x0 = guess[0], guess[1] / f_s
        else:  # pin touching the nearest wall point along F (or the guess), nothing loaded
            e0 = (unit * (jnp.min(self.boundary_radius) - self.pin_radius)
                  if offset_guess is None else offset_guess)
            x0 = jnp.zeros(n)
        z0 = jax.lax.stop_gradient(jnp.concatenate([x0, e0 / l_g]))
        args = (self, force, scales)

        def whole(z_start, steps_before=0):
            z, info = ncp.solve(_force_residual, z_start, args, tol=tol, jacobian=_force_jacobian,
                                polish=polish)
            return z, eqx.tree_at(lambda i: i.steps, info, info.steps + steps_before)

        if window is None:
            z, info = whole(z0)
        else:
            nodes = self.window_nodes(jax.lax.stop_gradient(force), window)
            zw, info_w = ncp.solve(_force_residual,
                                   jnp.concatenate([z0[:n][nodes], z0[n:]]),
                                   (self.restricted(nodes), force, scales), tol=tol,
                                   jacobian=_force_jacobian, polish=polish)
            z_in = jnp.concatenate([jnp.zeros(n).at[nodes].set(zw[:window]), zw[window:]])
            # the whole ring's residual there: the window's rows, and the open nodes
            # outside it (f = 0: phi = 0 where g >= 0, 2 g / l_g where g < 0)
            res = jnp.max(jnp.abs(_force_residual(jax.lax.stop_gradient(z_in),
                                                  jax.lax.stop_gradient(args))))
            inside = res <= tol
            info_in = ncp.NewtonInfo(converged=inside, residual=res, steps=info_w.steps,
                                     tol=tol)
            z, info = jax.lax.cond(
                inside, lambda: (z_in, info_in),
                lambda: whole(jax.lax.stop_gradient(z_in), info_w.steps))
        return self._solution(z[n:] * l_g, z[:n] * f_s, info)


def _force_residual(z, args):
    """Phi of the given-force problem: unknowns z = (f / f_s, e / l_g); rows the
    Fischer-Burmeister complementarity of (f, g) per node, then the two force
    equations L sum_j f_j u_j = F (relative to |F|)."""
    prob, force, (l_g, f_s, mag) = args
    n = prob.theta.shape[0]
    x, e = z[:n], z[n:] * l_g
    f = x * f_s
    g = prob.initial_gap(e) + prob.compliance @ f
    eq = (prob.length * (f @ prob.directions) - force) / mag
    return jnp.concatenate([ncp.fischer_burmeister(x, g / l_g), eq])


def _force_jacobian(z, args):
    """d Phi / dz of `_force_residual` in closed form (its forward-mode Jacobian,
    one tangent per unknown, cost n products with C; this costs one scaling of C):

        [[diag(a) + diag(b) C f_s / l_g,   diag(b) dg0/de],
         [L f_s u^T / |F|,                 0            ]]

    with (a, b) the Fischer-Burmeister partials and dg0_j/de = -u_j +
    (e x u_j) / sqrt(R^2 - (e x u_j)^2) d(e x u_j)/de (the exact ray gap)."""
    prob, _, (l_g, f_s, mag) = args
    n = prob.theta.shape[0]
    x, e = z[:n], z[n:] * l_g
    u = prob.directions
    g = (prob.initial_gap(e) + prob.compliance @ (x * f_s)) / l_g
    da, db = ncp.fischer_burmeister_partials(x, g)
    across = u[:, 0] * e[1] - u[:, 1] * e[0]
    root = jnp.sqrt(prob.pin_radius**2 - across**2)
    d_across = jnp.stack([-u[:, 1], u[:, 0]], axis=-1)
    dg0 = -u + (across / root)[:, None] * d_across
    top = jnp.concatenate([jnp.diag(da) + db[:, None] * prob.compliance * (f_s / l_g),
                           db[:, None] * dg0], axis=1)
    bottom = jnp.concatenate([(prob.length * f_s / mag) * u.T, jnp.zeros((2, 2))], axis=1)
    return jnp.concatenate([top, bottom], axis=0)


@eqx.filter_jit
def _condense(mesh, youngs_modulus, poisson_ratio):
    return inner_compliance(mesh, youngs_modulus, poisson_ratio), tributary_lengths(mesh)


# compiled once per problem shape and tolerance (a Python float: static)
_solve_offset = eqx.filter_jit(RingContact._solve_offset)
_solve_force = eqx.filter_jit(RingContact._solve_force)


def _check_vector(what: str, v) -> None:
    if v.shape != (2,):
        raise InputError(f"ring contact: {what} must be a 2-vector, got shape {v.shape}")
    check_finite(f"ring contact: {what}", v)
