"""How a sweep's points are run.

* `Batched`: ``jit(vmap(model))`` over chunks of points, split over devices
  with ``shard_map``: what an accelerator wants (thousands of points per
  kernel launch).
* `Looped`: one jitted single-point run after another, in this process.  On a
  CPU this beats vmap for the adaptive solvers of this project: a vmapped
  adaptive solve steps all its points in lockstep (each chunk runs as long
  as its slowest point), and ``lax.cond`` becomes ``select`` under vmap, so
  both branches are computed.
* `Pooled`: the points shared over processes, one per CPU core, each looping
  with the program compiled here (sent serialised, loaded in milliseconds;
  a program with Python callbacks cannot be, and is compiled in each
  process instead; a process, not a thread: XLA's CPU runtime does not run
  two executions at once from threads of one process;
  docs/notes/cpu-sweeps.md).
* `Auto` (the default): `Batched` on an accelerator (or when a chunk size or
  several devices are asked for); on a CPU it loops, times the first point
  after the compilation, and moves the rest to a pool when the time saved
  outweighs the pool's start-up (``POOL_START_S``, and the compilation where
  the program cannot be sent).

A looped or pooled point's result is exactly the single jitted run's.
"""

from __future__ import annotations

import math
import os
import pickle
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import InputError

# Start-up of a pool process before it compiles: spawning the interpreter and
# importing diffwear (2.1 s measured for ``import diffwear`` on a 2-core
# machine), with a margin for the spawn and the transfer of the model.
POOL_START_S = 4.0

# A pool is cut into this many blocks per process, so that the processes
# finish together and the progress moves.
BLOCKS_PER_WORKER = 4


@dataclass(frozen=True)
class Batched:
    """``jit(vmap(model))`` in chunks of ``chunk_size`` points (default: all
    that fit in memory), over ``devices`` (None: all local devices, a count,
    or a list) with ``shard_map``."""

    chunk_size: int | None = None
    devices: Any = None


@dataclass(frozen=True)
class Looped:
    """One jitted single-point run after another, in this process."""


@dataclass(frozen=True)
class Pooled:
    """The points shared over ``workers`` processes (default: the CPU cores
    this process may use), each running them one after another."""

    workers: int | None = None


@dataclass(frozen=True)
class Auto:
    """`Batched` on an accelerator; on a CPU `Looped`, or `Pooled` over
    ``workers`` processes (default: the cores; 1: never a pool) when the
    first point's time says the pool pays."""

    workers: int | None = None


Execution = Batched | Looped | Pooled | Auto


def available_cores() -> list[int]:
    """The CPU cores this process may run on ([] where the platform does not
    say: macOS, Windows)."""
    try:
        return sorted(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover
        return []


def cpu_cores() -> int:
    """How many CPU cores this process may run on."""
    return len(available_cores()) or os.cpu_count() or 1


def platform() -> str:
    """The platform computations go to: JAX's default device if one is set
    (``jax.default_device``), else its default backend."""
    device = jax.config.jax_default_device  # type: ignore[attr-defined]
    if device is not None:
        return device if isinstance(device, str) else device.platform
    return jax.default_backend()


def workers_for(workers: int | None) -> int:
    if workers is None:
        return cpu_cores()
    if int(workers) != workers or workers < 1:
        raise InputError(f"sweep: workers must be a positive integer, got {workers!r}")
    return int(workers)


def picklable(model_fn) -> bool:
    """Whether ``model_fn`` can be sent to a pool process: it pickles, and
    not as a name in the caller's script (``__main__``), which a worker
    process does not run.  The ready-made models can; a lambda, a closure
    or a script's own function cannot."""
    try:
        data = pickle.dumps(model_fn)
    except Exception:  # noqa: BLE001 - any pickling failure means: not here
        return False
    return b"__main__" not in data


def _point(cols: Mapping[str, np.ndarray], i: int) -> dict:
    return {k: np.asarray(v[i], dtype=np.float64) for k, v in cols.items()}


def compile_point(model_fn: Callable, names: Sequence[str], *, fresh: bool = False):
    """``jit(model_fn)`` compiled for one point (a dict of float64 scalars).
    ``fresh``: compiled here, not loaded from JAX's persistent compilation
    cache: a program to send to a pool (`serialized`).  A CPU program loaded
    from that cache serialises without some of its kernels, and a process
    that loads it fails when it runs ("Function ... not found")."""
    spec = {k: jax.ShapeDtypeStruct((), jnp.float64) for k in names}
    lowered = jax.jit(model_fn).lower(spec)
    if not fresh or not persistent_cache_on():
        return lowered.compile()
    from jax.experimental.compilation_cache import compilation_cache

    # JAX decides once per process whether its cache is in use: reset, so
    # that the switch is read again, and again after
    jax.config.update("jax_enable_compilation_cache", False)
    compilation_cache.reset_cache()
    try:
        return lowered.compile()
    finally:
        jax.config.update("jax_enable_compilation_cache", True)
        compilation_cache.reset_cache()


def persistent_cache_on() -> bool:
    """Whether JAX's persistent compilation cache is in use (enabled, with a
    folder: the command line sets one, `diffwear.cli.command`)."""
    values = jax.config.values
    return bool(values["jax_enable_compilation_cache"] and values["jax_compilation_cache_dir"])


def run_points(compiled, cols: Mapping[str, np.ndarray], indices, results: dict,
               progress: Callable[[int], None] | None = None) -> None:
    """Run ``compiled`` at the points ``indices`` of ``cols``, writing each
    output into ``results[name][i]``."""
    for i in indices:
        out = compiled(_point(cols, int(i)))
        for k, v in out.items():
            results[k][i] = float(v)
        if progress is not None:
            progress(1)


def serialized(compiled) -> tuple | None:
    """The compiled program (`compile_point` with ``fresh=True``) as bytes a
    pool process can load (XLA's own serialisation: the CPU backend has
    it), or None where it cannot be."""
    from jax.experimental import serialize_executable

    try:
        payload = serialize_executable.serialize(compiled)
        pickle.dumps(payload)
    except Exception:  # noqa: BLE001 - a backend or program without it: compile there
        return None
    return payload


def _pool_setup(program, model_fn, names, out_names, core):
    """In a pool process: CPU only, on its own ``core``; returns the handler
    of a block of points (`diffwear.worker`).  ``program``: the parent's
    compiled program (`serialized`), loaded here; without it the model is
    compiled at the first block.

    The core: XLA's CPU runtime runs its threads on every core it may use,
    and two such processes' threads fight; pinned, each runs a point at
    least as fast as one process alone (docs/notes/cpu-sweeps.md)."""
    jax.config.update("jax_platforms", "cpu")
    if core is not None and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {core})
    compiled: list = []
    if program is not None:
        from jax.experimental import serialize_executable

        # LAPACK's kernels are bound when a linear-algebra operation is first
        # lowered; a loaded program calling them before that crashes
        jax.jit(jnp.linalg.cholesky).lower(jnp.eye(1))
        compiled.append(serialize_executable.deserialize_and_load(*program))

    def block(cols: dict) -> tuple[dict, float]:
        t0 = time.perf_counter()
        if not compiled:
            compiled.append(compile_point(model_fn, names))
        compile_s = time.perf_counter() - t0
        n = len(next(iter(cols.values())))
        results = {k: np.empty(n) for k in out_names}
        run_points(compiled[0], cols, range(n), results)
        return results, compile_s

    return block, None


