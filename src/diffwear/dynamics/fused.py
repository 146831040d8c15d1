"""Small matrix-vector products written as elementwise sums.

XLA's CPU backend fuses an elementwise product and its sum with the
operations around them, where ``a @ x`` of a few-dozen-entry matrix is a
library call, and a kernel, of its own.  As sums, the right-hand side and
its Jacobian take fewer kernels and a rig cycle no more time, with the same
values to the last bit (the measurements: docs/notes/cpu-kernels.md).
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
