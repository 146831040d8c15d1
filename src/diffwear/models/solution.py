"""`WearSolution`: what every wear model's `solve` returns (as diffrax's
`Solution`): the wear of each joint after one integration, to a number of
cycles, to a depth limit, or to whichever comes first."""

from __future__ import annotations

from typing import Any

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..wear.status import RESULTS


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
    detail: the dynamic evolution's final state (`diffwear.wear.EvolutionResult`:
        end state for a checkpoint or the joint force on the final profile,
        load x sliding), or None
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
    detail: Any = None

    @property
    def cycles(self) -> Float[Array, ""]:
        """The real cycles reached, the least of ``joint_cycles``: the
        requested count, or fewer when a joint wore through its wall (or its
        model failed) first."""
        return jnp.min(self.joint_cycles)

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


__all__ = ["WearSolution"]
