"""`sweep`: vmap (and shard_map) a model function over a grid, in chunks."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .._checks import require_float64
from ..errors import InputError
from .grid import full_grid, validate
from .memory import chunk_for_memory
from .result import SweepResult, build_result

AXIS = "points"


def _shard_map():
    """``jax.shard_map`` (JAX >= 0.6) or the older ``jax.experimental`` one,
    both with the replication/VMA check off (diffrax's loops trip it)."""
    if hasattr(jax, "shard_map"):
        return lambda f, **kw: jax.shard_map(f, check_vma=False, **kw)
    from jax.experimental.shard_map import shard_map  # pragma: no cover (old JAX)

    return lambda f, **kw: shard_map(f, check_rep=False, **kw)  # pragma: no cover


def _devices(devices) -> list:
    if devices is None:
        return list(jax.local_devices())
    if isinstance(devices, int):
        local = jax.local_devices()
        if not 1 <= devices <= len(local):
            raise InputError(f"sweep: devices = {devices}, but {len(local)} local device(s)")
        return list(local[:devices])
    devices = list(devices)
    if not devices:
        raise InputError("sweep: devices is an empty list")
    return devices


def _output_names(model_fn, names) -> list[str]:
    spec = {n: jax.ShapeDtypeStruct((), jnp.float64) for n in names}
    out = jax.eval_shape(model_fn, spec)
    if not isinstance(out, Mapping) or not out:
        raise InputError("sweep: model_fn must return a non-empty dict name -> scalar, got "
                         f"{type(out).__name__}")
    bad = {k: v.shape for k, v in out.items() if getattr(v, "shape", None) != ()}
    if bad:
        raise InputError(f"sweep: model outputs must be scalars; got shapes {bad}")
    return list(out)


def batched_fn(model_fn: Callable, devices: Sequence) -> Any:
    """jit(vmap(model_fn)) over a dict of equal-length columns; with several
    devices, the columns are split over them with shard_map."""
    batched = jax.vmap(model_fn)
    if len(devices) > 1:
        from jax.sharding import Mesh
        from jax.sharding import PartitionSpec as P

        mesh = Mesh(np.asarray(devices), (AXIS,))
        batched = _shard_map()(batched, mesh=mesh, in_specs=P(AXIS), out_specs=P(AXIS))
    return jax.jit(batched)


def sweep(model_fn: Callable[[dict], dict], base_params: Mapping, grid: Mapping, *,
          chunk_size: int | None = None, devices=None,
          order_by: Callable[[dict], float] | None = None) -> SweepResult:
    """Evaluate ``model_fn`` at every point of the grid.

    ``model_fn(params) -> dict of scalars``: a pure JAX function of a dict of
    scalar parameters (all of ``base_params`` and ``grid``).  If it has a
    ``param_names`` attribute (the ready-made `models`), names are checked
    against it.  ``grid``: name -> 1-D array; the sweep is their cartesian
    product (C order, last name fastest), other parameters from ``base_params``.

    ``chunk_size``: points per ``jax.vmap`` call (default: all at once, or the
    largest chunk that fits in memory: `diffwear.sweep.memory`; a requested
    chunk that does not fit is refused with the estimate), rounded
    up to a multiple of the device count; the last chunk is padded with copies
    of its last point, whose outputs are dropped.  One compilation serves every
    chunk.  ``devices``: None (all local devices), a count, or a list; with more
    than one, each chunk is split over them with ``jax.shard_map``.
    ``order_by(params) -> estimated cost`` (params as Python floats): points are
    evaluated in increasing cost, so that a chunk holds similar-cost points (a
    vmapped adaptive solve runs as long as its slowest member); results come
    back in grid order either way.

    Exactness: a point's result is the single run's up to rounding.  Batched
    (vmapped) linear algebra may round differently from the unbatched kernels,
    and an adaptive solve turns ulp differences into differences at its
    tolerance level (another step sequence), which also makes results depend on
    the batch (chunk) size at that level.  Seen: the toy ODE of the tests is
    bit-identical; the reduced rig wear differs by 7e-7 relative; a clearance
    cycle's sampled impact peak force by 1 % (its RMS force by 3e-4).
    """
    require_float64("sweep")
    known = getattr(model_fn, "param_names", None)
    base, axes = validate(base_params, grid, None if known is None else tuple(known))
    cols, shape = full_grid(base, axes)
    results, info = evaluate(model_fn, cols, chunk_size=chunk_size, devices=devices,
                             order_by=order_by, describe=tuple(axes))
    return build_result(cols, results, tuple(axes), shape, info)


def evaluate(model_fn: Callable[[dict], dict], cols: Mapping[str, np.ndarray], *,
             chunk_size: int | None = None, devices=None,
             order_by: Callable[[dict], float] | None = None,
             describe: Sequence[str] = ()) -> tuple[dict[str, np.ndarray], dict]:
    """The engine of `sweep`: ``model_fn`` at every point of ``cols`` (name ->
    equal-length 1-D float64 columns, already validated), vmapped in padded
    chunks, shard_map over ``devices``, optionally cost-ordered.  Returns
    (outputs name -> column in the order of ``cols``, info).  `sweep` and
    `distributed.sweep_distributed` (on each worker) both call it, so a point
    goes through the same compiled function either way.  ``describe``: the
    names shown for a point in messages."""
    names = list(cols)
    n = int(np.asarray(cols[names[0]]).size)
    out_names = _output_names(model_fn, names)

    devs = _devices(devices)
    nd = len(devs)
    if chunk_size is not None and (int(chunk_size) != chunk_size or chunk_size < 1):
        raise InputError(f"sweep: chunk_size must be a positive integer, got {chunk_size!r}")
    fn = batched_fn(model_fn, devs)

    def compile_at(size: int):
        return fn.lower({k: jnp.zeros(size, jnp.float64) for k in names}).compile()

    # the chunk that fits in memory (`memory`): all points at once if they do
    t0 = time.perf_counter()
    size, per_point, compiled = chunk_for_memory(compile_at, n, nd, chunk_size, devs[0])
    if compiled is None:
        compiled = compile_at(size)
    compile_s = time.perf_counter() - t0
    n_chunks = math.ceil(n / size)

    t0 = time.perf_counter()
    if order_by is None:
        order = np.arange(n)
    else:
        costs = np.array([float(order_by({k: float(cols[k][i]) for k in names}))
                          for i in range(n)])
        if not np.all(np.isfinite(costs)):
            i = int(np.argmax(~np.isfinite(costs)))
            raise InputError(f"sweep: order_by gave {costs[i]} at point {i} "
                             f"({ {k: float(cols[k][i]) for k in describe} })")
        order = np.argsort(costs, kind="stable")
    padded = np.concatenate([order, np.full(n_chunks * size - n, order[-1])])
    order_s = time.perf_counter() - t0

    results = {k: np.empty(n) for k in out_names}
    chunk_s = []
    for c in range(n_chunks):
        idx = padded[c * size:(c + 1) * size]
        t0 = time.perf_counter()
        out = jax.block_until_ready(compiled({k: cols[k][idx] for k in names}))
        chunk_s.append(time.perf_counter() - t0)
        keep = idx[: max(0, min(size, n - c * size))]
        for k in out_names:
            results[k][keep] = np.asarray(out[k], dtype=float)[: keep.size]

    info = {"points": n, "chunks": n_chunks, "chunk_size": size, "padding": n_chunks * size - n,
            "bytes_per_point": per_point,
            "devices": nd, "ordered": order_by is not None, "order": order, "compile_s": compile_s,
            "run_s": float(sum(chunk_s)), "chunk_s": chunk_s, "order_s": order_s}
    return results, info

