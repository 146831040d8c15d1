"""Wear evolution over many crank cycles (thesis Ch. 4-6, Eq. 4-18..4-20).

The bushing wear profile h(theta_k) [m] is an array carried through
``jax.lax.scan`` over *dynamic* cycles.  Each scan step runs one dynamic cycle
(`wear_cycle`) with the current profile (``eqx.tree_at`` swaps the joint's
``profile``), carries the mechanism state (q, qd, contact-law memory) from the
end of one cycle into the next (no restart transient), and adds A x (wear of
that cycle) to the profile: one simulated cycle stands for A real cycles.

Methods (strategy objects, `wear.extrapolation`; or their names)
-------
``"constant"``  `Constant(A)`: fixed A (A = 1: every cycle simulated).
``"adaptive"``  `Adaptive(...)`: the thesis's scheme (Eq. 4-20): A_{j+1} = A_j + A_inc while the
                wear increment stays smooth, else A_j - A_dec; one integer A per
                cycle.  "Smooth" (``criterion``):
                ``"increment_change"`` (default): the wear increment of this
                cycle differs from the previous cycle's by less than
                ``change_fraction`` of its peak (smooth in cycle count);
                ``"pressure_jump"`` (the thesis's Delta p_ele < p_crit): the
                largest jump of the cycle-mean pressure p_k = dh_k / (k s_cycle)
                between neighbouring grid points stays below
                ``p_crit_fraction`` x max_k p_k.  On an EFM grid the edge of a
                worn pocket is such a jump, so this criterion shrinks A to 1
                once a pocket forms (seen on the rig: A = 1 after ~6 cycles);
                the thesis applied it to FEM element pressures.  The thesis
                gives no constants; ours are `Adaptive`'s defaults.
``"error"``     `ErrorControlled(rtol, atol)`: the profile as a slow ODE in the cycle count N,
                dh/dN = f(h) = wear of one dynamic cycle at profile h, integrated
                by an embedded Heun-Euler (RK2(1)) pair with step-size control on
                max_k |h_err| <= atol + rtol max_k |h|.  Accuracy decides how many
                dynamic cycles are simulated (2 per accepted step, 1 per retry).

Everything is a pure function of arrays (mechanism leaves included), so the
whole evolution jits once and differentiates (reverse or forward mode) w.r.t.
the wear coefficient, clearance, bushing depth and diameter.  Methods
"adaptive" and "error" run a fixed number of scan slots (``max_dynamic``);
slots after the end are skipped with ``lax.cond``.

Failure (bushing worn through, integrator failure) never raises inside jit:
the evolution stops updating, keeps the results so far and reports ``status``;
`EvolutionResult.check` raises `WearLimitError` naming the cycle and depth.
"""

from __future__ import annotations

import json
import math
import os
import time
from pathlib import Path
from typing import Any, NamedTuple, cast

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._checks import require_float64
from ..errors import InputError, SolverError
from ..mechanism import Mechanism
from .cycle import CYCLE_ATOL, CYCLE_RTOL, clearance_element, wear_parts
from .dynamic_term import CycleSettings, DynamicWear
from .engine import Engine, Stop, WearState, initial_state
from .extrapolation import extrapolation_method
from .status import STATUS_INCOMPLETE, STATUS_OK, STATUS_PIERCED


class WearLimitError(SolverError):
    """The wear evolution stopped early; ``.result`` holds the results so far."""

    def __init__(self, message, result=None):
        super().__init__(message)
        self.result = result


def smooth_max(x: Float[Array, " n"], temperature) -> Float[Array, ""]:
    """Smooth maximum T log(sum exp(x / T)) - T log(n): within T log(n) of max(x)
    and differentiable everywhere (logsumexp with temperature T, units of x)."""
    n = x.shape[0]
    return temperature * (jax.nn.logsumexp(x / temperature) - math.log(n))


def worn_volume(depth_profile, bushing_radius, bushing_depth) -> Float[Array, ""]:
    """Archard volume [m^3]: bushing depth x integral of h R_b dtheta."""
    n = depth_profile.shape[-1]
    return bushing_depth * bushing_radius * (2 * jnp.pi / n) * jnp.sum(depth_profile, axis=-1)


