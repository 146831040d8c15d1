"""Wear evolution of one joint over many crank cycles (thesis Ch. 4-6,
Eqs. 4-18..4-20): `evolve`, the dynamic model's route on the wear engine.

Each scan slot runs one dynamic cycle (`DynamicWear`) with the current
profile, carries the mechanism state from the end of one cycle into the next
(no restart transient) and extrapolates the cycle's wear over many real
cycles by the chosen solver (`Constant`, `Adaptive`, `ErrorControlled`:
`diffwear.wear.extrapolation`).  Everything is a pure function of arrays
(mechanism leaves included), so the whole evolution jits once and
differentiates (reverse or forward mode) w.r.t. the wear coefficient,
clearance, bushing depth and diameter.

Failure (bushing worn through, integrator failure) never raises inside jit:
the evolution stops updating, keeps the results so far and reports its
``result`` (a `diffwear.wear.RESULTS` member); `WearSolution.check` raises
`WearLimitError` naming the cycle and depth, and ``evolve(..., throw=True)``
raises inside jit (`eqx.error_if`, as diffrax's ``diffeqsolve(throw=True)``).
`ChunkedEvolution` runs the same scan in chunks with checkpoints.
"""

from __future__ import annotations

import dataclasses
import math

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import require_float64
from ..errors import InputError
from ..mechanism import Mechanism
from ._engine import Engine, Stop, WearState
from .cycle import clearance_element, wear_parts
from .dynamic_term import CycleSettings, DynamicWear
from .extrapolation import AbstractExtrapolation, Constant
from .modifier import AbstractWearModifier, JointGeometry
from .profile_ode import ProfileHistory
from .solution import WearSolution
from .status import RESULTS, stack


def smooth_max(x: Float[Array, " n"], temperature) -> Float[Array, ""]:
    """Smooth maximum T log(sum exp(x / T)) - T log(n): within T log(n) of max(x)
    and differentiable everywhere (logsumexp with temperature T, units of x)."""
    n = x.shape[0]
    return temperature * (jax.nn.logsumexp(x / temperature) - math.log(n))


def worn_volume(depth_profile, bushing_radius, bushing_depth) -> Float[Array, ""]:
    """Archard volume [m^3]: bushing depth x integral of h R_b dtheta."""
    n = depth_profile.shape[-1]
    return bushing_depth * bushing_radius * (2 * jnp.pi / n) * jnp.sum(depth_profile, axis=-1)


def _with_profile(mech: Mechanism, index: int, clearance):
    return eqx.tree_at(lambda m: m.forces[index].profile.clearance, mech, clearance)