def run_pool(program, model_fn, cols: Mapping[str, np.ndarray], indices: np.ndarray,
             workers: int, results: dict,
             progress: Callable[[int], None] | None = None) -> dict:
    """Run the points ``indices`` over ``workers`` fresh processes
    (`diffwear.worker`), in blocks, with this process's compiled program
    (``program``, `serialized`) or, where it could not be serialised (None:
    a program with Python callbacks), ``model_fn`` compiled in each process
    (it must then pickle); returns the pool's time and its longest
    compilation there."""
    from .. import worker

    if program is None and not picklable(model_fn):
        raise InputError("sweep: Pooled() sends the model to other processes, and this one "
                         "cannot be pickled (a lambda or a closure?) nor its compiled "
                         "program serialised; allowed: a model defined at a module's top "
                         "level, or Looped()")
    names = list(cols)
    size = max(1, math.ceil(indices.size / (workers * BLOCKS_PER_WORKER)))
    blocks = [indices[s:s + size] for s in range(0, indices.size, size)]
    compile_s = [0.0]

    def done(b: int, answer) -> None:
        out, c = answer
        compile_s.append(c)
        for k, v in out.items():
            results[k][blocks[b]] = v
        if progress is not None:
            progress(blocks[b].size)

    t0 = time.perf_counter()
    cores = available_cores()

    def args_of(i: int) -> tuple:  # worker i on a core of its own
        return (program, None if program else model_fn, names, list(results),
                cores[i % len(cores)] if cores else None)

    worker.run_pool(workers, _pool_setup, args_of,
                    ({k: np.asarray(cols[k])[b] for k in names} for b in blocks), done,
                    what="sweep's pool")
    return {"pool_s": time.perf_counter() - t0, "pool_compile_s": max(compile_s),
            "pool_program": "sent" if program is not None else "compiled in each process"}


def pool_pays(remaining: int, per_point_s: float, workers: int,
              compile_s: float = 0.0) -> bool:
    """Whether ``remaining`` points of ``per_point_s`` finish sooner over
    ``workers`` fresh processes than here: each starts (`POOL_START_S`),
    then loads the program compiled here, or compiles it (``compile_s``,
    where it cannot be sent), the processes at once."""
    if workers < 2 or remaining < 2:
        return False
    saved = remaining * per_point_s * (1.0 - 1.0 / min(workers, remaining))
    return saved > POOL_START_S + compile_s


__all__ = ["Auto", "Batched", "Execution", "Looped", "Pooled", "available_cores", "compile_point",
           "cpu_cores",
           "picklable", "platform", "pool_pays", "run_points", "run_pool", "serialized",
           "workers_for"]
