"""Wear models: how the wear of one crank cycle is computed, as strategy
objects that every consumer of wear takes (as diffrax takes a solver).

* `Dynamic`: the reference.  The mechanism with its clearance joints is
  integrated over each simulated cycle (Baumgarte DAE with the stiff EFM
  contact); the pin may impact and leave the wall.
* `QuasiStatic`: the pin at the equilibrium of the EFM springs (or the oil
  film and asperities) under the loads of the ideal mechanism; smooth, exact
  gradients, milliseconds per cycle; valid while the contact is kept (it
  checks).
* `FemRoute`: the dynamic model with the wear pressure of a finite-element
  bushing ring (thesis Ch. 5).

Each solves the wear of its joints to a number of cycles or to a depth limit
(`solve`, one `WearSolution`; `evolve` and `life`, `cycles_to_limit`, are
calls of it) and gives the joint force at the end, on the wear engine
(`diffwear.wear._engine`, private: its extension points, the term, the
solver, the stop and the state, are re-exported here).
A model may carry a modifier (`AbstractWearModifier`: hooks on the profile
each cycle sees and on the rate of each step), which is how the calibration's
effects reach them.
The models are the physics: a run of one (compiled once, timed, in chunks
with checkpoints) is `execution.run_model`, and what the reports say of a
model is `diffwear.studies.model_words`.
"""

from ..wear._engine import (
    MAX_CYCLES,
    AbstractWearSolver,
    AbstractWearTerm,
    CycleWear,
    Stop,
    WearState,
)
from ..wear.modifier import AbstractWearModifier, JointGeometry
from ..wear.solution import WearSolution
from ._base import AbstractWearModel
from .dynamic import Dynamic
from .execution import (
    Checkpoint,
    Checkpoints,
    ChunkedEvolution,
    RunTimes,
    load_checkpoint,
    run_model,
    save_checkpoint,
)
from .fem import FemRoute
from .life import cycles_to_limit
from .quasi_static import QuasiStatic, joint_mass

__all__ = ["AbstractWearModel", "WearSolution", "Dynamic", "QuasiStatic", "FemRoute",
           "cycles_to_limit", "joint_mass", "run_model", "Checkpoints", "RunTimes",
           "ChunkedEvolution", "Checkpoint", "save_checkpoint", "load_checkpoint", "MAX_CYCLES",
           "AbstractWearModifier", "JointGeometry", "AbstractWearTerm", "AbstractWearSolver",
           "CycleWear", "Stop", "WearState"]
