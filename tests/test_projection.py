"""Post-stabilisation (`ConstraintProjection`): the same constrained motion as
Baumgarte's stabilisation, checked against independent values (kinematic
analysis, energy conservation, a tight Baumgarte run, central differences)."""

import dataclasses

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from linkages import four_bar

from diffwear.dynamics import (
    Baumgarte,
    ConstraintProjection,
    Rodas4,
    along_trajectory,
    consistent_state,
    kinematic_analysis,
    project_to_constraints,
    reaction_wrench,
    simulate,
)
from diffwear.errors import InputError
from diffwear.mechanism import Mechanism
from diffwear.presets import TABLE_2_1, slider_crank

UNSTABILISED = Baumgarte(0.0, 0.0)
TS = jnp.linspace(0.0, 2.0, 101)  # one revolution of the Table 2-1 crank


def _controller(tol):
    return diffrax.PIDController(rtol=tol, atol=tol, pcoeff=0.3, icoeff=0.4)


def _projected(mech, y0, t1, tol, ts=None, solver=None, adjoint=None):
    solver = ConstraintProjection(diffrax.Tsit5() if solver is None else solver)
    return simulate(mech, y0, t1, ts=ts, solver=solver, baumgarte=UNSTABILISED,
                    stepsize_controller=_controller(tol), adjoint=adjoint)


@pytest.fixture(scope="module")
def slider():
    mech, q_guess = slider_crank(TABLE_2_1)
    return mech, q_guess, consistent_state(mech, q_guess)


def test_projection_returns_a_state_onto_the_constraints(slider):
    """A consistent state is left as it is; one displaced by ~1e-4 off the
    constraints comes back to |Phi| ~ (1e-4)^2 (one Gauss-Newton step), with
    Phi_dot = 0 exactly (linear in qd), by a move that is M-orthogonal to the
    constraints' tangent space (M dq in the row space of Phi_q)."""
    mech, _, y0 = slider
    t = jnp.asarray(0.0)  # y0 is consistent at the start time
    np.testing.assert_allclose(project_to_constraints(mech, y0, t), y0, atol=1e-14)
    off = y0 + 1e-4 * jnp.sin(jnp.arange(y0.size) + 1.0)
    y1 = project_to_constraints(mech, off, t)
    q1, qd1, _ = mech.split(y1)
    q0, _, _ = mech.split(off)
    assert float(jnp.abs(mech.phi(q0, t)).max()) > 1e-5
    assert float(jnp.abs(mech.phi(q1, t)).max()) < 1e-7
    assert float(jnp.abs(mech.phi_dot(q1, qd1, t)).max()) < 1e-12
    jac = np.asarray(mech.phi_q(q0, t))
    move = np.asarray(mech.mass_diagonal() * (q1 - q0))
    coeffs, *_ = np.linalg.lstsq(jac.T, move, rcond=None)
    np.testing.assert_allclose(jac.T @ coeffs, move, atol=1e-10 * np.abs(move).max())


def test_driven_slider_crank_is_its_kinematics_in_far_fewer_steps(slider):
    """The fully driven slider-crank's motion is its kinematic analysis
    (Newton on Phi = 0 at each time, independent of any integrator).  The
    projected, unstabilised route follows it at rtol 1e-8 in 68 steps, where
    the thesis's Baumgarte gains (250 1/s) take 2,276: their modes set the
    step.  Its crank-rod reaction agrees with a Baumgarte run at rtol 1e-12."""
    mech, q_guess, y0 = slider
    run = jax.jit(lambda m, y: _projected(m, y, 2.0, 1e-8, ts=TS))(mech, y0)
    run.raise_if_failed("projected slider-crank")
    qk, qdk, _ = kinematic_analysis(mech, TS, q_guess)
    q, qd, _ = jax.vmap(mech.split)(run.ys)
    np.testing.assert_allclose(q, qk, atol=2e-8)
    np.testing.assert_allclose(qd, qdk, atol=2e-7)
    baum = jax.jit(lambda m, y: simulate(m, y, 2.0, ts=TS,
                                         stepsize_controller=_controller(1e-8)))(mech, y0)
    assert int(run.num_steps) * 10 < int(baum.num_steps)

    def reaction(traj, gains):
        _, lam, _ = along_trajectory(mech, traj.ts, traj.ys, gains)
        qq, _, _ = jax.vmap(mech.split)(traj.ys)
        return jax.vmap(lambda a, b, t: reaction_wrench(mech, a, b, t, "crank_rod", "rod"))(
            qq, lam, traj.ts)

    tight = jax.jit(lambda m, y: simulate(m, y, 2.0, ts=TS,
                                          stepsize_controller=_controller(1e-12)))(mech, y0)
    f_ref = reaction(tight, Baumgarte())
    peak = float(jnp.abs(f_ref).max())
    assert float(jnp.abs(reaction(run, UNSTABILISED) - f_ref).max()) < 1e-6 * peak


