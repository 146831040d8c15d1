"""What every wear model provides: `AbstractWearModel`, whose `solve` returns
one `WearSolution`."""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
from jaxtyping import Array, Float

from ..mechanism import Mechanism
from ..wear.solution import WearSolution


class AbstractWearModel(eqx.Module):
    """How the wear of one crank cycle is computed, and with it the wear of
    many: every consumer of wear (lives, evolutions, the wear studies, the
    bushing design, the sweeps) takes a model object, as diffrax takes a
    solver.

    ``exact_gradients``: the pointwise derivative of its results is the slope
    users want (the quasi-static model), else callers should difference (the
    dynamic model).  ``precomputes``: `prepared` has something to compute that
    does not depend on the bushing design (the quasi-static model's joint
    loads).
    """

    name: eqx.AbstractClassVar[str]
    exact_gradients: eqx.AbstractClassVar[bool]
    precomputes: ClassVar[bool] = False

    @abc.abstractmethod
    def solve(self, mech: Mechanism, joints: tuple[str, ...], y0: Float[Array, " s"], *,
              period, cycles=None, limit=None, wall_thickness=None) -> WearSolution:
        """One integration of the wear of ``joints`` from unworn bushings: to
        ``cycles`` real cycles, to ``limit`` [m] of peak depth (each joint's
        life), or to whichever comes first where the model takes both;
        ``wall_thickness`` [m] (one for all, or one per joint): stop a joint
        whose peak depth reaches it."""

    def evolve(self, mech: Mechanism, joints: tuple[str, ...], y0: Float[Array, " s"], *,
               period, cycles, wall_thickness=None) -> WearSolution:
        """Wear of ``joints`` after ``cycles`` real cycles from unworn bushings
        (`solve` to ``cycles``)."""
        return self.solve(mech, joints, y0, period=period, cycles=cycles,
                          wall_thickness=wall_thickness)

    def life(self, mech: Mechanism, joints: tuple[str, ...], y0: Float[Array, " s"], *,
             period, limit) -> WearSolution:
        """Cycles until the peak wear depth of each joint reaches ``limit`` [m]
        (`solve` to ``limit``; the lives are ``.life``)."""
        return self.solve(mech, joints, y0, period=period, limit=limit)

    @abc.abstractmethod
    def joint_force(self, mech: Mechanism, joint: str, y0: Float[Array, " s"], *, period,
                    evolution: WearSolution, samples: int = 180) -> Float[Array, " T"]:
        """|joint force| [N] of ``joint`` over one cycle at the end of
        ``evolution``, equally spaced over the period (``samples`` of them
        where the model samples the cycle anew)."""

    @abc.abstractmethod
    def cycle_histories(self, mech: Mechanism, joint: str, y0, *, period,
                        evolution: WearSolution) -> tuple:
        """``joint`` over its first cycle (unworn) and its last (at the end of
        ``evolution``): (first, last `diffwear.contact.ContactHistory`, the
        crank angle [rad] of their samples from the cycle's start)."""

    def check_joints(self, mech: Mechanism, joints: tuple[str, ...],
                     what: str = "mechanism") -> None:
        """`InputError` for wearing joints this model does not evolve (none
        here); ``what`` names the mechanism's source in the message."""

    def reference(self) -> "AbstractWearModel | None":
        """The model a run of this one is compared with (the FEM route: the same
        dynamics with the EFM pressure), or None."""
        return None

    def prepared(self, mech: Mechanism, joints: tuple[str, ...], y0, period
                 ) -> "AbstractWearModel":
        """This model with what does not depend on the bushing design computed
        once for ``mech`` (nothing here)."""
        return self
