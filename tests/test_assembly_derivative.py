"""The derivative of an assembled configuration: the implicit function
theorem's dq/dp = -J^-1 dPhi/dp, checked against central differences in
forward and reverse mode, and a failure downstream reported as a NaN
derivative, never as an error that stops the program."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from linkages import four_bar

jax.config.update("jax_enable_x64", True)

from diffwear.dynamics import consistent_state  # noqa: E402
from diffwear.dynamics.kinematics import assemble  # noqa: E402

D = 0.3   # the ground link's length [m] (the linkages' four-bar)


def _guess():
    mech, q_guess = four_bar(d=D)
    return np.asarray(consistent_state(mech, q_guess)[: mech.n_coords])


def _rocker_angle(d, guess):
    mech, _ = four_bar(d=d)
    q, _ = assemble(mech, guess)
    return q[8]   # the rocker's angle


def test_assembly_derivative_is_the_implicit_one_in_both_modes():
    guess = _guess()
    h = 1e-6
    fd = (_rocker_angle(D + h, guess) - _rocker_angle(D - h, guess)) / (2 * h)
    reverse = jax.grad(_rocker_angle)(jnp.asarray(D), guess)
    _, forward = jax.jvp(lambda d: _rocker_angle(d, guess), (jnp.asarray(D),),
                         (jnp.asarray(1.0),))
    assert abs(float(fd)) > 0.1   # the rocker turns with the ground link
    assert float(reverse) == pytest.approx(float(fd), rel=1e-7)
    assert float(forward) == pytest.approx(float(fd), rel=1e-7)


def test_assembly_value_is_the_root_itself():
    """The derivative rule leaves the value alone: the same root jitted or
    not, Phi = 0 there."""
    guess = _guess()
    mech, _ = four_bar(d=D)
    q, ok = jax.jit(assemble)(mech, guess)
    assert bool(ok)
    np.testing.assert_array_equal(np.asarray(q), np.asarray(assemble(mech, guess)[0]))
    np.testing.assert_allclose(np.asarray(mech.phi(q, 0.0)), 0.0, atol=1e-12)


def test_a_nan_flowing_back_gives_a_nan_derivative_not_an_error():
    """A model downstream that fails (here: a NaN times the configuration)
    sends a NaN back; the derivative says so, and the program goes on."""
    guess = _guess()
    grad = jax.jit(jax.grad(lambda d: jnp.nan * _rocker_angle(d, guess)))(jnp.asarray(D))
    assert np.isnan(float(grad))
