"""Chapter 2: the ideal slider-crank, checked against independent computations."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from diffwear.dynamics import (
    Baumgarte,
    along_trajectory,
    consistent_state,
    driver_torque,
    kinematic_analysis,
    reaction_wrench,
    simulate,
)
from diffwear.mechanism import STANDARD_GRAVITY
from diffwear.presets import TABLE_2_1, slider_crank

T_END = 2.0  # s: one crank revolution at pi rad/s
TS = jnp.linspace(0.0, T_END, 401)


@pytest.fixture(scope="module")
def run():
    mech, q_guess = slider_crank()
    y0 = consistent_state(mech, q_guess)
    traj = jax.jit(lambda m, y: simulate(m, y, T_END, ts=TS))(mech, y0).raise_if_failed()
    qdd, lam, _ = along_trajectory(mech, traj.ts, traj.ys)
    q, qd, _ = jax.vmap(mech.split)(traj.ys)
    return mech, q_guess, q, qd, qdd, lam


def test_dynamic_matches_kinematic(run):
    mech, q_guess, q, qd, qdd, _ = run
    qk, qdk, qddk = kinematic_analysis(mech, TS, q_guess)
    # Crank COM (coords 0, 1): position to 1e-8 m, velocity 1e-6 m/s, acceleration 1e-4 m/s^2.
    np.testing.assert_allclose(q[:, :2], qk[:, :2], atol=1e-8)
    np.testing.assert_allclose(qd[:, :2], qdk[:, :2], atol=1e-6)
    np.testing.assert_allclose(qdd[:, :2], qddk[:, :2], atol=1e-4)
    np.testing.assert_allclose(q[:, 6], qk[:, 6], atol=1e-8)  # slider x
    # and the kinematics against the closed form (Eq. 2-9, half-lengths):
    p = TABLE_2_1
    phi1 = math.pi * np.asarray(TS)
    sin2 = -p.l1 * np.sin(phi1) / p.l2
    x_slider = 2 * p.l1 * np.cos(phi1) + 2 * p.l2 * np.sqrt(1 - sin2**2)
    np.testing.assert_allclose(qk[:, 6], x_slider, atol=1e-10)
    np.testing.assert_allclose(qdk[:, 0], -p.l1 * math.pi * np.sin(phi1), atol=1e-10)
    np.testing.assert_allclose(qddk[:, 1], -p.l1 * math.pi**2 * np.sin(phi1), atol=1e-9)


def _violation(baumgarte, rtol):
    import diffrax

    mech, q_guess = slider_crank()
    y0 = consistent_state(mech, q_guess)
    ctrl = diffrax.PIDController(rtol=rtol, atol=rtol)
    ts = jnp.linspace(0.0, 4.0, 81)
    traj = simulate(mech, y0, 4.0, ts=ts, baumgarte=baumgarte, stepsize_controller=ctrl)
    q = traj.raise_if_failed().ys[:, :9]
    return np.max(np.abs(np.asarray(jax.vmap(mech.phi)(q, ts))), axis=1)


def test_baumgarte_bounds_drift():
    stab = _violation(Baumgarte(250.0, 250.0), 1e-5)
    free = _violation(Baumgarte(0.0, 0.0), 1e-5)
    assert stab.max() < 1e-6
    # without stabilisation the drift grows: late violation >> early, and >> stabilised
    assert free[-10:].mean() > 10 * free[5:15].mean()
    assert free.max() > 100 * stab.max()


def test_reaction_equals_newton_euler(run):
    """Crank-on-rod force from the multipliers == Newton-Euler on rod and slider
    with the kinematic accelerations."""
    mech, q_guess, q, _, _, lam = run
    p, g = TABLE_2_1, STANDARD_GRAVITY
    qk, _, qddk = (np.asarray(a) for a in kinematic_analysis(mech, TS, q_guess))
    for k in range(0, len(TS), 20):
        r2, phi2 = qk[k, 3:5], qk[k, 5]
        rA = r2 + p.l2 * np.array([-np.cos(phi2), -np.sin(phi2)])  # crank end of rod
        rB = r2 + p.l2 * np.array([np.cos(phi2), np.sin(phi2)])    # slider end
        a, b = rA - r2, rB - r2
        # unknowns: F_cr (2), F_sr (2) on the rod, guide normal N, guide moment Mg
        A = np.array([
            [1, 0, 1, 0, 0, 0],
            [0, 1, 0, 1, 0, 0],
            [-a[1], a[0], -b[1], b[0], 0, 0],
            [0, 0, -1, 0, 0, 0],
            [0, 0, 0, -1, 1, 0],
            [0, 0, 0, 0, 0, 1],
        ])
        rhs = np.array([
            p.m2 * qddk[k, 3], p.m2 * qddk[k, 4] + p.m2 * g, p.inertia2 * qddk[k, 5],
            p.m3 * qddk[k, 6], p.m3 * qddk[k, 7] + p.m3 * g, p.inertia3 * qddk[k, 8],
        ])
        f_ne = np.linalg.solve(A, rhs)[:2]
        f_lam = np.asarray(reaction_wrench(mech, q[k], lam[k], TS[k], "crank_rod", "rod"))[:2]
        np.testing.assert_allclose(f_lam, f_ne, rtol=1e-5, atol=1e-3)


def test_driver_work_equals_energy_change(run):
    mech, _, q, qd, _, lam = run
    tau = jax.vmap(lambda qq, ll, t: driver_torque(mech, qq, ll, t, "driver"))(q, lam, TS)
    power = np.asarray(tau) * TABLE_2_1.omega
    ts = np.asarray(TS)
    work = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(ts))])
    energy = np.asarray(jax.vmap(mech.kinetic_energy)(qd) + jax.vmap(mech.potential_energy)(q))
    scale = np.max(np.abs(energy - energy[0]))
    assert scale > 100.0  # J: the check is not vacuous
    # trapezoidal rule on 401 points: error ~ h^2/12 * max|P''| * T, well below 1e-3 of scale
    np.testing.assert_allclose(work, energy - energy[0], atol=1e-3 * scale)


def _peak_force(m2, l1):
    p = TABLE_2_1
    params = type(p)(l1=l1, l2=p.l2, m1=p.m1, inertia1=p.inertia1, m2=m2,
                     inertia2=p.inertia2, m3=p.m3)
    mech, q_guess = slider_crank(params)
    y0 = consistent_state(mech, q_guess, check=False)
    ts = jnp.linspace(0.0, 1.0, 101)
    traj = simulate(mech, y0, 1.0, ts=ts)
    _, lam, _ = along_trajectory(mech, traj.ts, traj.ys)
    q = traj.ys[:, :9]
    f = jax.vmap(lambda qq, ll, t: reaction_wrench(mech, qq, ll, t, "crank_rod", "rod"))(q, lam, ts)
    return jnp.max(jnp.sqrt(f[:, 0] ** 2 + f[:, 1] ** 2))


def test_gradient_matches_finite_differences():
    m2, l1 = jnp.asarray(15.0), jnp.asarray(1.0)
    grad = jax.jit(jax.grad(_peak_force, argnums=(0, 1)))(m2, l1)
    f = jax.jit(_peak_force)
    h_m, h_l = 1e-4, 1e-6
    fd_m = (f(m2 + h_m, l1) - f(m2 - h_m, l1)) / (2 * h_m)
    fd_l = (f(m2, l1 + h_l) - f(m2, l1 - h_l)) / (2 * h_l)
    assert abs(float(grad[0])) > 1.0 and abs(float(grad[1])) > 1.0
    np.testing.assert_allclose(float(grad[0]), float(fd_m), rtol=1e-4)
    np.testing.assert_allclose(float(grad[1]), float(fd_l), rtol=1e-4)
