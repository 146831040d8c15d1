"""Running a wear model: compiled once and timed, in pieces with checkpoints,
resume and a progress bar.  The one place where a run is executed; the models
(`diffwear.models`) say only what is computed.

`run_model` runs a model's evolution: a model whose evolution is a scan over
dynamic cycles (`Dynamic`, `FemRoute`: an `Evolver`) through `run_evolution`,
every other model whole (`timed`).  `ChunkedEvolution` runs an `Evolver`'s
scan as a Python loop over chunks of slots (the same result as one scan),
`save_checkpoint` / `load_checkpoint` keep where it stands, and
`run_evolution` drives a whole run: compiled once and timed, in about
`CHUNKS` chunks with a checkpoint after each when an output folder is given
(`Checkpoints`), resumable, with a progress bar.
"""

from __future__ import annotations

import json
import math
import os
import time
from pathlib import Path
from typing import Any, Callable, NamedTuple, cast

import jax
import jax.numpy as jnp
import numpy as np

from .. import interrupt
from ..errors import InputError
from ..io import CHECKPOINT
from ..wear._engine import WearState
from ..wear.solution import WearSolution
from ..wear.status import RESULTS
from ._base import AbstractWearModel
from .dynamic import Dynamic, one_joint

CHUNKS = 10  # a run is cut into ~10 chunks: checkpoint and progress after each
# checkpoint keys added later, with the value that checkpoints written before meant
META_DEFAULTS = {"contact": "efm", "integrator": "tsit5", "model": "dynamic"}


class Checkpoint(NamedTuple):
    """Where a chunked evolution stands: ``state`` (`WearState`, numpy),
    ``history`` (per-slot history of the slots run so far, numpy) and
    ``slots_done`` (scan slots run, possibly past the end on the last chunk)."""

    state: WearState
    history: dict
    slots_done: int


class ChunkedEvolution:
    """Run an evolution as a Python loop over chunks of ``chunk_slots`` scan slots.

    ``make(p)`` builds the `Evolver` from the (traced) parameters ``p``.  One
    compiled chunk function is reused; after every chunk ``on_chunk(Checkpoint)``
    is called (to save it, to show progress; an exception there interrupts the
    run with the checkpoint already saved).  The loop stops once the evolution
    is done (all cycles, or a failure status).  Slots skipped after the end
    are recorded as the single scan records them, so the result (state and
    history) equals that of `evolve` run in one scan.
    """

    def __init__(self, make, p, y0, chunk_slots: int):
        if int(chunk_slots) < 1:
            raise InputError(f"chunk_slots must be >= 1, got {chunk_slots}")
        ev = make(p)  # input checks, static slot count
        self.n_slots, self.chunk_slots = ev.n_slots, int(chunk_slots)
        self.cycles = float(ev.cycles_arr)
        # jitted, then replaced by their compiled forms in `compile`
        self._init: Any = jax.jit(lambda p, y0: make(p).init(y0))
        self._chunk: Any = jax.jit(lambda p, c: make(p).run(c, self.chunk_slots))
        self._idle = jax.jit(lambda p, c: make(p).idle_record(c))
        self._result = jax.jit(lambda p, c, h: make(p).result(c, h))
        self._p, self._y0 = p, y0

    def compile(self) -> float:
        """Compile the warm-up and the chunk function ahead of time; seconds taken."""
        t0 = time.perf_counter()
        shape = jax.tree.map(lambda x: jax.ShapeDtypeStruct(x.shape, x.dtype),
                             jax.eval_shape(self._init, self._p, self._y0))
        self._init = self._init.lower(self._p, self._y0).compile()
        self._chunk = self._chunk.lower(self._p, shape).compile()
        return time.perf_counter() - t0

    def done(self, state) -> bool:
        return not (bool(state.status == RESULTS.ok) and float(state.n) < self.cycles - 1e-9)

    def run(self, start: Checkpoint | None = None, on_chunk=None) -> WearSolution:
        p = self._p
        if start is None:
            state = _as_numpy(self._init(p, self._y0))
            parts, slots = [], 0
        else:
            state, slots = start.state, int(start.slots_done)
            parts = [start.history] if slots > 0 else []
        while slots < self.n_slots and not self.done(state):
            new, h = self._chunk(p, jax.tree.map(jnp.asarray, state))
            state = _as_numpy(new)
            parts.append(_as_numpy(h))
            slots += self.chunk_slots
            if len(parts) > 1:
                parts = [{k: np.concatenate([q[k] for q in parts]) for k in parts[0]}]
            if on_chunk is not None:
                on_chunk(Checkpoint(state, parts[0], slots))
        done = slots if parts else 0
        if done < self.n_slots:  # the rest of the slots: idle, as in one scan
            idle = _as_numpy(self._idle(p, jax.tree.map(jnp.asarray, state)))
            pad = {k: np.repeat(np.asarray(v)[None], self.n_slots - done, axis=0)
                   for k, v in idle.items()}
            parts.append(pad)
        hist = {k: np.concatenate([q[k] for q in parts])[: self.n_slots] for k in parts[0]}
        return self._result(p, jax.tree.map(jnp.asarray, state),
                            jax.tree.map(jnp.asarray, hist))


