"""The quasi-static joint model: the pin at the equilibrium of the EFM springs.

The wear model built on it is `diffwear.models.QuasiStatic`;
`cycle_loads` the ideal mechanism's joint loads; `QuasiStaticJoint` one EFM
joint's equilibrium, wear per cycle and its exact response to the profile;
`LubricatedQuasiStaticJoint` the same for a lubricated joint (film plus
asperities).
"""

from .joint import Equilibrium, QuasiStaticJoint
from .loads import CycleLoads, JointLoads, cycle_loads, ideal_parent
from .lubricated import LubricatedEquilibrium, LubricatedQuasiStaticJoint

__all__ = ["Equilibrium", "QuasiStaticJoint", "LubricatedEquilibrium",
           "LubricatedQuasiStaticJoint", "CycleLoads", "JointLoads", "cycle_loads",
           "ideal_parent"]