class EvolutionResult(eqx.Module):
    """Final wear profile and state, counters, and per-slot history.

    ``history`` arrays have one entry per scan slot; ``history["valid"]`` marks
    the slots that advanced the profile.
    """

    depth: Float[Array, " n"]           # final wear depth on the grid [m]
    y: Float[Array, " s"]               # mechanism state at the end
    t: Float[Array, ""]                 # simulated time at the end [s]
    cycles: Float[Array, ""]            # real cycles represented
    dynamic_cycles: Array               # dynamic cycles simulated (incl. warm-up)
    load_sliding: Float[Array, ""]      # A-weighted sum of int N ds [N m]
    status: Array                       # 0 ok, 1 worn through, 2 solver failure, 3 out of slots
    fail_cycles: Float[Array, ""]       # real cycles done when it stopped
    fail_depth: Float[Array, ""]        # max depth when it stopped [m]
    history: dict
    state: WearState | None = None  # engine state at the end (`Evolver`): resumable

    def check(self, what: str = "wear evolution") -> "EvolutionResult":
        """Raise `WearLimitError` (carrying this result) if the run stopped early."""
        status = int(self.status)
        if status == STATUS_OK:
            return self
        cyc, dep = float(self.fail_cycles), float(self.fail_depth) * 1e3
        if status == STATUS_PIERCED:
            msg = (f"{what}: the wear reached the bushing wall after {cyc:.0f} cycles "
                   f"(max depth {dep:.4f} mm); stopped, results so far kept")
        elif status == STATUS_INCOMPLETE:
            msg = (f"{what}: all max_dynamic scan slots were used after {cyc:.0f} cycles "
                   f"(max depth {dep:.4f} mm) before reaching the requested cycles; raise "
                   "max_dynamic or loosen the extrapolation tolerances")
        else:
            msg = (f"{what}: the dynamic integration failed after {cyc:.0f} cycles "
                   f"(max depth {dep:.4f} mm); stopped, results so far kept. Tighten "
                   "the cycle tolerances or reduce the extrapolation factor")
        raise WearLimitError(msg, self)


def _with_profile(mech: Mechanism, index: int, clearance):
    return eqx.tree_at(lambda m: m.forces[index].profile.clearance, mech, clearance)


def worn_mechanism(mech: Mechanism, joint: str, depth) -> Mechanism:
    """``mech`` with the bushing of clearance joint ``joint`` worn by ``depth`` [m]
    on its profile grid (e.g. ``EvolutionResult.depth``): the mechanism of the
    next dynamic cycle."""
    index, el = clearance_element(mech, joint)
    return _with_profile(mech, index, el.profile.clearance + depth)


def evolve(
    mech: Mechanism,
    joint: str,
    y0: Float[Array, " s"],
    cycles,
    *,
    period,
    method: str = "constant",
    extrapolation=1.0,
    max_dynamic: int | None = None,
    rtol: float = 1e-2,
    atol: float = 1e-7,
    wall_thickness=None,
    warmup_cycles: int = 1,
    adaptive: dict | None = None,
    cycle_rtol: float = CYCLE_RTOL,
    cycle_atol: float = CYCLE_ATOL,
    adjoint=None,
    max_steps: int = 200_000,
    cycle_solver=None,
    start: WearState | None = None,
    slots: int | None = None,
) -> EvolutionResult:
    """Evolve the wear of clearance joint ``joint`` over ``cycles`` real cycles.

    ``period`` [s]: one crank cycle (2 pi / omega).  ``y0``: state at t = 0.
    ``extrapolation``: A for "constant" (static number of scan steps:
    ceil(cycles / A); ``cycles`` must then be a Python number); A_0 for
    "adaptive" (default 1 % of the run).  ``rtol``/``atol`` [m]: tolerance of
    method "error".  ``wall_thickness`` [m]: stop when max depth reaches it.
    ``warmup_cycles`` dynamic cycles are run first and their wear discarded
    (start-up transient of the pin from the centred position; the thesis drops
    its first ~1.3 revolutions too).  ``cycle_rtol``, ``cycle_atol``,
    ``cycle_solver`` (default Tsit5; `diffwear.wear.cycle.CYCLE_INTEGRATORS`),
    ``adjoint``, ``max_steps``: each dynamic cycle's integration.

    Resuming: ``start`` is an engine state (``EvolutionResult.state`` of an
    earlier call, or `Evolver.init`); the warm-up is then skipped and ``y0``
    ignored.  ``slots`` scan slots are run (default: all of the method's).  See
    `ChunkedEvolution` for a checkpointing driver.
    """
    require_float64("evolve")
    ev = Evolver(mech, joint, cycles, period=period, method=method,
                 extrapolation=extrapolation, max_dynamic=max_dynamic, rtol=rtol, atol=atol,
                 wall_thickness=wall_thickness, warmup_cycles=warmup_cycles, adaptive=adaptive,
                 cycle_rtol=cycle_rtol, cycle_atol=cycle_atol, adjoint=adjoint,
                 max_steps=max_steps, cycle_solver=cycle_solver)
    state = ev.init(y0) if start is None else start
    state, hist = ev.run(state, ev.n_slots if slots is None else int(slots))
    return ev.result(state, hist)


