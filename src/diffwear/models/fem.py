"""`FemRoute`: the dynamic model with the wear pressure of a finite-element
bushing ring (thesis Ch. 5; `diffwear.wear.fem_route`)."""

from __future__ import annotations

from typing import ClassVar

from ..errors import InputError
from ..wear.fem_route import FemEvolver, FemWearModel
from ..wear.solution import WearSolution
from .dynamic import Dynamic


class FemRoute(Dynamic):
    """The dynamic model whose wear pressure comes from the FE ring ``fem``
    (`FemWearModel`, e.g. `diffwear.wear.fem_route.default_model`): the
    dynamics still run with the elastic foundation, which supplies the joint
    force and the pin's rotation; the profile evolves with constant
    extrapolation.  Lives are not computed on this route (`Dynamic` or
    `QuasiStatic`)."""

    name: ClassVar[str] = "fem"
    fem: FemWearModel | None = None

    def __check_init__(self):
        if not isinstance(self.fem, FemWearModel):
            raise InputError(f"FemRoute: fem must be a FemWearModel, got {self.fem!r}")
        if self.modifier is not None or self.force_samples is not None:
            raise InputError("FemRoute: its FE wear term takes no modifier or force trace; "
                             "allowed: Dynamic(modifier=..., force_samples=...)")

    def evolver(self, mech, joint: str, cycles, *, period, wall_thickness=None) -> FemEvolver:
        assert self.fem is not None
        return FemEvolver(mech, joint, cycles, fem=self.fem, period=period,
                          method=self.solver(cycles), wall_thickness=wall_thickness,
                          warmup_cycles=self.warmup_cycles, cycle=self.cycle)

    def reference(self) -> Dynamic:
        """The same dynamic model with the EFM pressure."""
        return Dynamic(steps=self.steps, implicit=self.implicit, cycle=self.cycle,
                       warmup_cycles=self.warmup_cycles, extrapolation=self.extrapolation,
                       dynamic_cycles=self.dynamic_cycles, max_dynamic=self.max_dynamic)

    def solve(self, mech, joints, y0, *, period, cycles=None, limit=None,
              wall_thickness=None) -> WearSolution:
        """The wear of one joint to ``cycles`` real cycles (`Dynamic.solve`);
        a life to ``limit`` is an `InputError` on this route."""
        if limit is not None:
            raise InputError("the FEM route evolves the wear over a number of cycles; lives "
                             "to a depth limit come from Dynamic() or QuasiStatic()")
        return super().solve(mech, joints, y0, period=period, cycles=cycles,
                             wall_thickness=wall_thickness)


__all__ = ["FemRoute"]
