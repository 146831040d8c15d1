import jax

jax.config.update("jax_enable_x64", True)

import diffwear  # noqa: E402,F401  (also enables x64)
