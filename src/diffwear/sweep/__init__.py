"""Parameter sweeps: evaluate a pure JAX model function over a grid of parameters.

``sweep(model_fn, base_params, grid)`` forms the cartesian product of the
``grid`` arrays (other parameters from ``base_params``), evaluates ``model_fn``
as `execution` says (on a CPU one jitted run after another, over a process
per core when that pays; on an accelerator with ``jax.vmap`` in chunks, and
``jax.shard_map`` over the local devices when there are several) and returns
a `SweepResult` (named NumPy columns, CSV, rows, grid-shaped views).
Ready-made model functions: `diffwear.sweep.models`.
"""

from .execution import Auto, Batched, Looped, Pooled
from .grid import full_grid, validate
from .result import SweepResult
from .runner import sweep

__all__ = ["Auto", "Batched", "Looped", "Pooled", "SweepResult", "full_grid", "sweep",
           "validate"]