def _as_numpy(tree):
    return jax.tree.map(np.asarray, tree)


def save_checkpoint(path, ckpt: Checkpoint, meta: dict) -> None:
    """Write ``ckpt`` and ``meta`` (JSON-able) to ``path`` (.npz) atomically."""
    path = Path(path)
    arrays = {f"state.{k}": np.asarray(v) for k, v in ckpt.state.as_dict().items()}
    arrays.update({f"history.{k}": np.asarray(v) for k, v in ckpt.history.items()})
    arrays["slots_done"] = np.asarray(ckpt.slots_done)
    arrays["meta"] = np.asarray(json.dumps(meta))
    # the output folders' name for a write in progress (`diffwear.io`), so that
    # one cut short by a kill is recognised there as this run's own, not foreign
    tmp = path.with_name(f".{path.name}.partial")
    try:
        with open(tmp, "wb") as f:
            np.savez(f, **cast(dict[str, Any], arrays))
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:  # a full disk, or Ctrl-C while writing: no half file left
        tmp.unlink(missing_ok=True)
        raise


def load_checkpoint(path) -> tuple[Checkpoint, dict]:
    """Read a checkpoint written by `save_checkpoint`: (checkpoint, meta)."""
    try:
        with np.load(path, allow_pickle=False) as z:
            state = WearState.from_dict(
                {k[6:]: z[k] for k in z.files if k.startswith("state.")})
            hist = {k[8:]: z[k] for k in z.files if k.startswith("history.")}
            slots, meta = int(z["slots_done"]), json.loads(str(z["meta"]))
    except (OSError, KeyError, ValueError, InputError) as err:
        raise InputError(f"cannot read checkpoint {path}: {err}") from err
    return Checkpoint(state, hist, slots), meta


class Checkpoints(NamedTuple):
    """Where and how a run keeps checkpoints: the output folder ``out`` (an
    `OutputDir`: ``out/checkpoint.npz``), the run's ``meta`` (JSON-able: a
    checkpoint resumes only a run with the same), ``resume`` from the
    checkpoint there, and ``progress``: a bar of real cycles done."""

    out: Any
    meta: dict
    resume: bool = False
    progress: bool = False


class RunTimes(NamedTuple):
    """Seconds to compile and to run a wear evolution, and what the summary
    says of its checkpoints (``info``)."""

    compile_time: float
    wall_time: float
    info: dict


def timed(fn: Callable, *args) -> tuple[Any, RunTimes]:
    """``fn(*args)`` compiled (timed) and run (timed)."""
    t0 = time.perf_counter()
    compiled = jax.jit(fn).lower(*args).compile()
    compile_time = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = jax.block_until_ready(compiled(*args))
    return res, RunTimes(compile_time, time.perf_counter() - t0, {})


