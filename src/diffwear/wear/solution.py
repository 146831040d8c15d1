"""`WearSolution`: the one result of a wear integration (as diffrax's
`Solution`): the wear of each joint after one integration, to a number of
cycles, to a depth limit, or to whichever comes first.  Every model's
`solve`, `evolve` and the dynamic evolution (`Evolver`) return it."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..errors import SolverError
from ._engine import WearState
from .status import RESULTS, message, name


class WearLimitError(SolverError):
    """The wear integration stopped early; ``.result`` holds the results so far."""

    def __init__(self, message, result=None):
        super().__init__(message)
        self.result = result


class WearSolution(eqx.Module):
    """The wear of each joint from unworn bushings, from one integration.

    depth: final wear profiles [m], one per joint (tuple); NaN, with NaN
        derivatives, where a joint has no answer (`diffwear.wear.status.not_computed`)
    joint_cycles: per joint, the real cycles its profile represents
    life: per joint, the real cycles at which its peak depth reached the
        limit; NaN (with NaN derivatives) where it did not, or where no limit
        was asked
    result: a `diffwear.wear.RESULTS` member (the worst over the joints)
    joint_result: per joint (`RESULTS` of shape (J,))
    contact_margin, contact_margin_worn: per joint, the quasi-static model's
        contact check on the unworn and the final profile (NaN where the
        model needs none)
    stats: the integration's counts: ``steps`` (per joint, the steps taken),
        ``evaluations`` (cycle-model evaluations), and ``dynamic_cycles``
        (dynamic cycles simulated, warm-up included) where the model
        simulates them
    history: per joint a `diffwear.wear.profile_ode.ProfileHistory` (index 0
        the start): cycles, peak depth, whether the step was taken, and the
        profiles where the integration keeps them (else ``depth`` None)
    state: the engine's `WearState` at the end where the model simulates
        cycles (the mechanism's end state ``memory["y"]``, ``memory["t"]``
        for the joint force on the final profile, the profiles as reached
        ``h``, load x sliding per joint, where a step failed or the wall was
        reached ``fail_n`` / ``fail_h``; a dynamic evolution continues from
        it, `Evolver.solve`), else None
    slots: the dynamic evolution's record per scan slot (``cycles``,
        ``max_depth``, ``volume``, ``extrapolation``, ``valid``,
        ``dynamic_cycles``, ``depth``; ``force`` where kept), else None
    """

    depth: tuple
    joint_cycles: Float[Array, " J"]
    life: Float[Array, " J"]
    result: RESULTS
    joint_result: RESULTS
    contact_margin: Float[Array, " J"]
    contact_margin_worn: Float[Array, " J"]
    stats: dict
    history: tuple
    state: WearState | None = None
    slots: dict | None = None

    @property
    def cycles(self) -> Float[Array, ""]:
        """The real cycles reached, the least of ``joint_cycles``: the
        requested count, or fewer when a joint wore through its wall (or its
        model failed) first."""
        return jnp.min(self.joint_cycles)

    def check(self, what: str = "wear evolution") -> "WearSolution":
        """This (concrete) solution, or `WearLimitError` (carrying it) naming
        the cycle and the depth where the integration stopped early."""
        if bool(self.result == RESULTS.ok):
            return self
        if self.state is not None and not bool(self.result == RESULTS.run_ended_early):
            # where the step failed or the wall was reached
            cyc, dep = float(self.state.fail_n), float(self.state.fail_h)
        else:  # where the steps ran out: the last profile reached
            cyc = float(self.cycles)
            dep = max(float(np.max(np.asarray(h.peak)[np.asarray(h.valid)]))
                      for h in self.history)
        raise WearLimitError(f"{what}: {message(self.result)} after {cyc:.0f} cycles "
                             f"(max depth {dep * 1e3:.4f} mm); {_REMEDY[name(self.result)]}",
                             self)

    def reached(self) -> "WearSolution":
        """This (concrete) solution with each joint's profile as far as it
        got: where the final profile is not an answer (NaN: the joint's model
        failed or its steps ran out, `diffwear.wear.status.not_computed`), the
        last profile of its history.  What the report of a run that stopped
        early shows beside its result; never differentiated."""
        depth = []
        for d, h in zip(self.depth, self.history):
            if (h is None or h.depth is None
                    or bool(np.all(np.isfinite(np.asarray(d))))):
                depth.append(d)
                continue
            valid = np.asarray(h.valid)
            depth.append(jnp.asarray(np.asarray(h.depth)[valid][-1]))
        return eqx.tree_at(lambda e: e.depth, self, tuple(depth))


# what to do about an integration that stopped early, by `RESULTS` member name
_REMEDY = {
    "wall_reached": "stopped, results so far kept",
    "cycle_model_failed": ("stopped, results so far kept. Tighten the cycle tolerances or "
                           "reduce the extrapolation factor"),
    "run_ended_early": ("all max_dynamic scan slots were used; raise max_dynamic or loosen "
                        "the extrapolation tolerances"),
    "contact_lost": "stopped, results so far kept",
}


__all__ = ["WearSolution", "WearLimitError"]
