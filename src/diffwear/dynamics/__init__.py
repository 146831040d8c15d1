"""Dynamics: Baumgarte DAE, diffrax integration (with post-stabilisation as an
option), kinematics, reactions."""

from .equations import Baumgarte, accelerations, vector_field
from .kinematics import (
    assemble,
    check_assembly,
    consistent_state,
    kinematic_accelerations,
    kinematic_analysis,
    velocities,
)
from .projection import ConstraintProjection, project_to_constraints
from .reactions import along_trajectory, driver_torque, reaction_wrench
from .rosenbrock import ROS3P, ROS34PW2, AbstractRosenbrock, Rodas4, RosenbrockTableau
from .simulate import Trajectory, simulate

__all__ = [
    "Baumgarte", "accelerations", "vector_field", "assemble", "check_assembly",
    "consistent_state", "kinematic_accelerations", "kinematic_analysis", "velocities",
    "along_trajectory", "driver_torque", "reaction_wrench", "Trajectory", "simulate",
    "AbstractRosenbrock", "ROS3P", "ROS34PW2", "Rodas4", "RosenbrockTableau",
    "ConstraintProjection", "project_to_constraints",
]
