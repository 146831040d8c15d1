"""`Dynamic`: the dynamic wear model (the reference), as a strategy object.

Each simulated cycle integrates the mechanism with its clearance joints
(Baumgarte DAE with the stiff EFM contact, diffrax); the pin may impact and
leave the wall.  Its evolution extrapolates the wear of one simulated cycle
over many real ones (`diffwear.wear.extrapolation`); its life steps in depth
(`diffwear.wear.life`).
"""

from __future__ import annotations

import math
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp

from .._checks import check_int_option
from ..contact import contact_history
from ..errors import InputError
from ..wear.cycle import wear_cycle
from ..wear.dynamic_term import CycleSettings
from ..wear.evolution import Evolver, worn_mechanism
from ..wear.extrapolation import AbstractExtrapolation, Constant
from ..wear.life import dynamic_cycles_to_limit
from ..wear.modifier import AbstractWearModifier
from ..wear.solution import WearSolution
from ..wear.status import not_an_answer, not_computed
from ._base import AbstractWearModel


class Dynamic(AbstractWearModel):
    """The dynamic model (the reference): each simulated cycle integrates the
    mechanism with its EFM clearance joints.

    ``cycle``: how each dynamic cycle is integrated (`CycleSettings`: default
    Tsit5 at 1e-6; ``Rodas4()`` at 1e-4 is several times faster, see
    `diffwear.wear.cycle.CYCLE_INTEGRATORS`; for derivatives on a stiff
    contact use ``Rodas4()`` at 1e-6, or, while the pin stays in contact,
    ``Rodas4(sensitivity="ros2")`` at a quarter of the cost: the tangents are
    not error-controlled, see the guide "Which derivatives to trust";
    ``adjoint=diffrax.ForwardMode()`` for `jax.jacfwd`); ``warmup_cycles``
    dynamic cycles run first with their wear discarded.

    Lives: ``steps`` scan slots the fastest-wearing joint takes to a wear
    limit (the accuracy knob; error ~ 1 / steps), ``implicit``: the linearly
    implicit profile update (else explicit Euler).  Evolutions (one wearing
    joint): ``extrapolation`` (`Constant`, `Adaptive`, `ErrorControlled`;
    default constant A = cycles / ``dynamic_cycles``), ``max_dynamic`` scan
    slots of the adaptive methods (default 4 ``dynamic_cycles``),
    ``modifier``: an `AbstractWearModifier` of the joint's wear (its rate
    factor is held over each extrapolated step), ``force_samples``: keep
    each dynamic cycle's |joint force| at this many states in the history
    (``slots["force"]``).
    """

    name: ClassVar[str] = "dynamic"
    exact_gradients: ClassVar[bool] = False
    steps: int = eqx.field(static=True, default=10)
    implicit: bool = eqx.field(static=True, default=True)
    cycle: CycleSettings = CycleSettings()
    warmup_cycles: int = eqx.field(static=True, default=1)
    extrapolation: AbstractExtrapolation | None = None
    dynamic_cycles: int = eqx.field(static=True, default=50)
    max_dynamic: int | None = eqx.field(static=True, default=None)
    modifier: AbstractWearModifier | None = None
    force_samples: int | None = eqx.field(static=True, default=None)

    def __check_init__(self):
        # counts of slots and cycles: a zero or negative one has nothing to
        # integrate (an `InputError` here, not a failure in the traced program)
        check_int_option("Dynamic: steps", self.steps, 1)
        check_int_option("Dynamic: warmup_cycles", self.warmup_cycles, 0)
        check_int_option("Dynamic: dynamic_cycles", self.dynamic_cycles, 1)
        if self.max_dynamic is not None:
            check_int_option("Dynamic: max_dynamic", self.max_dynamic, 1)

    def solver(self, cycles) -> AbstractExtrapolation:
        """The extrapolation of an evolution over ``cycles`` real cycles."""
        if self.extrapolation is not None:
            return self.extrapolation
        return Constant(max(1.0, float(math.ceil(float(cycles) / self.dynamic_cycles))))

    def evolver(self, mech, joint: str, cycles, *, period, wall_thickness=None) -> Evolver:
        """The evolution of ``joint`` set up (`Evolver`: run it whole or in chunks)."""
        return Evolver(mech, joint, cycles, period=period, method=self.solver(cycles),
                       max_dynamic=(4 * self.dynamic_cycles if self.max_dynamic is None
                                    else self.max_dynamic),
                       wall_thickness=wall_thickness, warmup_cycles=self.warmup_cycles,
                       cycle=self.cycle, modifier=self.modifier,
                       force_samples=self.force_samples)

    def solve(self, mech, joints, y0, *, period, cycles=None, limit=None,
              wall_thickness=None) -> WearSolution:
        """The wear of ``joints`` to ``cycles`` real cycles (one joint: its
        evolution, `evolver`; ``wall_thickness`` [m] stops it) or the lives of
        ``joints`` to ``limit`` [m] of peak depth (several joints together:
        `diffwear.wear.life.dynamic_cycles_to_limit`, no wall): two
        integrations, so one of ``cycles`` and ``limit``, not both."""
        if (cycles is None) == (limit is None):
            raise InputError(f"{type(self).__name__}.solve: give cycles= (an evolution) or "
                             f"limit= (a life), not {'both' if cycles is not None else 'neither'}"
                             "; allowed: one of them (QuasiStatic takes both)")
        if limit is not None:
            if self.modifier is not None or self.force_samples is not None:
                raise InputError(f"{type(self).__name__}.solve: a life to limit= steps in "
                                 "depth, where a modifier's rate over a step and a force "
                                 "trace per cycle are not defined; allowed: cycles= with "
                                 "modifier= or force_samples=")
            if wall_thickness is not None:
                raise InputError(f"{type(self).__name__}.solve: a life to limit= runs "
                                 f"without a wall, got wall_thickness={wall_thickness!r}; "
                                 "allowed: None")
            return self._life(mech, tuple(joints), y0, period=period, limit=limit)
        joints = one_joint(joints)
        wall = None
        if wall_thickness is not None:
            wall = jnp.reshape(jnp.asarray(wall_thickness, dtype=float), (-1,))[0]
        ev = self.evolver(mech, joints[0], cycles, period=period, wall_thickness=wall)
        solution = ev.solve(y0)
        # a failed or cut-short evolution has no final profile: NaN with NaN
        # derivatives (the profiles reached stay in ``history``, ``slots`` and ``state``)
        depth = not_an_answer(solution.depth[0], not_computed(solution.result),
                              (self, mech, y0, period, cycles, wall_thickness))
        return eqx.tree_at(lambda e: e.depth, solution, (depth,))

    def _life(self, mech, joints, y0, *, period, limit) -> WearSolution:
        """The lives of ``joints`` (`dynamic_cycles_to_limit`): the history
        holds cycles, peak depths and valid slots, not the profiles."""
        return dynamic_cycles_to_limit(
            mech, joints, y0, period=period, limit=limit, steps=self.steps,
            implicit=self.implicit, warmup_cycles=self.warmup_cycles, cycle=self.cycle)

    def check_joints(self, mech, joints, what: str = "mechanism") -> None:
        """One wearing joint.  A lubricated one is taken: its cycles run on
        Rodas4 at a tolerance scaled by its film's roughness, and its wear is
        the asperities' (`diffwear.wear.cycle.lubricated_cycle`)."""
        one_joint(joints, what)

    def cycle_histories(self, mech, joint, y0, *, period, evolution: WearSolution) -> tuple:
        """The first dynamic cycle after a warm-up one, and the last: on the
        final profile after one settling cycle from the evolution's end state
        (that state belongs to the profile before the last wear step; on the
        deeper final profile the pin would first drop into the groove, an
        impact the gradually worn joint never sees).  Both at the default
        cycle tolerances, `CYCLE_SAMPLES` states each."""
        end = _end_state(evolution)
        warm = _cycle(mech, joint, y0, 0.0, period)
        first = _cycle(mech, joint, warm.y_end, period, period)
        worn = worn_mechanism(mech, joint, end.h[0])
        y, t = end.memory["y"], end.memory["t"]
        settle = _cycle(worn, joint, y, t, period)
        last = _cycle(worn, joint, settle.y_end, t + period, period)
        crank = 2 * jnp.pi * (first.ts - first.ts[0]) / period
        return (contact_history(mech, joint, first.ys), contact_history(worn, joint, last.ys),
                crank)

    def joint_force(self, mech, joint, y0, *, period, evolution: WearSolution,
                    samples: int = 180):
        """One more dynamic cycle on the final profile, from the evolution's
        end state (``evolution.state``), at ``samples`` equally spaced
        states (its end, a repeat of its start, left out)."""
        end = _end_state(evolution)
        worn = worn_mechanism(mech, joint, end.h[0])
        cyc = wear_cycle(worn, joint, end.memory["y"], end.memory["t"], period,
                         n_save=samples + 1, **self.cycle.options())
        assert cyc.ys is not None  # saved: n_save is given
        return contact_history(worn, joint, cyc.ys).force_magnitude[:-1]


def one_joint(joints, what: str = "mechanism") -> tuple[str]:
    """``joints`` when it is one joint (the dynamic models evolve one), else
    an `InputError`; ``what`` names the mechanism's source in the message."""
    joints = tuple(joints)
    if len(joints) != 1:
        raise InputError(f"the dynamic wear model evolves one clearance joint over a fixed "
                         f"number of cycles; this {what} wears {len(joints)} "
                         f"({', '.join(joints)}); allowed: --model quasi-static, or one "
                         "joint with a wear law")
    return joints  # type: ignore[return-value]


# States saved over the first and the last cycle of `Dynamic.cycle_histories`
# (400 intervals: 0.9 deg of crank).
CYCLE_SAMPLES = 401


@eqx.filter_jit
def _cycle(mech, joint, y, t, period):
    return wear_cycle(mech, joint, y, t, period, n_save=CYCLE_SAMPLES)


def _end_state(evolution: WearSolution):
    """The engine's final state of a dynamic evolution (`Dynamic.solve`)."""
    if evolution.state is None:
        raise InputError("the joint force at the end needs a dynamic evolution's final state "
                         "(WearSolution.state); this solution has none")
    return evolution.state


__all__ = ["Dynamic", "one_joint"]
