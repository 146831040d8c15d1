"""`sweep`: a model function over a grid, run as `execution` says (batched in
chunks with vmap and shard_map, looped, or over a pool of processes)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .. import worker
from .._checks import require_float64
from ..errors import InputError, SolverError
from .execution import (
    Auto,
    Batched,
    Execution,
    Looped,
    Pooled,
    compile_point,
    persistent_cache_on,
    platform,
    pool_pays,
    run_points,
    run_pool,
    serialized,
    workers_for,
)
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
          execution: Execution | None = None, chunk_size: int | None = None, devices=None,
          order_by: Callable[[dict], float] | None = None,
          progress: Callable[[int], None] | None = None) -> SweepResult:
    """Evaluate ``model_fn`` at every point of the grid.

    ``model_fn(params) -> dict of scalars``: a pure JAX function of a dict of
    scalar parameters (all of ``base_params`` and ``grid``).  If it has a
    ``param_names`` attribute (the ready-made `models`), names are checked
    against it.  ``grid``: name -> 1-D array; the sweep is their cartesian
    product (C order, last name fastest), other parameters from ``base_params``.

    ``execution``: how the points run (`diffwear.sweep.execution`):
    `Auto()` (default) batches them on an accelerator and, on a CPU, runs
    them one jitted run after another, moving them to a process per core
    when the first point's time says that pays; `Batched`, `Looped` and
    `Pooled` choose.  ``info["execution"]`` says which ran.

    Batched (``chunk_size`` or ``devices`` given also mean batched):
    ``chunk_size`` points per ``jax.vmap`` call (default: all at once, or the
    largest chunk that fits in memory: `diffwear.sweep.memory`; a requested
    chunk that does not fit is refused with the estimate), rounded
    up to a multiple of the device count; the last chunk is padded with copies
    of its last point, whose outputs are dropped.  One compilation serves every
    chunk.  ``devices``: None (all local devices), a count, or a list; with more
    than one, each chunk is split over them with ``jax.shard_map``.
    ``order_by(params) -> estimated cost`` (params as Python floats): points are
    evaluated in increasing cost, so that a chunk holds similar-cost points (a
    vmapped adaptive solve runs as long as its slowest member); results come
    back in grid order either way.  ``progress(points)`` is called as points
    finish.

    Exactness: a looped or pooled point's result is the single jitted run's,
    exactly.  A batched one is the single run's up to rounding: batched
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
    results, info = evaluate(model_fn, cols, execution=execution, chunk_size=chunk_size,
                             devices=devices, order_by=order_by, describe=tuple(axes),
                             progress=progress)
    return build_result(cols, results, tuple(axes), shape, info)


def resolve(execution: Execution | None, chunk_size, devices) -> Execution:
    """The execution to run: ``chunk_size`` and ``devices`` belong to
    `Batched` (given with `Auto` or None, they choose it; with `Looped` or
    `Pooled` they are refused); `Auto` on an accelerator is `Batched`."""
    execution = Auto() if execution is None else execution
    if not isinstance(execution, Batched | Looped | Pooled | Auto):
        raise InputError(f"sweep: execution {execution!r}; allowed: Batched(), Looped(), "
                         "Pooled() or Auto() (diffwear.sweep.execution)")
    batched_options = chunk_size is not None or devices is not None
    if isinstance(execution, Batched):
        if batched_options:
            raise InputError("sweep: give chunk_size and devices to Batched(...), not beside it")
        return execution
    if isinstance(execution, Auto) and (batched_options or platform() != "cpu"):
        return Batched(chunk_size, devices)
    if batched_options:
        raise InputError(f"sweep: chunk_size and devices belong to batched execution, not "
                         f"{type(execution).__name__}()")
    return execution


def evaluate(model_fn: Callable[[dict], dict], cols: Mapping[str, np.ndarray], *,
             execution: Execution | None = None, chunk_size: int | None = None, devices=None,
             order_by: Callable[[dict], float] | None = None,
             describe: Sequence[str] = (),
             progress: Callable[[int], None] | None = None) -> tuple[dict[str, np.ndarray], dict]:
    """The engine of `sweep`: ``model_fn`` at every point of ``cols`` (name ->
    equal-length 1-D float64 columns, already validated), run as ``execution``
    says (`resolve`), optionally cost-ordered.  Returns (outputs name ->
    column in the order of ``cols``, info).  `sweep` and
    `distributed.sweep_distributed` (on each worker) both call it.
    ``describe``: the names shown for a point in messages."""
    names = list(cols)
    n = int(np.asarray(cols[names[0]]).size)
    out_names = _output_names(model_fn, names)
    execution = resolve(execution, chunk_size, devices)

    t0 = time.perf_counter()
    order = _order(cols, n, order_by, describe)
    order_s = time.perf_counter() - t0
    if isinstance(execution, Batched):
        results, info = _batched(model_fn, cols, order, out_names, execution, progress)
    else:
        results, info = _one_at_a_time(model_fn, cols, order, out_names, execution, progress)
    info |= {"points": n, "ordered": order_by is not None, "order": order, "order_s": order_s}
    return results, info


