"""diffwear: differentiable planar multibody dynamics with clearance and wear.

Importing diffwear enables float64 in JAX (``jax_enable_x64``): contact
penetrations of micrometres on metre-scale positions are meaningless in float32.
"""

import jax as _jax

_jax.config.update("jax_enable_x64", True)

from . import dynamics, mechanism, presets  # noqa: E402
from .errors import DiffwearError, InputError, SolverError  # noqa: E402
from .gradcheck import GradCheck, gradcheck  # noqa: E402

__version__ = "0.1.0"

__all__ = ["dynamics", "mechanism", "presets", "DiffwearError", "InputError", "SolverError",
           "GradCheck", "gradcheck"]
