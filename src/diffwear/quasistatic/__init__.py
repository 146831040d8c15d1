"""The quasi-static joint model: the pin at the equilibrium of the EFM springs.

`QuasiStatic` is the wear-model strategy (beside `diffwear.wear.Dynamic`);
`cycle_loads` the ideal mechanism's joint loads; `QuasiStaticJoint` one EFM
joint's equilibrium, wear per cycle and its exact response to the profile;
`LubricatedQuasiStaticJoint` the same for a lubricated joint (film plus
asperities).
"""

from .joint import Equilibrium, QuasiStaticJoint
from .loads import CycleLoads, JointLoads, cycle_loads, ideal_parent
from .lubricated import LubricatedEquilibrium, LubricatedQuasiStaticJoint
from .model import QuasiStatic, QuasiStaticEvolution, joint_mass

__all__ = ["Equilibrium", "QuasiStaticJoint", "LubricatedEquilibrium",
           "LubricatedQuasiStaticJoint", "CycleLoads", "JointLoads", "cycle_loads",
           "ideal_parent", "QuasiStatic", "QuasiStaticEvolution", "joint_mass"]
