"""The clearance slider-crank against the ideal joint (thesis Ch. 3 and 6)."""

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from linkages import seated_rotor

from diffwear.contact import PTFE
from diffwear.dynamics import simulate
from diffwear.errors import SolverError
from diffwear.presets import clearance_slider_crank
from diffwear.studies.clearance_sweep import ideal_force, simulate_clearance

CYCLES = 2
TS = jnp.linspace(0.0, 2.0 * CYCLES, 401 * CYCLES)
KEEP = np.asarray(TS) >= 2.0  # the first cycle holds the start-up transient


@pytest.fixture(scope="module")
def ideal():
    return ideal_force(TS)[0]


def _force(law, clearance):
    mech, y0 = clearance_slider_crank(law, clearance)
    traj, hist = simulate_clearance(mech, y0, TS)
    traj.raise_if_failed(f"{law} {clearance}", mech)
    return np.asarray(hist.force_magnitude), hist


def _rel_rms(a, b):
    return np.sqrt(np.mean((a[KEEP] - b[KEEP]) ** 2) / np.mean(b[KEEP] ** 2))


@pytest.mark.parametrize("law", ["ln", "kv", "efm"])
def test_small_clearance_tracks_ideal_joint(law, ideal):
    force, _ = _force(law, 0.0005e-3)
    assert _rel_rms(force, ideal) < 0.05


@pytest.fixture(scope="module")
def ln_sweep():
    return {c: _force("ln", c) for c in (0.0005e-3, 0.05e-3, 0.5e-3, 5e-3)}


def test_peaks_grow_with_clearance(ln_sweep, ideal):
    peaks = [ln_sweep[c][0][KEEP].max() for c in sorted(ln_sweep)]
    assert peaks[-1] > 2.0 * ideal[KEEP].max()  # impacts at 5 mm
    assert peaks[-1] > peaks[-2] > peaks[0] * 1.01
    assert peaks[0] == pytest.approx(ideal[KEEP].max(), rel=0.01)


def test_contact_is_lost_only_at_large_clearance(ln_sweep):
    in_contact = {c: np.asarray(h.penetration)[KEEP] > 0 for c, (_, h) in ln_sweep.items()}
    assert in_contact[0.0005e-3].all()
    lost = 1.0 - in_contact[5e-3].mean()
    assert 0.005 < lost < 0.5  # free flight for part of the cycle


def test_contact_locus_near_0_and_pi(ln_sweep):
    _, hist = ln_sweep[0.5e-3]
    theta = np.asarray(hist.contact_angle)[KEEP & (np.asarray(hist.penetration) > 0)]
    near_0 = np.mean(np.cos(theta) > np.cos(np.pi / 6))
    near_pi = np.mean(np.cos(theta) < -np.cos(np.pi / 6))
    assert near_0 > 0.3 and near_pi > 0.2 and near_0 + near_pi > 0.8


def _rotor_normal_load(clearance, modulus, mu, adjoint):
    """Mean total normal load [N] in the clearance pivot of a driven, unbalanced
    10 kg rotor (gravity + centripetal load), pin seated at the start so that the
    contact never opens: a smooth, well-conditioned statistic.  Fixed steps
    (dt = 1e-4 s, below the 4e-4 s Tsit5 limit at the ~9 kHz contact mode) make
    finite differences and the derivative of the discrete solution agree."""
    from diffwear.contact import contact_history

    mech, y0 = seated_rotor(clearance, modulus, mu)
    ts = jnp.linspace(0.2, 0.4, 21)
    traj = simulate(mech, y0, 0.4, ts=ts, dt0=1e-4, stepsize_controller=diffrax.ConstantStepSize(),
                    max_steps=5000, adjoint=adjoint)
    return jnp.mean(contact_history(mech, "pivot", traj.ys).normal_load)


