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
from ..wear.evolution import EvolutionResult, Evolver, worn_mechanism
from ..wear.extrapolation import AbstractExtrapolation, Constant
from ..wear.life import LifeResult, dynamic_cycles_to_limit
from ..wear.profile_ode import ProfileHistory
from ..wear.status import not_an_answer, not_computed, stack
from ._base import AbstractWearModel, WearEvolution


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
    slots of the adaptive methods (default 4 ``dynamic_cycles``).
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

    def __check_init__(self):
        # counts of slots and cycles: a zero or negative one has nothing to
        # integrate (an `InputError` here, not a failure in the traced program)
        check_int_option("Dynamic: steps", self.steps, 1)
        check_int_option("Dynamic: warmup_cycles", self.warmup_cycles, 0)
        check_int_option("Dynamic: dynamic_cycles", self.dynamic_cycles, 1)
        if self.max_dynamic is not None:
            check_int_option("Dynamic: max_dynamic", self.max_dynamic, 1)

    def life(self, mech, joints, y0, *, period, limit) -> LifeResult:
        return dynamic_cycles_to_limit(
            mech, joints, y0, period=period, limit=limit, steps=self.steps,
            implicit=self.implicit, warmup_cycles=self.warmup_cycles, cycle=self.cycle)

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
                       cycle=self.cycle)

    def evolve(self, mech, joints, y0, *, period, cycles, wall_thickness=None
               ) -> WearEvolution:
        joints = one_joint(joints)
        wall = None
        if wall_thickness is not None:
            wall = jnp.reshape(jnp.asarray(wall_thickness, dtype=float), (-1,))[0]
        ev = self.evolver(mech, joints[0], cycles, period=period, wall_thickness=wall)
        evolution = as_evolution(ev.solve(y0))
        # a failed or cut-short evolution has no final profile: NaN with NaN
        # derivatives (the profiles reached stay in ``history`` and ``detail``)
        depth = not_an_answer(evolution.depth[0], not_computed(evolution.status),
                              (self, mech, y0, period, cycles, wall_thickness))
        return eqx.tree_at(lambda e: e.depth, evolution, (depth,))

    def check_joints(self, mech, joints, what: str = "mechanism") -> None:
        """One wearing joint.  A lubricated one is taken: its cycles run on
        Rodas4 at a tolerance scaled by its film's roughness, and its wear is
        the asperities' (`diffwear.wear.cycle.lubricated_cycle`)."""
        one_joint(joints, what)

    def cycle_histories(self, mech, joint, y0, *, period, evolution: WearEvolution) -> tuple:
        """The first dynamic cycle after a warm-up one, and the last: on the
        final profile after one settling cycle from the evolution's end state
        (that state belongs to the profile before the last wear step; on the
        deeper final profile the pin would first drop into the groove, an
        impact the gradually worn joint never sees).  Both at the default
        cycle tolerances, `CYCLE_SAMPLES` states each."""
        res = evolution.detail
        warm = _cycle(mech, joint, y0, 0.0, period)
        first = _cycle(mech, joint, warm.y_end, period, period)
        worn = worn_mechanism(mech, joint, res.depth)
        settle = _cycle(worn, joint, res.y, res.t, period)
        last = _cycle(worn, joint, settle.y_end, res.t + period, period)
        crank = 2 * jnp.pi * (first.ts - first.ts[0]) / period
        return (contact_history(mech, joint, first.ys), contact_history(worn, joint, last.ys),
                crank)

    def joint_force(self, mech, joint, y0, *, period, evolution: WearEvolution,
                    samples: int = 180):
        """One more dynamic cycle on the final profile, from the evolution's
        end state (``evolution.detail``), at ``samples`` equally spaced
        states (its end, a repeat of its start, left out)."""
        res = evolution.detail
        worn = worn_mechanism(mech, joint, res.depth)
        cyc = wear_cycle(worn, joint, res.y, res.t, period, n_save=samples + 1,
                         **self.cycle.options())
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


def as_evolution(res: EvolutionResult) -> WearEvolution:
    """One joint's `EvolutionResult` as a `WearEvolution` (``detail`` keeps it)."""
    h = res.history
    nan = jnp.full(1, jnp.nan)
    return WearEvolution(
        depth=(res.depth,), cycles=res.cycles, joint_cycles=res.cycles[None],
        status=res.status, joint_status=stack([res.status]), contact_margin=nan,
        contact_margin_worn=nan,
        history=(ProfileHistory(
            cycles=jnp.concatenate([jnp.zeros(1), h["cycles"]]),
            peak=jnp.concatenate([jnp.zeros(1), h["max_depth"]]),
            depth=jnp.concatenate([jnp.zeros_like(res.depth)[None], h["depth"]]),
            valid=jnp.concatenate([jnp.ones(1, bool), h["valid"]])),),
        detail=res)


__all__ = ["Dynamic", "as_evolution", "one_joint"]