def run_evolution(make: Callable, p, y0, checkpoints: Checkpoints | None = None,
                  chunks: int = CHUNKS) -> tuple[WearSolution, RunTimes]:
    """Compile (timed) and run (timed) the evolution ``make(p)`` (an `Evolver`
    from the traced parameters ``p``) from ``y0``.

    Without ``checkpoints``: one jitted function.  With them: in ``chunks``
    chunks of scan slots (`ChunkedEvolution`, same result), saving the
    checkpoint (state, history so far, ``meta``) after each chunk; ``resume``
    continues from the one there, which must carry the same ``meta``.
    """
    if checkpoints is None:
        def whole(p, y0):
            ev = make(p)
            return ev.solve(y0)

        return timed(whole, p, y0)

    from tqdm.auto import tqdm

    out, meta = checkpoints.out, checkpoints.meta
    path = out.path / CHECKPOINT
    start = None
    if checkpoints.resume:
        if not path.is_file():
            raise InputError(f"--resume {out.path}: no {CHECKPOINT} there to resume from")
        start, saved = load_checkpoint(path)
        for key, value in meta.items():
            if saved.get(key, META_DEFAULTS.get(key)) != value:
                raise InputError(
                    f"--resume {out.path}: the checkpoint belongs to a run with {key} = "
                    f"{saved.get(key)!r}, this run has {key} = {value!r}; resume with the "
                    "options of the interrupted run")

    n_slots = make(p).n_slots
    run = ChunkedEvolution(make, p, y0, max(1, math.ceil(n_slots / chunks)))
    compile_time = run.compile()
    done0 = 0.0 if start is None else float(start.state.n)
    bar = tqdm(total=run.cycles, initial=done0, unit="cycle", disable=not checkpoints.progress,
               desc=meta.get("study", "wear"), dynamic_ncols=True,
               bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} cycles [{elapsed}<{remaining}]")

    def on_chunk(ck):
        save_checkpoint(path, ck, meta)
        bar.update(float(ck.state.n) - bar.n)
        interrupt.check()  # a Ctrl-C lost inside a callback ends the run here

    t0 = time.perf_counter()
    try:
        res = jax.block_until_ready(run.run(start=start, on_chunk=on_chunk))
    finally:
        bar.close()
    if path.exists():
        out.file(CHECKPOINT)  # listed in the summary; kept after the run
    info = {"finished": True, "checkpoint": CHECKPOINT if path.exists() else None,
            "resumed_from_cycles": done0 if start is not None else None}
    return res, RunTimes(compile_time, time.perf_counter() - t0, info)


def run_model(model: AbstractWearModel, mech_of: Callable, p, joints: tuple[str, ...], y0, *,
              period, cycles, wall_thickness=None, checkpoints: Checkpoints | None = None
              ) -> tuple[WearSolution, RunTimes]:
    """``model.evolve`` of the mechanism ``mech_of(p)`` (``p``: its traced
    inputs) compiled once and run, both timed.  ``checkpoints``: the output
    folder and settings of a run kept in checkpoints.

    A dynamic model (`Dynamic`, `FemRoute`) runs its `Evolver` through
    `run_evolution`: with ``checkpoints`` in chunks, a checkpoint after each,
    resumable.  Every other model runs whole (seconds; a resume is an
    `InputError`), and a joint that stopped early has the profile it reached
    (`WearSolution.reached`)."""
    if not isinstance(model, Dynamic):
        if checkpoints is not None and checkpoints.resume:
            raise InputError(f"--resume: the {model.name} model runs whole, without "
                             "checkpoints (seconds); run it again instead")

        def evolution(p, y0):
            return model.evolve(mech_of(p), joints, y0, period=period, cycles=cycles,
                                wall_thickness=wall_thickness)

        res, times = timed(evolution, p, y0)
        return res.reached(), times  # a run that stopped early: its results so far
    (joint,) = one_joint(joints)
    return run_evolution(lambda p: model.evolver(mech_of(p), joint, cycles, period=period,
                                                 wall_thickness=wall_thickness),
                         p, y0, checkpoints)


__all__ = ["Checkpoint", "ChunkedEvolution", "save_checkpoint", "load_checkpoint",
           "Checkpoints", "RunTimes", "timed", "run_evolution", "run_model", "CHUNKS",
           "META_DEFAULTS"]
