"""A crank-rocker four-bar built from the core API, checked against closed forms.

The linkage (`linkages.four_bar`) is only bodies, revolute joints, a driver and
gravity; the references below are independent of diffwear: the rocker pin B as
the intersection of the circle of radius b about the crank pin A with the circle
of radius c about the rocker pivot O4, and Freudenstein's equation.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from linkages import COUPLER, CRANK, CRANK_SPEED, GROUND_LINK, ROCKER, four_bar

from diffwear.dynamics import (
    along_trajectory,
    consistent_state,
    driver_torque,
    kinematic_analysis,
    simulate,
)

T_END = 1.0  # s: one crank revolution at 2 pi rad/s
TS = jnp.linspace(0.0, T_END, 201)


def wrap(angle):
    """Angle difference folded into (-pi, pi]."""
    return np.angle(np.exp(1j * np.asarray(angle)))


def closed_form(theta2, a=CRANK, b=COUPLER, c=ROCKER, d=GROUND_LINK):
    """(coupler angle theta3, rocker angle theta4) of the open assembly by circle
    intersection.  B lies left of the directed line A -> O4 for every crank angle:
    leaving that side needs |A O4| = b + c or |b - c|, impossible for |A O4| in
    [d - a, d + a] = [0.3, 0.5] m."""
    A = a * np.stack([np.cos(theta2), np.sin(theta2)], axis=-1)
    D = np.array([d, 0.0]) - A
    r = np.linalg.norm(D, axis=-1)
    beta = np.arccos((b**2 + r**2 - c**2) / (2 * b * r))  # angle O4-A-B, law of cosines
    theta3 = np.arctan2(D[:, 1], D[:, 0]) + beta
    B = A + b * np.stack([np.cos(theta3), np.sin(theta3)], axis=-1)
    theta4 = np.arctan2(B[:, 1], B[:, 0] - d)
    return theta3, theta4


@pytest.fixture(scope="module")
def kinematics():
    mech, q_guess = four_bar()
    y0 = consistent_state(mech, q_guess)
    return mech, y0, kinematic_analysis(mech, TS, y0[: mech.n_coords])


@pytest.fixture(scope="module")
def dynamics(kinematics):
    mech, y0, _ = kinematics
    traj = simulate(mech, y0, T_END, ts=TS).raise_if_failed("four-bar")
    qdd, lam, _ = jax.jit(along_trajectory)(mech, traj.ts, traj.ys)
    q, qd, _ = jax.vmap(mech.split)(traj.ys)
    return traj, q, qd, qdd, lam


def test_kinematics_match_circle_intersection(kinematics):
    _, _, (q, qd, _) = kinematics
    q, qd = np.asarray(q), np.asarray(qd)
    theta2 = CRANK_SPEED * np.asarray(TS)
    theta3, theta4 = closed_form(theta2)
    np.testing.assert_allclose(wrap(q[:, 2] - theta2), 0.0, atol=1e-12)
    np.testing.assert_allclose(wrap(q[:, 5] - theta3), 0.0, atol=1e-10)
    np.testing.assert_allclose(wrap(q[:, 8] - theta4), 0.0, atol=1e-10)
    assert np.ptp(theta4) > 0.5  # rad: the rocker really rocks (about 40 deg)
    # rocker COM at the link midpoint
    com = np.array([GROUND_LINK, 0.0]) + ROCKER / 2 * np.stack([np.cos(theta4), np.sin(theta4)], -1)
    np.testing.assert_allclose(q[:, 6:8], com, atol=1e-10)
    # Freudenstein: K1 cos th4 - K2 cos th2 + K3 = cos(th2 - th4)
    a, b, c, d = CRANK, COUPLER, ROCKER, GROUND_LINK
    k1, k2, k3 = d / a, d / c, (a**2 - b**2 + c**2 + d**2) / (2 * a * c)
    th2, th4 = q[:, 2], q[:, 8]
    np.testing.assert_allclose(
        k1 * np.cos(th4) - k2 * np.cos(th2) + k3, np.cos(th2 - th4), atol=1e-9
    )
    # rocker speed from the velocity loop a w2 e2' + b w3 e3' = c w4 e4' (dotted with e3)
    w4 = a * CRANK_SPEED * np.sin(theta3 - theta2) / (c * np.sin(theta3 - theta4))
    np.testing.assert_allclose(qd[:, 8], w4, atol=1e-9)


def test_dynamics_match_kinematics(kinematics, dynamics):
    _, _, (qk, qdk, qddk) = kinematics
    traj, q, qd, qdd, _ = dynamics
    assert int(traj.num_steps) > 10
    # Tsit5 at rtol = atol = 1e-8 with Baumgarte 250 1/s; measured errors are about
    # 3e-11 m(rad), 1e-8 m/s and 3e-6 m/s^2 (peak acceleration about 20 m/s^2).
    np.testing.assert_allclose(q, qk, atol=1e-8)
    np.testing.assert_allclose(qd, qdk, atol=1e-6)
    np.testing.assert_allclose(qdd, qddk, atol=1e-5 * np.max(np.abs(qddk)))


def test_driver_work_equals_energy_change(kinematics, dynamics):
    mech = kinematics[0]
    _, q, qd, _, lam = dynamics
    tau = jax.vmap(lambda qq, ll, t: driver_torque(mech, qq, ll, t, "driver"))(q, lam, TS)
    power = np.asarray(tau) * CRANK_SPEED
    ts = np.asarray(TS)
    work = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(ts))])
    energy = np.asarray(jax.vmap(mech.kinetic_energy)(qd) + jax.vmap(mech.potential_energy)(q))
    scale = np.max(np.abs(energy - energy[0]))
    assert scale > 0.1  # J: the check is not vacuous
    # the crank returns to its start after one revolution: no net work over the cycle
    assert abs(energy[-1] - energy[0]) < 1e-6 * scale
    # trapezoidal rule on 201 points: error ~ h^2/12 max|P''| T, well below 1e-3 of scale
    np.testing.assert_allclose(work, energy - energy[0], atol=1e-3 * scale)