def worn_mechanism(mech: Mechanism, joint: str, depth) -> Mechanism:
    """``mech`` with the bushing of clearance joint ``joint`` worn by ``depth`` [m]
    on its profile grid (e.g. ``WearSolution.depth[0]``): the mechanism of the
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
    method: AbstractExtrapolation = Constant(),
    max_dynamic: int | None = None,
    wall_thickness=None,
    warmup_cycles: int = 1,
    cycle: CycleSettings = CycleSettings(),
    throw: bool = False,
) -> WearSolution:
    """Evolve the wear of clearance joint ``joint`` over ``cycles`` real cycles.

    ``period`` [s]: one crank cycle (2 pi / omega).  ``y0``: state at t = 0.
    ``method``: the extrapolation (`Constant(A)`: ceil(cycles / A) scan
    slots, ``cycles`` then a Python number; `Adaptive`, `ErrorControlled`:
    ``max_dynamic`` scan slots).  ``wall_thickness`` [m]: stop when the max
    depth reaches it.  ``warmup_cycles`` dynamic cycles are run first and
    their wear discarded (start-up transient of the pin from the centred
    position; the thesis drops its first ~1.3 revolutions too).  ``cycle``:
    how each dynamic cycle is integrated (`CycleSettings`).

    Resuming is `Evolver.solve` (``start``: ``WearSolution.state`` of an
    earlier run, or a state of `Evolver.init` or `Evolver.run`; ``slots``:
    how many scan slots to run);
    `ChunkedEvolution` is a checkpointing driver.

    Returns a `WearSolution` of the one joint: its final profile (as
    reached, also where the run stopped early), the engine's ``state`` at
    the end (`Evolver.solve` continues from it) and the record of every scan
    slot (``slots``).

    ``throw``: raise (`eqx.error_if`, at run time inside jit; under
    `jax.vmap` if any point stopped) with the result's message where the
    evolution stopped early, as diffrax's ``diffeqsolve(throw=True)``; by
    default the solution reports it in ``result`` (`WearSolution.check`
    raises outside jit).
    """
    require_float64("evolve")
    ev = Evolver(mech, joint, cycles, period=period, method=method, max_dynamic=max_dynamic,
                 wall_thickness=wall_thickness, warmup_cycles=warmup_cycles, cycle=cycle)
    res = ev.solve(y0)
    return res.result.error_if(res, res.result != RESULTS.ok) if throw else res


class Evolver:
    """One joint's wear evolution on the wear engine (`diffwear.wear._engine`):
    the dynamic term (`DynamicWear`), the extrapolation solver and the stop at
    ``cycles`` (or the wall).  `init` (warm-up, the initial state), `run`
    (``length`` scan slots from a state), `result`.  Running the slots in
    several pieces, each from the state the previous one returned, computes
    exactly what one scan does.  Build it inside a jitted function from
    traced mechanism leaves."""

    def __init__(self, mech: Mechanism, joint: str, cycles, *, period,
                 method: AbstractExtrapolation = Constant(), max_dynamic=None,
                 wall_thickness=None, warmup_cycles=1, cycle: CycleSettings = CycleSettings(),
                 modifier: AbstractWearModifier | None = None, force_samples: int | None = None):
        if not isinstance(method, AbstractExtrapolation):
            raise InputError(f"method must be an extrapolation (Constant(A), Adaptive(), "
                             f"ErrorControlled()), got {method!r}")
        self.strategy = method
        _, el = clearance_element(mech, joint)
        law, _ = wear_parts(el)
        self.radius, self.bdepth = el.bushing_radius, law.depth
        self.term = self.make_term(mech, joint, jnp.asarray(period, dtype=float), cycle)
        self.force_samples = force_samples
        changes: dict = {}
        if modifier is not None:
            changes.update(modifier=modifier, geometry=JointGeometry.of(el))
        if force_samples is not None:
            changes.update(saves=int(force_samples), force_trace=True)
        if changes:
            self.term = dataclasses.replace(self.term, **changes)
        self.warmup_cycles = int(warmup_cycles)
        self.cycles_arr = jnp.asarray(cycles, dtype=float)
        stop = Stop(cycles=cycles, wall=wall_thickness)
        self.n_slots = self.strategy.slots(stop, max_dynamic)
        self.engine = Engine(self.term, self.strategy, stop, slots=self.n_slots,
                             keep_profiles=True, keep_memory=force_samples is not None)

    def make_term(self, mech, joint, period, settings) -> DynamicWear:
        """The wear term of one dynamic cycle (the FEM route's is another)."""
        return DynamicWear(mech, (joint,), period, settings)

    def init(self, y0) -> WearState:
        """Warm-up cycles (wear discarded), then the initial engine state."""
        memory, ok = self.term.warm_up(y0, self.warmup_cycles)
        state = WearState.initial(self.term.zeros(), memory, evaluations=self.warmup_cycles, ok=ok)
        return self.engine.init(state)

    def _history(self, h: dict) -> dict:
        out = dict(cycles=h["cycles"], max_depth=h["max_depth"][..., 0],
                   volume=worn_volume(h["depth"][0], self.radius, self.bdepth),
                   extrapolation=h["step"], valid=h["valid"], dynamic_cycles=h["evaluations"],
                   depth=h["depth"][0])
        if self.force_samples is not None:   # each slot's |joint force| trace
            out["force"] = h["memory"]["force"]
        return out

    def run(self, state: WearState, length: int):
        """``length`` scan slots from ``state``: (new state, history of these slots)."""
        state, hist = self.engine.run(state, length)
        return state, self._history(hist)

    def idle_record(self, state: WearState) -> dict:
        """The history entry of a slot after the end (what `run` records there)."""
        return self._history(self.engine.idle_record(state))

    def solve(self, y0, start: WearState | None = None, slots: int | None = None
              ) -> WearSolution:
        """The evolution from ``y0`` (its warm-up, then every slot) in one call;
        from the engine state ``start`` instead (``y0`` ignored), ``slots``
        of them (default: all)."""
        state = self.init(y0) if start is None else start
        state, hist = self.run(state, self.n_slots if slots is None else int(slots))
        return self.result(state, hist)

    def result(self, final: WearState, hist: dict) -> WearSolution:
        """The `WearSolution` of the slots run to ``final`` with the record
        ``hist`` (the profile as reached: a model masks one that is no
        answer; ``state`` is ``final``, from which `solve` continues)."""
        done = self.engine.finish(final)
        depth = done.h[0]
        nan = jnp.full(1, jnp.nan)
        return WearSolution(
            depth=(depth,), joint_cycles=done.n[None], life=nan, result=done.status,
            joint_result=stack([done.status]), contact_margin=nan, contact_margin_worn=nan,
            stats={"steps": jnp.sum(hist["valid"]).astype(int)[None],
                   "evaluations": done.evaluations, "dynamic_cycles": done.evaluations},
            history=(ProfileHistory.from_slots(jnp.zeros_like(depth), 0.0, hist["cycles"],
                                               hist["max_depth"], hist["valid"],
                                               hist["depth"]),),
            state=final, slots=hist)
