"""Sweeps beyond one machine: the grid split into tasks for a Dask cluster.

``sweep_distributed(model_fn, base, grid, client=client)`` validates the input
exactly as `sweep` does, flattens the grid (C order), cuts the points into
contiguous blocks of ``points_per_task`` and submits one task per block.  Each
task runs on a worker the same local engine as `sweep`
(`runner.evaluate`: jit(vmap) in padded chunks of ``chunk_size``, shard_map over
the worker's devices); the blocks are put back in grid order into one
`SweepResult`.  The points are independent, so a block's results do not depend
on where it ran (they may depend, at integration-tolerance level, on the chunk
size: see `sweep`).

Needs the optional extra ``pip install diffwear[cluster]`` (``dask[distributed]``).
A cluster: ``distributed.Client("tcp://scheduler:8786")`` for one started with
``dask scheduler`` / ``dask worker`` on each machine, or
``Client(LocalCluster(n_workers=N, threads_per_worker=1))`` on one machine.
Workers need diffwear installed; ``model_fn`` travels by (cloud)pickle, so the
ready-made `models` (importable) are the easy case.  Every worker compiles the
model once per task shape (each block has the same size except the last).

float64: the task function lives in this module, so unpickling it on a worker
imports ``diffwear``, which leaves float64 to its caller; the task sets it
before it traces anything, and the result columns are checked to be float64.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping

import numpy as np

from ..errors import InputError
from .grid import full_grid, validate
from .result import SweepResult, build_result


def _run_block(model_fn, cols: dict, chunk_size, start: int):
    """One task, on a worker: the local engine over a block of points."""
    import jax

    jax.config.update("jax_enable_x64", True)  # diffwear computes in float64
    from .execution import Auto
    from .runner import evaluate

    # one process per worker already: never a pool inside it
    out, info = evaluate(model_fn, cols, execution=Auto(workers=1), chunk_size=chunk_size)
    info = {k: v for k, v in info.items() if k not in ("order", "chunk_s")}
    info["start"] = start
    info["x64"] = bool(jax.config.read("jax_enable_x64"))
    try:
        from distributed import get_worker

        info["worker"] = get_worker().address
    except (ImportError, ValueError):  # pragma: no cover (run outside a worker)
        info["worker"] = None
    return out, info


def _client(client):
    try:
        import distributed
    except ImportError:  # pragma: no cover (extra not installed)
        raise InputError("sweep_distributed needs Dask: pip install 'diffwear[cluster]' "
                         "(dask[distributed])") from None
    if client is None:
        try:
            return distributed.get_client()
        except ValueError:
            raise InputError("sweep_distributed: no Dask client; pass client=Client(...) "
                             "(or create one first)") from None
    if isinstance(client, str):
        return distributed.Client(client)
    return client


def sweep_distributed(model_fn: Callable[[dict], dict], base_params: Mapping, grid: Mapping, *,
                      client=None, points_per_task: int | None = None,
                      chunk_size: int | None = None) -> SweepResult:
    """`sweep` with the grid's points spread over the workers of a Dask cluster.

    ``client``: a ``distributed.Client``, a scheduler address (``"tcp://h:8786"``)
    or None (the current client).  ``points_per_task``: points per task (default:
    the points split evenly over the workers, one task each).  ``chunk_size``:
    points per vmap call inside a task (default: the whole block).  Results
    come back in grid order; ``info`` holds ``tasks``, ``workers`` (addresses
    that ran a task), per-task ``task_info``, ``compile_s`` (the largest of the
    tasks), ``run_s`` (wall time of the whole distributed run) and ``x64``.
    """
    known = getattr(model_fn, "param_names", None)
    base, axes = validate(base_params, grid, None if known is None else tuple(known))
    cols, shape = full_grid(base, axes)
    n = int(np.prod(shape))
    client = _client(client)
    n_workers = max(1, len(client.scheduler_info().get("workers", {})))
    if points_per_task is None:
        points_per_task = math.ceil(n / n_workers)
    elif int(points_per_task) != points_per_task or points_per_task < 1:
        raise InputError(f"sweep_distributed: points_per_task must be a positive integer, "
                         f"got {points_per_task!r}")
    block = int(points_per_task)
    starts = list(range(0, n, block))

    t0 = time.perf_counter()
    futures = [client.submit(_run_block, model_fn, {k: v[s:s + block] for k, v in cols.items()},
                             chunk_size, s, pure=False) for s in starts]
    parts = client.gather(futures)
    run_s = time.perf_counter() - t0

    out_names = list(parts[0][0])
    results = {k: np.empty(n) for k in out_names}
    for (out, info) in parts:
        s = info["start"]
        for k in out_names:
            col = np.asarray(out[k])
            if col.dtype != np.float64:
                raise InputError(f"sweep_distributed: worker {info['worker']} returned {k} as "
                                 f"{col.dtype}, not float64")
            results[k][s:s + col.size] = col
    task_info = [info for _, info in parts]
    info = {"points": n, "tasks": len(starts), "points_per_task": block,
            "workers": sorted({i["worker"] for i in task_info if i["worker"]}),
            "compile_s": max(i["compile_s"] for i in task_info), "run_s": run_s,
            "x64": all(i["x64"] for i in task_info), "task_info": task_info,
            "order": np.arange(n), "devices": None, "chunk_size": chunk_size}
    return build_result(cols, results, tuple(axes), shape, info)


__all__ = ["sweep_distributed"]