class Evolver:
    """One joint's wear evolution on the wear engine (`diffwear.wear.engine`):
    the dynamic term (`DynamicWear`), the extrapolation solver and the stop at
    ``cycles`` (or the wall).  `init` (warm-up, the initial state), `run`
    (``length`` scan slots from a state), `result`.  Running the slots in
    several pieces, each from the state the previous one returned, computes
    exactly what one scan does.  Build it inside a jitted function from
    traced mechanism leaves."""

    def __init__(self, mech: Mechanism, joint: str, cycles, *, period, method="constant",
                 extrapolation=1.0, max_dynamic=None, rtol=1e-2, atol=1e-7,
                 wall_thickness=None, warmup_cycles=1, adaptive=None,
                 cycle_rtol=CYCLE_RTOL, cycle_atol=CYCLE_ATOL, adjoint=None,
                 max_steps=200_000, cycle_solver=None):
        self.strategy = extrapolation_method(method, extrapolation=extrapolation, rtol=rtol,
                                             atol=atol, adaptive=adaptive)
        _, el = clearance_element(mech, joint)
        law, _ = wear_parts(el)
        self.radius, self.bdepth = el.bushing_radius, law.depth
        settings = CycleSettings(cycle_rtol, cycle_atol, cycle_solver, adjoint, max_steps)
        self.term = self.make_term(mech, joint, jnp.asarray(period, dtype=float), settings)
        self.warmup_cycles = int(warmup_cycles)
        self.cycles_arr = jnp.asarray(cycles, dtype=float)
        stop = Stop(cycles=cycles, wall=wall_thickness)
        self.n_slots = self.strategy.slots(stop, max_dynamic)
        self.engine = Engine(self.term, self.strategy, stop, slots=self.n_slots,
                             keep_profiles=True)

    def make_term(self, mech, joint, period, settings) -> DynamicWear:
        """The wear term of one dynamic cycle (the FEM route's is another)."""
        return DynamicWear(mech, (joint,), period, settings)

    def init(self, y0) -> WearState:
        """Warm-up cycles (wear discarded), then the initial engine state."""
        memory, ok = self.term.warm_up(y0, self.warmup_cycles)
        state = initial_state(self.term.zeros(), memory, evaluations=self.warmup_cycles, ok=ok)
        return self.engine.init(state)

    def _history(self, h: dict) -> dict:
        return dict(cycles=h["cycles"], max_depth=h["max_depth"][..., 0],
                    volume=worn_volume(h["depth"][0], self.radius, self.bdepth),
                    extrapolation=h["step"], valid=h["valid"], dynamic_cycles=h["evaluations"])

    def run(self, state: WearState, length: int):
        """``length`` scan slots from ``state``: (new state, history of these slots)."""
        state, hist = self.engine.run(state, length)
        return state, self._history(hist)

    def idle_record(self, state: WearState) -> dict:
        """The history entry of a slot after the end (what `run` records there)."""
        return self._history(self.engine.idle_record(state))

    def result(self, final: WearState, hist: dict) -> EvolutionResult:
        done = self.engine.finish(final)
        return EvolutionResult(
            depth=done.h[0], y=done.memory["y"], t=done.memory["t"], cycles=done.n,
            dynamic_cycles=done.evaluations, load_sliding=done.load_sliding[0],
            status=done.status, fail_cycles=done.fail_n, fail_depth=done.fail_h, history=hist,
            state=final)


# ------------------------------------------------------- chunks and checkpoints
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
        return not (int(state.status) == STATUS_OK and float(state.n) < self.cycles - 1e-9)

    def run(self, start: Checkpoint | None = None, on_chunk=None) -> EvolutionResult:
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