def _order(cols, n: int, order_by, describe) -> np.ndarray:
    if order_by is None:
        return np.arange(n)
    names = list(cols)
    costs = np.array([float(order_by({k: float(cols[k][i]) for k in names}))
                      for i in range(n)])
    if not np.all(np.isfinite(costs)):
        i = int(np.argmax(~np.isfinite(costs)))
        raise InputError(f"sweep: order_by gave {costs[i]} at point {i} "
                         f"({ {k: float(cols[k][i]) for k in describe} })")
    return np.argsort(costs, kind="stable")


def _batched(model_fn, cols, order, out_names, execution: Batched, progress):
    """jit(vmap) in padded chunks, shard_map over the devices."""
    names = list(cols)
    n = order.size
    chunk_size = execution.chunk_size
    devs = _devices(execution.devices)
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
    padded = np.concatenate([order, np.full(n_chunks * size - n, order[-1])])

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
        if progress is not None:
            progress(int(keep.size))

    info = {"execution": "batched", "processes": 1, "chunks": n_chunks, "chunk_size": size,
            "padding": n_chunks * size - n, "bytes_per_point": per_point, "devices": nd,
            "compile_s": compile_s, "run_s": float(sum(chunk_s)), "chunk_s": chunk_s}
    return results, info


def _one_at_a_time(model_fn, cols, order, out_names, execution: Looped | Pooled | Auto,
                   progress):
    """Single jitted runs of the program compiled here: in this process
    (`Looped`), over processes (`Pooled`), or here until the first point's
    time says a pool pays (`Auto`)."""
    n = order.size
    results = {k: np.full(n, np.nan) for k in out_names}
    workers = 1 if isinstance(execution, Looped) else workers_for(execution.workers)
    if isinstance(execution, Pooled) and not worker.AVAILABLE:
        raise InputError("sweep: Pooled() needs worker processes, which this platform does "
                         "not offer (pipes cannot be passed to a child); allowed: Looped()")
    info: dict = {"execution": "looped", "processes": 1, "chunks": n, "chunk_size": 1,
                  "padding": 0, "bytes_per_point": None, "devices": 1}
    t0 = time.perf_counter()
    # a program sent to a pool is compiled afresh (`compile_point`)
    compiled = compile_point(model_fn, list(cols), fresh=isinstance(execution, Pooled))
    compile_s = time.perf_counter() - t0
    t_run = time.perf_counter()
    done = 0
    program = serialized(compiled) if isinstance(execution, Pooled) else None
    if not isinstance(execution, Pooled):
        probe = min(n, 2)  # the first point's run, then one timed alone
        run_points(compiled, cols, order[:1], results, progress)
        t1 = time.perf_counter()
        run_points(compiled, cols, order[1:probe], results, progress)
        per_point = time.perf_counter() - t1 if probe == 2 else t1 - t_run
        done = probe
        pays = (isinstance(execution, Auto) and worker.AVAILABLE
                and pool_pays(n - done, per_point, workers))
        if pays:  # serialised only now; a program that cannot be sent is compiled there
            program = serialized(compile_point(model_fn, list(cols), fresh=True)
                                 if persistent_cache_on() else compiled)
            pays = program is not None or pool_pays(n - done, per_point, workers, compile_s)
        if not pays:
            run_points(compiled, cols, order[done:], results, progress)
            done = n
    if done < n:
        try:
            pool = run_pool(program, model_fn, cols, order[done:], workers, results, progress)
        except (SolverError, InputError) as err:
            if isinstance(execution, Pooled) or "the sweep's pool failed" in str(err):
                raise
            # `Auto`: a pool that cannot take the model leaves the points here
            run_points(compiled, cols, order[done:], results, progress)
            info["pool_error"] = str(err)
        else:
            info |= {"execution": "pooled", "processes": min(workers, n - done), **pool}
    info |= {"compile_s": compile_s, "run_s": time.perf_counter() - t_run}
    return results, info
