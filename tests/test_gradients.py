"""Reverse-mode gradients through `simulate` under jit equal forward mode.

Regression test: with constant t0/t1 under an outer jit, XLA folded diffrax's
step-time formula differently in the forward loop and in the checkpointed
recomputation, moving a save time into another step and giving a gradient
off by 2x here (found with jax 0.10.2 / diffrax 0.7.2; fixed in `simulate`
with an optimization barrier on t0, t1).
"""

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from diffwear.dynamics import simulate
from diffwear.mechanism import Body, LinearSpring, Mechanism


def _displacement(stiffness, adjoint):
    spring = LinearSpring("s", "mass", (0.0, 0.0), "ground", (0.0, 0.0), stiffness, 0.0,
                          damping=0.5)
    mech = Mechanism((Body("mass", 1.0, 1.0),), (), (spring,))
    y0 = mech.join(jnp.array([0.1, 0.0, 0.0]), jnp.zeros(3))
    ts = jnp.linspace(0.2, 0.4, 21)  # ts[2] lies on a step boundary to 1 ulp
    traj = simulate(mech, y0, 0.4, ts=ts, dt0=1e-4, adjoint=adjoint, max_steps=5000,
                    stepsize_controller=diffrax.ConstantStepSize())
    return traj.ys[2, 0]


def test_jitted_reverse_mode_equals_forward_mode():
    k = jnp.asarray(400.0)
    rev = jax.jit(jax.grad(lambda s: _displacement(s, diffrax.RecursiveCheckpointAdjoint())))(k)
    fwd = jax.jit(jax.jacfwd(lambda s: _displacement(s, diffrax.ForwardMode())))(k)
    f = jax.jit(lambda s: _displacement(s, diffrax.RecursiveCheckpointAdjoint()))
    fd = (float(f(k + 1e-3)) - float(f(k - 1e-3))) / 2e-3
    np.testing.assert_allclose(float(fwd), fd, rtol=1e-6)
    np.testing.assert_allclose(float(rev), float(fwd), rtol=1e-9)


def test_schur_solve_derivative_rule_equals_autodiff():
    """`equations.schur_solve` has a hand-written JVP (one back substitution with
    the primal's Cholesky factor per tangent); it must equal autodiff of the plain
    factorise-and-solve, forward and reverse, w.r.t. every input."""
    from diffwear.dynamics import equations

    keys = jax.random.split(jax.random.PRNGKey(0), 4)
    jac = jax.random.normal(keys[0], (7, 9))
    minv = 1.0 + jax.random.uniform(keys[1], (9,))
    force, rhs = jax.random.normal(keys[2], (9,)), jax.random.normal(keys[3], (7,))

    def flat(solve):
        return lambda *a: jnp.concatenate(solve(*a)[:2])

    args = (jac, minv, force, rhs)
    for i in range(4):
        want = jax.jacfwd(flat(equations._schur_solve), argnums=i)(*args)
        for diff in (jax.jacfwd, jax.jacrev):
            got = diff(flat(equations.schur_solve), argnums=i)(*args)
            np.testing.assert_allclose(got, want, rtol=0,
                                       atol=1e-12 * float(jnp.max(jnp.abs(want))))


def test_gradcheck_verdicts():
    """ok on a smooth function; mismatch on a wrong derivative rule; rough on
    a function with fine-scale ripples (its differences disagree between
    steps); nan where autodiff is NaN."""
    from diffwear import gradcheck

    def f(x):
        return jnp.stack([jnp.sin(x[0]) * x[1], x[0] ** 3])

    smooth = gradcheck(f, jnp.array([0.7, 1.3]), rtol=1e-6)
    assert smooth.ok, smooth.message
    np.testing.assert_allclose(smooth.autodiff, [[np.cos(0.7) * 1.3, np.sin(0.7)],
                                                 [3 * 0.7**2, 0.0]], rtol=1e-12)
    np.testing.assert_allclose(smooth.value, [np.sin(0.7) * 1.3, 0.7**3], rtol=1e-15)
    eager = gradcheck(f, jnp.array([0.7, 1.3]), rtol=1e-6, jit=False)
    np.testing.assert_allclose(eager.autodiff, smooth.autodiff, rtol=1e-15)

    @jax.custom_jvp
    def wrong(x):
        return x**2

    wrong.defjvp(lambda p, t: (p[0] ** 2, 3.0 * p[0] * t[0]))
    assert gradcheck(wrong, 1.5).verdict == "mismatch"
    ripple = gradcheck(lambda x: x + 1e-3 * jnp.sin(1e5 * x), 0.3, rtol=1e-3)
    assert ripple.verdict == "rough", ripple.message
    assert gradcheck(lambda x: jnp.sqrt(x), 0.0).verdict == "nan"


@pytest.mark.slow
def test_dynamic_gradient_through_contact_loss_is_finite():
    """The mean joint force of a 1 s clearance-joint run had NaN gradients at
    0.25 and 0.30 mm (|force| = 0 exactly in free flight, differentiated
    through a bare sqrt).  Finite now; the derivative itself is not a
    meaningful slope there (gradcheck says "rough")."""
    from diffwear.contact import contact_history
    from diffwear.presets import clearance_slider_crank

    def mean_force(clearance):
        mech, y0 = clearance_slider_crank("efm", clearance, check=False)
        traj = simulate(mech, y0, 1.0, ts=jnp.linspace(0.5, 1.0, 51))
        return contact_history(mech, "crank_rod", traj.ys).force_magnitude.mean()

    grad = jax.jit(jax.grad(mean_force))
    for c in (0.25e-3, 0.30e-3):
        assert np.isfinite(float(grad(jnp.asarray(c))))
