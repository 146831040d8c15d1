"""What every wear model provides: `AbstractWearModel` and its evolution result."""

from __future__ import annotations

import abc
from typing import Any, ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..mechanism import Mechanism
from ..wear.status import RESULTS


class WearEvolution(eqx.Module):
    """Wear of each joint after ``cycles`` real cycles.

    depth: final wear profiles [m], one per joint (tuple)
    cycles: real cycles reached: the requested count, or fewer when a joint
        wore through its wall (or its model failed) first
    joint_cycles: per joint, the cycles its profile represents
    status: a `diffwear.wear.RESULTS` member (the worst over the joints)
    joint_status: per joint (`RESULTS` of shape (J,))
    contact_margin, contact_margin_worn: per joint, the quasi-static model's
        contact check on the unworn and the final profile (NaN where the
        model needs none)
    history: per joint a `diffwear.wear.profile_ode.ProfileHistory` (index 0
        the start)
    detail: the model's own result (the dynamic model's `EvolutionResult`:
        end state, load x sliding, dynamic cycles), or None
    """

    depth: tuple
    cycles: Float[Array, ""]
    joint_cycles: Float[Array, " J"]
    status: RESULTS
    joint_status: RESULTS
    contact_margin: Float[Array, " J"]
    contact_margin_worn: Float[Array, " J"]
    history: tuple
    detail: Any = None

    def reached(self) -> "WearEvolution":
        """This (concrete) evolution with each joint's profile as far as it
        got: where the final profile is not an answer (NaN: the joint's model
        failed or its steps ran out, `diffwear.wear.status.not_computed`), the
        last profile of its history.  What the report of a run that stopped
        early shows beside its status; never differentiated."""
        depth = []
        for d, h in zip(self.depth, self.history):
            if h is None or bool(np.all(np.isfinite(np.asarray(d)))):
                depth.append(d)
                continue
            valid = np.asarray(h.valid)
            depth.append(jnp.asarray(np.asarray(h.depth)[valid][-1]))
        return eqx.tree_at(lambda e: e.depth, self, tuple(depth))


class AbstractWearModel(eqx.Module):
    """How the wear of one crank cycle is computed, and with it the wear of
    many: every consumer of wear (lives, evolutions, the wear studies, the
    bushing design, the sweeps) takes a model object, as diffrax takes a
    solver.

    ``exact_gradients``: the pointwise derivative of its results is the slope
    users want (the quasi-static model), else callers should difference (the
    dynamic model).  ``precomputes``: `prepared` has something to compute that
    does not depend on the bushing design (the quasi-static model's joint
    loads).
    """

    name: eqx.AbstractClassVar[str]
    exact_gradients: eqx.AbstractClassVar[bool]
    precomputes: ClassVar[bool] = False

    @abc.abstractmethod
    def life(self, mech: Mechanism, joints: tuple[str, ...], y0: Float[Array, " s"], *,
             period, limit):
        """Cycles until the peak wear depth of each joint reaches ``limit`` [m]:
        a `diffwear.wear.LifeResult`."""

    @abc.abstractmethod
    def evolve(self, mech: Mechanism, joints: tuple[str, ...], y0: Float[Array, " s"], *,
               period, cycles, wall_thickness=None) -> WearEvolution:
        """Wear of ``joints`` after ``cycles`` real cycles from unworn bushings;
        ``wall_thickness`` [m] (one for all, or one per joint): stop a joint
        whose peak depth reaches it."""

    @abc.abstractmethod
    def joint_force(self, mech: Mechanism, joint: str, y0: Float[Array, " s"], *, period,
                    evolution: WearEvolution, samples: int = 180) -> Float[Array, " T"]:
        """|joint force| [N] of ``joint`` over one cycle at the end of
        ``evolution``, equally spaced over the period (``samples`` of them
        where the model samples the cycle anew)."""

    @abc.abstractmethod
    def cycle_histories(self, mech: Mechanism, joint: str, y0, *, period,
                        evolution: WearEvolution) -> tuple:
        """``joint`` over its first cycle (unworn) and its last (at the end of
        ``evolution``): (first, last `diffwear.contact.ContactHistory`, the
        crank angle [rad] of their samples from the cycle's start)."""

    def check_joints(self, mech: Mechanism, joints: tuple[str, ...],
                     what: str = "mechanism") -> None:
        """`InputError` for wearing joints this model does not evolve (none
        here); ``what`` names the mechanism's source in the message."""

    def reference(self) -> "AbstractWearModel | None":
        """The model a run of this one is compared with (the FEM route: the same
        dynamics with the EFM pressure), or None."""
        return None

    def prepared(self, mech: Mechanism, joints: tuple[str, ...], y0, period
                 ) -> "AbstractWearModel":
        """This model with what does not depend on the bushing design computed
        once for ``mech`` (nothing here)."""
        return self
