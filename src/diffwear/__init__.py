"""diffwear: differentiable planar multibody dynamics with clearance and wear.

Importing diffwear enables float64 in JAX (``jax_enable_x64``): contact
penetrations of micrometres on metre-scale positions are meaningless in float32.
"""

import jax as _jax

_jax.config.update("jax_enable_x64", True)

from . import dynamics, mechanism, presets  # noqa: E402
from .errors import DiffwearError, InputError, SolverError  # noqa: E402
from .gradcheck import GradCheck, gradcheck  # noqa: E402

try:  # the one version string is pyproject.toml's
    from importlib.metadata import version as _version

    __version__ = _version("diffwear")
except Exception:  # pragma: no cover - running from a source tree without metadata
    __version__ = "0+unknown"

__all__ = ["dynamics", "mechanism", "presets", "DiffwearError", "InputError", "SolverError",
           "GradCheck", "gradcheck"]
