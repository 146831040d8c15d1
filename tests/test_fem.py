"""diffwear.fem: Q9 plane-strain ring, condensation and pin contact, each
checked against an independent value (closed form, a different algorithm or a
finite difference)."""

import jax

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.optimize import brentq  # noqa: E402

from diffwear.errors import InputError, SolverError  # noqa: E402
from diffwear.fem.condense import inner_compliance, inner_stiffness, tributary_lengths  # noqa: E402
from diffwear.fem.contact import RingContact  # noqa: E402
from diffwear.fem.elasticity import assemble, solve_prescribed, stresses  # noqa: E402
from diffwear.fem.element import plane_strain_matrix  # noqa: E402
from diffwear.fem.mesh import ring_mesh  # noqa: E402

E_PTFE, NU_PTFE = 0.5e9, 0.38  # PTFE of the thesis, Table 3-2 (diffwear.contact.PTFE)


def _patch():
    """2 x 2 Q9 elements on [0, 2]^2, nodes on a 5 x 5 grid, every interior
    node and every boundary node (along its edge) moved by up to 0.15."""
    rng = np.random.default_rng(0)
    g = np.linspace(0.0, 2.0, 5)
    x, y = np.meshgrid(g, g, indexing="xy")
    nodes = np.stack([x.ravel(), y.ravel()], axis=-1)
    iy, ix = np.divmod(np.arange(25), 5)
    shift = rng.uniform(-0.15, 0.15, (25, 2))
    shift[(ix == 0) | (ix == 4), 0] = 0.0  # boundary nodes slide along their edge
    shift[(iy == 0) | (iy == 4), 1] = 0.0
    nodes = nodes + shift
    elements = []
    for ey in range(2):
        for ex in range(2):
            elements.append([(2 * ey + i_eta) * 5 + 2 * ex + i_xi
                             for i_eta in range(3) for i_xi in range(3)])
    boundary = np.flatnonzero((ix == 0) | (ix == 4) | (iy == 0) | (iy == 4))
    return jnp.asarray(nodes), jnp.asarray(elements), boundary


def test_patch_test_constant_strain_is_exact():
    nodes, elements, boundary = _patch()
    grad_u = np.array([[1.0e-3, -0.4e-3], [0.7e-3, -0.2e-3]])  # du_i/dx_j
    u_exact = (np.asarray(nodes) @ grad_u.T + np.array([2e-4, -1e-4])).ravel()
    k = jax.jit(assemble)(nodes, elements, E_PTFE, NU_PTFE)
    fixed = np.stack([2 * boundary, 2 * boundary + 1], axis=-1).ravel()
    u = solve_prescribed(k, fixed, jnp.asarray(u_exact[fixed]))
    assert np.max(np.abs(u - u_exact)) < 1e-10 * np.max(np.abs(u_exact))
    eps = np.array([grad_u[0, 0], grad_u[1, 1], grad_u[0, 1] + grad_u[1, 0]])
    sigma = np.asarray(plane_strain_matrix(E_PTFE, NU_PTFE)) @ eps
    s = jax.jit(stresses)(nodes, elements, u, E_PTFE, NU_PTFE)
    assert np.max(np.abs(s - sigma)) < 1e-10 * np.max(np.abs(sigma))


def test_ring_condensation_equals_dense_schur_complement():
    depth = 1e-4 * (1.0 + np.sin(np.arange(16) * 2 * np.pi / 16))  # worn, 0.2 mm peak
    mesh = ring_mesh(0.01, 0.014, 16, 3, depth)
    s = eqx.filter_jit(inner_stiffness)(mesh, E_PTFE, NU_PTFE)
    k = jax.jit(assemble)(mesh.nodes, mesh.elements, E_PTFE, NU_PTFE)
    m, free = 2 * 16, 2 * 16 * 2 * 3  # inner dofs; dofs off the fixed outer ring
    kf = k[:free, :free]
    dense = kf[:m, :m] - kf[:m, m:] @ jnp.linalg.solve(kf[m:, m:], kf[m:, :m])
    assert np.max(np.abs(s - dense)) < 1e-10 * np.max(np.abs(dense))


def _lame_inner_displacement(a, b, e, nu, p):
    """Plane strain, u = A r + B / r, u(b) = 0, sigma_rr(a) = -p:
    sigma_rr = 2 (lam + mu) A - 2 mu B / r^2 and B = -A b^2 give
    u(a) = p (b^2 - a^2) / a / (2 (lam + mu) + 2 mu b^2 / a^2)."""
    lam = e * nu / ((1 + nu) * (1 - 2 * nu))
    mu = e / (2 * (1 + nu))
    return p * (b * b - a * a) / a / (2 * (lam + mu) + 2 * mu * b * b / (a * a))


