"""Plane-strain finite-element model of a bushing ring and its pin contact.

- `mesh`: structured Q9 mesh of a (worn) ring, `ring_mesh`.
- `element`, `elasticity`: the Q9 element, dense stiffness, solves.
- `condense`: compliance of the inner surface (radial nodal force ->
  radial displacement), consistent pressure loads.
- `contact`: frictionless unilateral contact of a rigid round pin, for a given
  pin offset or a given joint force, differentiable by implicit differentiation.
"""

from .condense import inner_compliance, inner_stiffness, pressure_load_matrix, tributary_lengths
from .contact import ContactSolution, RingContact
from .mesh import RingMesh, ring_mesh

__all__ = ["ContactSolution", "RingContact", "RingMesh", "ring_mesh", "inner_compliance",
           "inner_stiffness", "pressure_load_matrix", "tributary_lengths"]
