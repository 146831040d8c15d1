"""`gradcheck`: is an autodiff derivative the slope a user wants?

A pointwise derivative of a simulation output is only useful where the output
is smooth at the scale the user cares about.  `gradcheck` compares
`jax.jacfwd` with central differences at several relative steps and returns
a verdict:

* ``"ok"``: autodiff matches the differences at one of the steps within
  ``rtol`` (the larger steps may carry truncation error);
* ``"mismatch"``: the differences agree with each other but not with autodiff
  (a bug, or a derivative of the discretisation that is not the slope);
* ``"rough"``: no step matches and the differences themselves disagree
  between steps by more than ``rtol``: the output is not smooth at these
  scales (impacts, contact loss, chaotic rattling, integrator noise), so no
  derivative, autodiff or differenced, is a reliable slope there;
* ``"nan"``: autodiff or the output gave NaN/inf.

Errors are relative to the largest entry of each output row (of the
central-difference Jacobian).
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

DEFAULT_STEPS = (1e-2, 1e-3, 1e-4)


@dataclass
class GradCheck:
    """Result of `gradcheck`: ``value`` (m,) the output at x (flattened, the
    Jacobians' rows), ``autodiff`` (m, n) Jacobian, ``differences``
    {relative step: (m, n) Jacobian}, ``error`` {step: autodiff vs that
    step's differences}, ``spread`` (largest disagreement between the steps'
    differences), ``verdict`` and a one-line ``message``."""

    value: np.ndarray
    autodiff: np.ndarray
    differences: dict
    error: dict
    spread: float
    verdict: str
    rtol: float

    @property
    def ok(self) -> bool:
        return self.verdict == "ok"

    @property
    def message(self) -> str:
        best = min(self.error.values()) if self.error else float("nan")
        text = {
            "ok": f"autodiff matches central differences within {best:.1e}",
            "mismatch": f"autodiff disagrees with central differences by {best:.1e} although "
                        f"they agree between steps within {self.spread:.1e}",
            "rough": f"central differences disagree between steps by {self.spread:.1e}: the "
                     "output is not smooth at these scales (impacts, contact loss, integrator "
                     "noise); no pointwise derivative is a reliable slope here",
            "nan": "autodiff or the output is NaN/inf",
        }[self.verdict]
        return f"{self.verdict}: {text} (rtol {self.rtol:g})"

    def __str__(self) -> str:
        return self.message


def _relative(a, b):
    scale = np.max(np.abs(b), axis=-1, keepdims=True)
    scale = np.where(scale > 0, scale, 1.0)
    return float(np.max(np.abs(a - b) / scale))


def gradcheck(f, x, *, steps=DEFAULT_STEPS, rtol: float = 1e-4, mode: str = "auto",
              jit: bool = True) -> GradCheck:
    """Check the autodiff Jacobian of ``f`` at ``x`` against central
    differences at the relative ``steps`` (each variable perturbed by
    step x |x_i|, or by the step itself where x_i = 0).  ``f`` maps an array
    (or scalar) to an array (or scalar).  ``mode``: "forward" (`jax.jacfwd`),
    "reverse" (`jax.jacrev`) or "auto" (forward, reverse where ``f`` holds a
    reverse-only rule, e.g. diffrax's default checkpointed adjoint).
    ``jit``: compile ``f`` and its Jacobian as one program each (a new
    compilation of the whole of ``f``); with False they are called as given,
    which reuses the compiled programs of an ``f`` that compiles itself, as
    the diffwear models do (`TwoJointLife`).  See the module
    notes for the verdicts; the result holds ``f(x)`` as ``value``."""
    if mode not in ("auto", "forward", "reverse"):
        raise ValueError(f"mode must be 'auto', 'forward' or 'reverse', got {mode!r}")
    x = jnp.asarray(x, dtype=float)
    flat = x.reshape(-1)

    def g(v):
        return jnp.atleast_1d(jnp.asarray(f(v.reshape(x.shape)), dtype=float)).reshape(-1)

    value = jax.jit(g) if jit else g

    def jacobian(diff):
        return np.asarray((jax.jit(diff(g)) if jit else diff(g))(flat))

    if mode == "reverse":
        jac = jacobian(jax.jacrev)
    else:
        try:
            jac = jacobian(jax.jacfwd)
        except TypeError as err:  # custom_vjp: no forward mode
            if mode == "forward" or "custom_vjp" not in str(err):
                raise
            jac = jacobian(jax.jacrev)
    y0 = np.asarray(value(flat))
    if not (np.all(np.isfinite(jac)) and np.all(np.isfinite(y0))):
        return GradCheck(y0, jac, {}, {}, float("nan"), "nan", rtol)
    differences, error = {}, {}
    base = np.abs(np.asarray(flat))
    for step in steps:
        h = np.where(base > 0, step * base, step)
        cols = []
        for i in range(flat.shape[0]):
            e = jnp.zeros_like(flat).at[i].set(h[i])
            cols.append((np.asarray(value(flat + e)) - np.asarray(value(flat - e))) / (2 * h[i]))
        d = np.stack(cols, axis=-1)
        differences[step] = d
        error[step] = _relative(jac, d)
    keys = list(differences)
    spread = max((_relative(differences[a], differences[b]) for a in keys for b in keys
                  if a != b), default=0.0)
    if not all(np.all(np.isfinite(d)) for d in differences.values()):
        verdict = "nan"
    elif min(error.values()) <= rtol:
        verdict = "ok"
    elif spread > rtol:
        verdict = "rough"
    else:
        verdict = "mismatch"
    return GradCheck(y0, jac, differences, error, spread, verdict, rtol)
