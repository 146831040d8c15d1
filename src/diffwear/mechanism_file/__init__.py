"""A loaded mechanism file (`diffwear.config.MechanismFile`) run as a whole:
its motion (`motion`: initial state, trajectory, reactions, contacts, up-front
checks), what its size will cost to compile (`size`) and the wear of its
clearance joints (`wear`: quasi-static or dynamic, each joint stopped at its
bushing wall).  ``diffwear run FILE`` writes what these
compute (`diffwear.cli.run`)."""

from . import wear
from .motion import (
    Results,
    check_motion,
    check_step_budget,
    contact_warnings,
    first_driver,
    initial_state,
    integrate,
    postprocess,
)
from .size import check_size
from .wear import evolve_file, evolve_file_dynamic

__all__ = ["Results", "check_motion", "check_size", "check_step_budget", "contact_warnings",
           "evolve_file", "evolve_file_dynamic", "first_driver", "initial_state", "integrate",
           "postprocess", "wear"]