def test_gradients_match_finite_differences():
    x = (jnp.asarray(20e-6), jnp.asarray(0.5e9), jnp.asarray(0.13))
    fwd = jax.jit(jax.jacfwd(lambda *a: _rotor_normal_load(*a, diffrax.ForwardMode()),
                             argnums=(0, 1, 2)))(*x)
    rev = jax.jit(jax.grad(lambda *a: _rotor_normal_load(*a, diffrax.RecursiveCheckpointAdjoint()),
                           argnums=(0, 1, 2)))(*x)
    f = jax.jit(lambda *a: _rotor_normal_load(*a, diffrax.RecursiveCheckpointAdjoint()))
    for i, rel_step in enumerate((1e-3, 1e-4, 1e-4)):
        h = float(x[i]) * rel_step
        up = list(x)
        up[i] = x[i] + h
        dn = list(x)
        dn[i] = x[i] - h
        fd = (float(f(*up)) - float(f(*dn))) / (2 * h)
        assert np.isfinite(float(fwd[i])) and abs(fd) > 0
        np.testing.assert_allclose(float(fwd[i]), fd, rtol=2e-3)
        np.testing.assert_allclose(float(rev[i]), float(fwd[i]), rtol=1e-6)


def test_step_limit_is_reported_with_the_joint():
    mech, y0 = clearance_slider_crank("ln", 0.5e-3)
    traj = simulate(mech, y0, 1.0, max_steps=50)
    with pytest.raises(SolverError, match=r"crank_rod.*eccentricity"):
        traj.raise_if_failed("tiny budget", mech)


def test_two_clearance_joints_track_the_ideal_reactions():
    """A mechanism can have several clearance joints: crank-rod and rod-slider,
    both EFM at 0.0005 mm, follow the ideal joints' reactions."""
    from diffwear.contact import ClearanceJoint, CoulombFriction, contact_history, with_clearance
    from diffwear.dynamics import along_trajectory, consistent_state, reaction_wrench
    from diffwear.presets import efm_law, slider_crank

    ideal, q_guess = slider_crank()
    y_ideal = consistent_state(ideal, q_guess)
    mech = ideal
    for joint, mass in (("crank_rod", 15.0), ("rod_slider", 30.0)):
        law = efm_law(PTFE, 0.0200005, 13.31e-3, 12.8e-3, 0.8, mass)
        mech = with_clearance(mech, joint, pin_radius=0.02, bushing_radius=0.0200005, law=law,
                              friction=CoulombFriction(0.13), n_theta=90)
    assert sum(isinstance(f, ClearanceJoint) for f in mech.forces) == 2
    q, qd, _ = ideal.split(y_ideal)
    y0 = mech.join(q, qd, mech.initial_aux(q, qd))
    ts = jnp.linspace(0.5, 1.0, 51)
    ctrl = diffrax.PIDController(rtol=1e-6, atol=1e-6, pcoeff=0.3, icoeff=0.4)
    traj = jax.jit(lambda m, y: simulate(m, y, 1.0, ts=ts, stepsize_controller=ctrl))(mech, y0)
    traj.raise_if_failed("two clearance joints", mech)
    ref = simulate(ideal, y_ideal, 1.0, ts=ts).raise_if_failed()
    _, lam, _ = along_trajectory(ideal, ref.ts, ref.ys)
    for joint, bushing in (("crank_rod", "rod"), ("rod_slider", "slider")):
        f = jax.vmap(lambda qq, ll, t: reaction_wrench(ideal, qq, ll, t, joint, bushing))(
            ref.ys[:, :9], lam, ts)
        f_ideal = np.hypot(np.asarray(f[:, 0]), np.asarray(f[:, 1]))
        f_clear = np.asarray(contact_history(mech, joint, traj.ys).force_magnitude)
        rel = np.sqrt(np.mean((f_clear - f_ideal) ** 2) / np.mean(f_ideal**2))
        assert rel < 0.05, (joint, rel)
