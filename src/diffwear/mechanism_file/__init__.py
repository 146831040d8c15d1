"""A loaded mechanism file (`diffwear.config.MechanismFile`) run as a whole:
its motion (`motion`: initial state, trajectory, reactions, contacts, up-front
checks), how long its start-up transient lasts (`transient`), what its size
will cost to compile (`size`) and the wear of its clearance joints (`wear`:
quasi-static or dynamic, each joint stopped at its bushing wall).
``diffwear run FILE`` writes what these compute (`diffwear.cli.run`)."""

from . import wear
from .motion import (
    Results,
    Timed,
    check_motion,
    check_step_budget,
    contact_warnings,
    first_driver,
    force_signals,
    initial_state,
    integrate,
    integrate_timed,
    lubricated,
    motion_integrator,
    postprocess,
    start_up_transient,
)
from .size import check_size
from .transient import Settling, settled_part
from .wear import evolve_file

__all__ = ["Results", "Settling", "Timed", "check_motion", "check_size", "check_step_budget",
           "contact_warnings", "evolve_file",
           "first_driver", "force_signals", "initial_state", "integrate", "integrate_timed",
           "lubricated", "motion_integrator", "postprocess", "settled_part",
           "start_up_transient", "wear"]
