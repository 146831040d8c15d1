"""The NUTS chains of the calibration's posterior (`posterior.nuts_chains`)
on closed-form Gaussians: numbers whose spreads differ by orders of
magnitude (a wear coefficient's ln beside a shape's) are drawn with their
means, spreads and correlation, R-hat at the goal and no divergence; the
chains go on until R-hat meets its target, continuing where they stopped."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from blackjax.diagnostics import rhat

from diffwear.calibrate.posterior import (
    CHAINS,
    MAX_SAMPLES,
    R_HAT_TARGET,
    SAMPLES,
    WARMUP,
    max_r_hat,
    nuts_chains,
)


def _gaussian(spreads, correlation):
    """Mean, covariance and log density of a Gaussian with these spreads and
    one correlation between the first two numbers."""
    spreads = np.asarray(spreads, float)
    corr = np.eye(spreads.size)
    corr[0, 1] = corr[1, 0] = correlation
    cov = corr * np.outer(spreads, spreads)
    mean = np.linspace(0.5, 2.0, spreads.size)
    precision = jnp.asarray(np.linalg.inv(cov))

    def log_p(z):
        d = z - jnp.asarray(mean)
        return -0.5 * d @ precision @ d

    return mean, cov, log_p


@pytest.mark.parametrize("given", ["exact", "off"])
def test_nuts_draws_numbers_whose_spreads_differ_by_four_orders(given):
    """Spreads 1e-3, 0.4 and 30 (the first two correlated at 0.8), at the
    shipped chains, warm-up and draws.  The covariance NUTS is given is the
    exact one, or one off by 2x in every spread and without the correlation
    (a Gauss-Newton covariance is an approximation): either way the draws'
    means lie within 5 Monte-Carlo errors of the truth, their spreads within
    15 % and their correlation within 0.1, R-hat <= 1.01 for every number
    (the chains run on until it is, within `MAX_SAMPLES`), no divergence.
    Sampled in the numbers' own units instead (the warm-up's covariance
    estimate shrunk towards 1e-3 I), R-hat reached 1.02."""
    spreads = np.array([1e-3, 0.4, 30.0])
    mean, cov, log_p = _gaussian(spreads, 0.8)
    given_cov = cov if given == "exact" else np.diag((2.0 * spreads) ** 2)
    lines: list[str] = []
    z, divergent = nuts_chains(jax.jit(log_p), mean, given_cov, parallel=False, log=lines.append)
    assert z.shape[0] == CHAINS and z.shape[2] == 3
    assert z.shape[1] in range(SAMPLES, MAX_SAMPLES + 1, SAMPLES)
    assert f"chain {CHAINS} of {CHAINS} ({WARMUP} warm-up" in lines[CHAINS - 1]
    assert int(divergent.sum()) == 0
    r_hat = np.array([float(rhat(jnp.asarray(z[..., i]))) for i in range(3)])
    assert np.all(r_hat <= 1.01), r_hat
    flat = z.reshape(-1, 3)
    draws = flat.shape[0]
    # Monte-Carlo error of a mean: spread / sqrt(draws), the draws correlated
    # by at most a factor 4 in their effective number
    np.testing.assert_array_less(np.abs(flat.mean(axis=0) - mean),
                                 5 * spreads / np.sqrt(draws / 4))
    np.testing.assert_allclose(flat.std(axis=0), spreads, rtol=0.15)
    assert np.corrcoef(flat[:, 0], flat[:, 1])[0, 1] == pytest.approx(0.8, abs=0.1)


def test_chains_go_on_where_they_stopped_until_r_hat_meets_its_target():
    """Blocks of 40 draws on a 2-D unit Gaussian.  With the target the
    chains stop at the first block whose R-hat meets it, or at the cap;
    their first 40 draws are those of the same chains without a target
    (the later blocks continue the chains, they do not restart them).  A
    target no sampler meets (0.5) runs every chain to the cap, 200; the
    vectorised chains continue as the chains one after another do, and
    their continued draws keep the Gaussian's mean and spread."""
    def log_p(z):
        return -0.5 * jnp.sum(z ** 2)

    blocks = 40
    lines: list[str] = []
    once, _ = nuts_chains(log_p, np.zeros(2), np.eye(2), samples=blocks, parallel=False,
                          r_hat_target=None)
    assert once.shape == (CHAINS, blocks, 2)
    z, divergent = nuts_chains(log_p, np.zeros(2), np.eye(2), samples=blocks, parallel=False,
                               log=lines.append, max_samples=200)
    np.testing.assert_array_equal(z[:, :blocks], once)
    n = z.shape[1]
    assert n % blocks == 0 and blocks <= n <= 200 and divergent.shape == (CHAINS, n)
    for m in range(blocks, n, blocks):    # each earlier stop was above the target
        assert max_r_hat(z[:, :m]) > R_HAT_TARGET
    if n < 200:
        assert max_r_hat(z) <= R_HAT_TARGET
    assert sum("goes on for 40 more" in line for line in lines) == n // blocks - 1
    never, _ = nuts_chains(log_p, np.zeros(2), np.eye(2), samples=blocks, parallel=True,
                           r_hat_target=0.5, max_samples=200)
    assert never.shape == (CHAINS, 200, 2)
    # the vectorised chains continue as the chains one after another do
    in_turn, _ = nuts_chains(log_p, np.zeros(2), np.eye(2), samples=blocks, parallel=False,
                             r_hat_target=0.5, max_samples=2 * blocks)
    np.testing.assert_allclose(never[:, :2 * blocks], in_turn, rtol=1e-7, atol=1e-9)
    # the vectorised chains' continued draws are still the Gaussian's
    flat = never.reshape(-1, 2)
    np.testing.assert_allclose(flat.std(axis=0), 1.0, rtol=0.15)
    np.testing.assert_array_less(np.abs(flat.mean(axis=0)), 5 / np.sqrt(flat.shape[0] / 4))
