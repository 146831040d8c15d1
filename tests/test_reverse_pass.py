"""The quasi-static wear integration differentiated in reverse mode (one pass
for a scalar's gradient: a sampler's log posterior, a design objective):
the same derivative as forward mode and as central differences, for the dry
and the lubricated joint; and of each cycle the pass keeps only the pin
offsets, recomputing the rest, so that it stores no (samples x nodes) array
per step of the integration."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.extend
import jax.numpy as jnp
import numpy as np
import pytest

from diffwear.contact import MixedLubrication, default_film
from diffwear.models import QuasiStatic
from diffwear.studies import rig_21400
from diffwear.wear import worn_volume

JOINT = "crank_rod"
CYCLES = 2_000.0
SAMPLES = 60   # load samples: not the node count, so their arrays are told apart


def _rig(n_theta: int = 36):
    _, mech, y0 = rig_21400._setup(n_theta=n_theta)
    return mech, y0


def _volume(model: QuasiStatic, mech, y0):
    """(log k factor, log k_f factor) -> the worn volume [mm^3] after `CYCLES`."""
    el = mech.element(JOINT)

    def volume(x):
        m = eqx.tree_at(lambda m: (m.element(JOINT).wear.coefficient,
                                   m.element(JOINT).law.stiffness), mech,
                        (el.wear.coefficient * jnp.exp(x[0]), el.law.stiffness * jnp.exp(x[1])))
        sol = model.solve(m, (JOINT,), y0, period=2.0, cycles=CYCLES)
        return 1e9 * worn_volume(sol.depth[0], el.bushing_radius, el.law.depth)

    return volume


def _scan_outputs(jaxpr) -> list[tuple]:
    """Shapes of every scan's outputs in ``jaxpr``, nested ones included."""
    shapes = []
    for eqn in jaxpr.eqns:
        if eqn.primitive.name == "scan":
            shapes += [tuple(v.aval.shape) for v in eqn.outvars]
        for sub in jax.extend.core.jaxprs_in_params(eqn.params):
            shapes += _scan_outputs(sub)
    return shapes


def test_reverse_mode_equals_forward_mode_and_central_differences():
    """The worn volume's gradient in the wear coefficient and the foundation
    stiffness: jax.grad against jax.jacfwd within 1e-10, and against central
    differences (step 1e-5 in the logarithms) within 1e-6."""
    mech, y0 = _rig()
    volume = _volume(QuasiStatic(steps=8, samples=SAMPLES), mech, y0)
    x = jnp.zeros(2)
    rev = np.asarray(jax.jit(jax.grad(volume))(x))
    fwd = np.asarray(jax.jit(jax.jacfwd(volume))(x))
    np.testing.assert_allclose(rev, fwd, rtol=1e-10)
    f = jax.jit(volume)
    h = 1e-5
    fd = np.array([(float(f(x.at[i].set(h))) - float(f(x.at[i].set(-h)))) / (2 * h)
                   for i in range(2)])
    np.testing.assert_allclose(rev, fd, rtol=1e-6)
    # Archard: the volume rises with k (nearly in proportion) and barely with k_f
    assert 0.9 * float(f(x)) < rev[0] < 1.1 * float(f(x))
    assert abs(rev[1]) < 0.1 * rev[0]


def test_the_reverse_pass_keeps_no_samples_by_nodes_array_per_step():
    """The forward scan of the reverse pass stacks, per step, what the
    backward one reads: the pin offsets (steps x samples x 2) and the profile
    (steps x nodes), never an array over the cycle's samples and the bushing's
    nodes (steps x samples x nodes: the pressures, contact indicators and
    their derivatives, about thirty of them before they were recomputed)."""
    n, steps = 36, 8
    mech, y0 = _rig(n)
    volume = _volume(QuasiStatic(steps=steps, samples=SAMPLES), mech, y0)
    jaxpr = jax.make_jaxpr(lambda x: jax.vjp(volume, x)[1](jnp.ones(())))(jnp.zeros(2)).jaxpr
    shapes = _scan_outputs(jaxpr)
    stacked = [s for s in shapes if len(s) >= 3 and s[1:3] == (SAMPLES, n)]
    assert stacked == []
    # the offsets themselves are kept: the solves are not run again
    assert any(len(s) == 3 and s[1:] == (SAMPLES, 2) for s in shapes)


@pytest.mark.extended
def test_the_lubricated_joint_reverse_mode_equals_forward_mode():
    """The lubricated rig (the film a file gets, its orbit with the squeeze
    film): the worn volume's derivative in the viscosity, jax.grad against
    jax.jvp within 1e-9."""
    mech, y0 = _rig()
    el = mech.element(JOINT)
    c = el.bushing_radius - el.pin_radius
    eps_max = MixedLubrication.saturation(0.4e-6, c)
    model = QuasiStatic(steps=4, samples=SAMPLES)

    def volume(log_mu):
        film = default_film(1e-2 * jnp.exp(log_mu), el.law.depth, c, el.pin_radius, eps_max)
        m = eqx.tree_at(lambda m: m.element(JOINT).law, mech,
                        MixedLubrication(film, el.law, 0.4e-6))
        sol = model.solve(m, (JOINT,), y0, period=2.0, cycles=CYCLES)
        return 1e9 * worn_volume(sol.depth[0], el.bushing_radius, el.law.depth)

    x = jnp.zeros(())
    rev = float(jax.jit(jax.grad(volume))(x))
    _, fwd = jax.jit(lambda x: jax.jvp(volume, (x,), (jnp.ones(()),)))(x)
    assert np.isfinite(rev) and rev < 0.0   # a thicker oil wears less
    assert rev == pytest.approx(float(fwd), rel=1e-9)
