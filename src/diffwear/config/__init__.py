"""The input formats: mechanism files (``diffwear run FILE.toml``) and sweep
files (`sweep.load_sweep`).

`load` reads a file into a `MechanismFile` (mechanism, coordinate guess, integration
settings, requested outputs); every problem is an `InputError` naming the file,
the key path and what is allowed.  New element types register in
`JOINT_TYPES` / `FORCE_TYPES` (see `elements`); units live in `units.DIMENSIONS`.
"""

from . import schema, units
from .clearance import CLEARANCE
from .elements import FORCE_TYPES, JOINT_TYPES, ElementType, FieldError

JOINT_TYPES["clearance"] = CLEARANCE
from .loader import load, load_dict, loads
from .mechanism_file import ContactOutput, MechanismFile, ReactionOutput, Simulation

__all__ = [
    "schema", "units", "FORCE_TYPES", "JOINT_TYPES", "ElementType", "FieldError", "load",
    "load_dict", "loads",
    "ContactOutput", "ReactionOutput", "Simulation", "MechanismFile",
]