def test_pressurised_ring_converges_to_lame():
    a, b, p = 0.01, 0.02, 1e6
    exact = _lame_inner_displacement(a, b, E_PTFE, NU_PTFE, p)
    errors = []

    @eqx.filter_jit
    def inner_displacement(mesh):
        return inner_compliance(mesh, E_PTFE, NU_PTFE) @ (p * tributary_lengths(mesh))

    for n_theta, n_r in [(16, 1), (32, 2), (64, 4)]:
        u = inner_displacement(ring_mesh(a, b, n_theta, n_r))
        errors.append(np.max(np.abs(u - exact)) / exact)
    # measured: 6.5e-3, 6.7e-4, 5.1e-5 (max over the inner nodes)
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[-1] < 1e-4
    assert np.all(rates > 3.0), (errors, rates)  # measured 3.3, 3.7


def _winkler(force, clearance, pin_radius, length, k):
    """Elastic-foundation pin contact, p = k (e cos t - c) on |t| < alpha,
    cos alpha = c / e, F = k R L e (alpha - sin alpha cos alpha): (alpha, e, p_max)."""
    def res(al):
        return (k * pin_radius * length * clearance / np.cos(al) * (al - np.sin(al) * np.cos(al))
                - force)
    al = brentq(res, 1e-9, np.pi / 2 - 1e-12)
    e = clearance / np.cos(al)
    return al, e, k * (e - clearance)


def _check_solution(sol, force, rtol_resultant=1e-8):
    f, g = np.asarray(sol.nodal_force), np.asarray(sol.gap)
    f_max, g_scale = f.max(), np.abs(g).max()
    assert np.max(np.abs(np.asarray(sol.resultant) - force)) < rtol_resultant * np.hypot(*force)
    assert f.min() > -1e-10 * f_max
    assert g.min() > -1e-10 * g_scale
    assert np.max(np.abs(f * g)) < 1e-10 * f_max * g_scale


def test_thin_wall_contact_approaches_winkler():
    """Wall / radius 0.05, contact width ~ 20 x wall: the ring is a thin layer on
    a rigid backing, whose limit is the Winkler foundation with the constrained
    modulus k = E (1 - nu) / ((1 + nu)(1 - 2 nu)) / (b - a)."""
    a, b, c, length, force = 0.01, 0.0105, 20e-6, 0.01, 2000.0
    prob = RingContact.build(ring_mesh(a, b, 96, 2), E_PTFE, NU_PTFE, c, length)
    sol = prob.solve_force(jnp.array([force, 0.0]))
    _check_solution(sol, [force, 0.0])
    k = E_PTFE * (1 - NU_PTFE) / ((1 + NU_PTFE) * (1 - 2 * NU_PTFE)) / (b - a)
    alpha, e, p_max = _winkler(force, c, a - c, length, k)
    # measured: p_max 19.255 vs 19.250 MPa, e 30.34 vs 30.28 um, half-angle 50.6 vs 48.7 deg
    assert abs(float(sol.peak_pressure) / p_max - 1) < 2e-3
    assert abs(float(sol.offset[0]) / e - 1) < 5e-3
    assert abs(float(sol.offset[1])) < 1e-12
    assert abs(float(sol.contact_arc) / 2 - alpha) <= 2 * np.pi / 96  # one node spacing


def test_thick_wall_contact_mesh_converged():
    """a = 10 mm, b = 15 mm: the contact at n_theta = 96, n_r = 4 against the
    same problem on a mesh refined twice in each direction."""
    a, b, c, length, force = 0.01, 0.015, 20e-6, 0.01, jnp.array([2000.0, 0.0])
    coarse = RingContact.build(
        ring_mesh(a, b, 96, 4), E_PTFE, NU_PTFE, c, length).solve_force(force)
    fine = RingContact.build(ring_mesh(a, b, 192, 8), E_PTFE, NU_PTFE, c, length).solve_force(force)
    for sol in (coarse, fine):
        _check_solution(sol, np.asarray(force))
    # measured (96, 4) vs (192, 8): offset 94.693 vs 94.694 um (1.3e-5), peak pressure
    # 13.674 vs 13.671 MPa (2.3e-4), half-angle 76.9 vs 75.9 deg (node spacings 3.75, 1.9)
    assert abs(float(coarse.offset[0]) / float(fine.offset[0]) - 1) < 5e-5
    assert abs(float(coarse.peak_pressure) / float(fine.peak_pressure) - 1) < 1e-3
    assert abs(float(coarse.contact_arc - fine.contact_arc)) <= 2 * 2 * np.pi / 96


