"""Elastic materials and the contact stiffnesses derived from them."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._checks import check_positive, check_range, float_leaf


class Material(eqx.Module):
    """Isotropic linear-elastic material: Young's modulus E [Pa], Poisson's ratio nu."""

    youngs_modulus: Float[Array | np.ndarray, ""]  # NumPy float64 when given numbers
    poisson_ratio: Float[Array | np.ndarray, ""]

    def __init__(self, youngs_modulus, poisson_ratio, name: str = "material"):
        check_positive(f"{name}: Young's modulus E [Pa]", youngs_modulus)
        check_range(f"{name}: Poisson ratio nu", poisson_ratio, -1.0, 0.5,
                    low_open=True, high_open=True)
        self.youngs_modulus = float_leaf(youngs_modulus)
        self.poisson_ratio = float_leaf(poisson_ratio)

    @property
    def compliance_h(self) -> Float[Array | np.ndarray, ""]:
        """h = (1 - nu^2) / (pi E) [1/Pa] (thesis Eq. 3-4)."""
        nu = self.poisson_ratio
        return (1.0 - nu * nu) / (jnp.pi * self.youngs_modulus)

    @property
    def foundation_modulus(self) -> Float[Array | np.ndarray, ""]:
        """E_W = (1 - nu) E / ((1 + nu)(1 - 2 nu)) [Pa]: the constrained (oedometric)
        modulus of a thin layer (thesis Eq. 6-3)."""
        nu = self.poisson_ratio
        return (1.0 - nu) * self.youngs_modulus / ((1.0 + nu) * (1.0 - 2.0 * nu))


# Thesis Table 3-2 / 5-2 / 6-2 / 7-2 (E in Pa).
STEEL = Material(206.8e9, 0.29, name="steel (Table 3-2)")
PTFE = Material(0.5e9, 0.38, name="PTFE (Table 3-2)")
