"""Input validation that works on concrete values and stays silent under tracing.

Model constructors run both with concrete numbers (a user building a model:
validate, raise `InputError`) and inside ``jax.grad``/``jax.vmap`` (values are
tracers: nothing to check at trace time; the untraced call already did).
"""

from __future__ import annotations

import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .errors import InputError


def concrete(value: Any) -> np.ndarray | None:
    """The value as a NumPy array, or ``None`` when it is a JAX tracer."""
    if any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(value)):
        return None
    return np.asarray(value, dtype=float)


def float_leaf(value: Any) -> np.ndarray | jax.Array:
    """``value`` as a float64 parameter of a model.  A Python or NumPy number
    stays a NumPy float64 array: an object built before the caller switches
    on ``jax_enable_x64`` (a preset built on import, before the ``diffwear``
    command switches it on) keeps its float64 values, where ``jnp.asarray``
    would have rounded them to float32 for good.  Anything else (a JAX array,
    a tracer) becomes a JAX array of JAX's float type."""
    if isinstance(value, (int, float, np.ndarray, np.generic)) and not isinstance(value, bool):
        return np.asarray(value, dtype=np.float64)
    return jnp.asarray(value, dtype=float)


def _numbers(what: str, value: Any) -> np.ndarray | None:
    """`concrete`, with a value that is not a number an `InputError` naming ``what``."""
    try:
        return concrete(value)
    except (TypeError, ValueError):
        raise InputError(f"{what} must be a number, got {value!r}") from None


def check_finite(what: str, value: Any) -> None:
    v = _numbers(what, value)
    if v is not None and not np.all(np.isfinite(v)):
        raise InputError(f"{what} must be finite, got {v.tolist()}")


def check_positive(what: str, value: Any, *, allow_zero: bool = False) -> None:
    v = _numbers(what, value)
    if v is None:
        return
    check_finite(what, v)
    bad = v < 0 if allow_zero else v <= 0
    if np.any(bad):
        bound = ">= 0" if allow_zero else "> 0"
        raise InputError(f"{what} must be {bound}, got {v.tolist()}")


def check_range(
    what: str,
    value: Any,
    low: float = -math.inf,
    high: float = math.inf,
    *,
    low_open: bool = False,
    high_open: bool = False,
) -> None:
    v = _numbers(what, value)
    if v is None:
        return
    check_finite(what, v)
    too_low = v <= low if low_open else v < low
    too_high = v >= high if high_open else v > high
    if np.any(too_low) or np.any(too_high):
        lo = "(" if low_open else "["
        hi = ")" if high_open else "]"
        raise InputError(f"{what} must lie in {lo}{low}, {high}{hi}, got {v.tolist()}")


def check_int_option(option: str, value: Any, low: int, high: int | None = None) -> None:
    """A count (``--cycles``, ``n_samples``, ...): an integer in [low, high]
    (``high`` None: >= low), else `InputError` naming the option, the allowed
    range and the value."""
    if (isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low
            or (high is not None and value > high)):
        allowed = f">= {low:,}" if high is None else f"in [{low:,}, {high:,}]"
        raise InputError(f"{option} must be an integer {allowed}, got {value!r}")


def require_float64(what: str) -> None:
    """Raise `InputError` unless JAX computes in float64 (``jax_enable_x64``).

    Contact penetrations of micrometres on metre-scale positions, and wear
    depths of nanometres per cycle, are lost in float32; diffwear does not
    switch the process-wide flag on import (that is the user's or the
    command line's choice), so every simulation entry point checks it."""
    if not jax.config.read("jax_enable_x64"):
        raise InputError(
            f"{what}: diffwear computes in float64; call "
            "jax.config.update('jax_enable_x64', True) before building a model "
            "(the diffwear command does this itself)")