def test_worn_ring_oblique_force_complementarity_and_offset_roundtrip():
    n = 64
    th = 2 * np.pi * np.arange(n) / n
    depth = 30e-6 * np.exp(-((th - 0.6) / 0.4) ** 2)  # a worn pocket at 34 deg
    prob = RingContact.build(ring_mesh(0.01, 0.014, n, 3, depth), E_PTFE, NU_PTFE, 15e-6, 0.008)
    force = np.array([400.0, 700.0])
    sol = prob.solve_force(jnp.asarray(force))
    _check_solution(sol, force)
    again = prob.solve_offset(sol.offset)  # given-offset problem at the solved offset
    assert np.max(np.abs(again.nodal_force - sol.nodal_force)) < 1e-8 * float(sol.nodal_force.max())
    # the pin sits in the pocket: contact centred within the worn zone
    centre = np.angle(np.sum(np.asarray(sol.nodal_force) * np.exp(1j * th)))
    assert abs(centre - np.arctan2(force[1], force[0])) < 0.2


def test_gradients_match_central_differences():
    n, a, b, nu, length = 32, 0.01, 0.015, NU_PTFE, 0.01
    th = 2 * np.pi * np.arange(n) / n
    depth0 = 5e-6 * np.exp(-((th - 0.2) / 0.5) ** 2)

    def outputs(q):
        force, e, c, dk = q
        depth = jnp.asarray(depth0).at[2].add(dk)
        prob = RingContact.build(ring_mesh(a, b, n, 2, depth), e, nu, c, length)
        sol = prob.solve_force(force * jnp.array([np.cos(0.2), np.sin(0.2)]))
        return jnp.array([sol.peak_pressure, sol.offset[0], sol.offset[1]])

    q0 = jnp.array([2000.0, E_PTFE, 20e-6, 0.0])
    f = jax.jit(outputs)
    jf = jax.jit(jax.jacfwd(outputs))(q0)
    jr = jax.jit(jax.jacrev(outputs))(q0)
    assert np.max(np.abs(jr - jf)) <= 1e-12 * np.max(np.abs(jf))
    for i, h in enumerate([1e-3, 1e3, 1e-11, 1e-11]):  # steps ~1e-6 relative (depth: 1e-6 c)
        dq = jnp.zeros(4).at[i].set(h)
        fd = (f(q0 + dq) - f(q0 - dq)) / (2 * h)
        np.testing.assert_allclose(jf[:, i], fd, rtol=1e-5)  # measured <= 3e-6


def test_solver_failure_raises_solver_error():
    prob = RingContact.build(ring_mesh(0.01, 0.014, 16, 1), E_PTFE, NU_PTFE, 20e-6, 0.01)
    with pytest.raises(SolverError, match="did not converge"):  # tol 0: stops at the step limit
        prob.solve_force(jnp.array([100.0, 0.0]), tol=0.0)
    sol = jax.jit(lambda p: p.solve_force(jnp.array([100.0, 0.0]), tol=0.0))(prob)
    with pytest.raises(SolverError, match="did not converge"):  # under jit: checked after
        sol.raise_if_failed()


@pytest.mark.parametrize("kwargs, match", [
    (dict(n_theta=6), "n_theta"),
    (dict(n_theta=17), "n_theta"),
    (dict(n_r=0), "n_r"),
    (dict(b=0.01), "outer radius b"),
    (dict(b=0.009), "outer radius b"),
    (dict(a=float("nan")), "inner radius a"),
    (dict(depth=np.full(16, 0.005)), "pierces the wall"),
    (dict(depth=np.full(16, 0.0038)), "too thin"),
    (dict(depth=-1e-6 * np.ones(16)), "wear depth must be >= 0"),
    (dict(depth=np.full(16, np.inf)), "wear depth"),
    (dict(depth=np.zeros(15)), "one value per inner-surface node"),
])
def test_bad_mesh_input(kwargs, match):
    args = dict(a=0.01, b=0.014, n_theta=16, n_r=2, depth=None) | kwargs
    with pytest.raises(InputError, match=match):
        ring_mesh(args["a"], args["b"], args["n_theta"], args["n_r"], args["depth"])


def test_bad_contact_input():
    mesh = ring_mesh(0.01, 0.014, 16, 1)
    with pytest.raises(InputError, match="clearance"):
        RingContact.build(mesh, E_PTFE, NU_PTFE, -1e-6, 0.01)
    with pytest.raises(InputError, match="Poisson"):
        RingContact.build(mesh, E_PTFE, 0.5, 1e-5, 0.01)
    with pytest.raises(InputError, match="axial length"):
        RingContact.build(mesh, E_PTFE, NU_PTFE, 1e-5, 0.0)
    prob = RingContact.build(mesh, E_PTFE, NU_PTFE, 1e-5, 0.01)
    with pytest.raises(InputError, match="nonzero"):
        prob.solve_force(jnp.zeros(2))
    with pytest.raises(InputError, match="2-vector"):
        prob.solve_force(jnp.ones(3))
    with pytest.raises(InputError, match="below the pin radius"):
        prob.solve_offset(jnp.array([0.02, 0.0]))