def _free_four_bar():
    """The test four-bar with its driver removed: one free degree of freedom
    swinging under gravity, so its energy is conserved."""
    mech, q_guess = four_bar()
    free = Mechanism(mech.bodies, tuple(c for c in mech.constraints if c.name != "driver"),
                     mech.forces)
    qd_guess = jnp.zeros(9).at[2].set(6.0)  # the crank swung at ~6 rad/s
    return free, consistent_state(free, q_guess, qd_guess)


def test_free_linkage_keeps_constraints_and_energy_over_many_swings():
    """A free four-bar under gravity for 10 s: with the projection, the
    constraints hold to round-off at the end and the energy (closed form:
    constant) to 1e-7; unstabilised and unprojected, the drift is orders of
    magnitude larger at the same tolerance."""
    mech, y0 = _free_four_bar()

    def energy(y):
        q, qd, _ = mech.split(y)
        return mech.kinetic_energy(qd) + mech.potential_energy(q)

    def violation(y, t):
        q, qd, _ = mech.split(y)
        return max(float(jnp.abs(mech.phi(q, t)).max()),
                   float(jnp.abs(mech.phi_dot(q, qd, t)).max()))

    proj = jax.jit(lambda m, y: _projected(m, y, 10.0, 1e-8))(mech, y0)
    proj.raise_if_failed("free four-bar, projected")
    plain = jax.jit(lambda m, y: simulate(m, y, 10.0, baumgarte=UNSTABILISED,
                                          stepsize_controller=_controller(1e-8)))(mech, y0)
    e0 = float(energy(y0))
    assert abs(float(energy(proj.y_final)) - e0) < 1e-7 * abs(e0)
    assert violation(proj.y_final, 10.0) < 1e-12
    assert violation(plain.y_final, 10.0) > 1e3 * violation(proj.y_final, 10.0)


def test_gradient_through_the_projected_route_matches_central_differences(slider):
    """d(slider position at 0.6 s)/d(rod half-length) through the projected
    route (assembly included), forward mode, against central differences of
    the same route."""

    def slider_x(l2):
        mech, q_guess = slider_crank(dataclasses.replace(TABLE_2_1, l2=l2))
        y = consistent_state(mech, q_guess, check=False)
        return _projected(mech, y, 0.6, 1e-9, adjoint=diffrax.ForwardMode()).y_final[6]

    l2 = jnp.asarray(TABLE_2_1.l2)
    f = jax.jit(slider_x)
    grad = float(jax.jit(jax.jacfwd(slider_x))(l2))
    h = 1e-5
    fd = (float(f(l2 + h)) - float(f(l2 - h))) / (2 * h)
    assert abs(grad) > 0.1
    assert grad == pytest.approx(fd, rel=1e-5)


def test_a_rosenbrock_solver_inside_is_configured_as_simulate_does(slider):
    """`simulate` gives a wrapped Rosenbrock solver its Jacobian structure:
    Rodas4 inside the projection follows the kinematics too."""
    mech, q_guess, y0 = slider
    ts = TS[:26]  # a quarter revolution
    run = jax.jit(lambda m, y: _projected(m, y, ts[-1], 1e-8, ts=ts, solver=Rodas4()))(mech, y0)
    run.raise_if_failed("projected Rodas4")
    qk, _, _ = kinematic_analysis(mech, ts, q_guess)
    np.testing.assert_allclose(jax.vmap(mech.split)(run.ys)[0], qk, atol=1e-7)


def test_a_solver_without_an_error_estimate_is_refused():
    with pytest.raises(InputError, match="error estimate"):
        ConstraintProjection(diffrax.Euler())
