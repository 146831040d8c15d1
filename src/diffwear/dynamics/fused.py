"""Small matrix-vector products written as elementwise sums.

XLA's CPU backend fuses an elementwise product and its sum with the
operations around them, where ``a @ x`` of a few-dozen-entry matrix is a
library call, and a kernel, of its own.  Measured on the rig: as sums, the
Schur-complement solve's products took the right-hand side from 42 to 37
kernels and its Jacobian from 110 to 96, and the Rosenbrock stages'
combinations took a Rodas4 rig cycle to 0.95-1.00 of the time with the same
values to the last bit (the performance docs;
`benchmarks/experiments/rosenbrock_step_profile.py`).
"""

from __future__ import annotations

import jax.numpy as jnp


def times(a, x):
    """a @ x for a small matrix ``a`` (m, n) and a vector ``x`` (n,)."""
    return jnp.sum(a * x, axis=-1)


def t_times(a, x):
    """a^T @ x for a small matrix ``a`` (m, n) and a vector ``x`` (m,): the
    rows of ``a`` weighted by ``x`` and summed."""
    return jnp.sum(a * x[:, None], axis=0)
