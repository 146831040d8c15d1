"""The state a wear evolution carries through ``lax.scan`` (and a checkpoint
holds): `EvolutionState`."""

from __future__ import annotations

import dataclasses

import equinox as eqx
from jaxtyping import Array, Float

from ..errors import InputError


class EvolutionState(eqx.Module):
    """Where a wear evolution stands after some scan slots: the carry of
    ``lax.scan`` and what a checkpoint holds.  ``memory``: what the
    extrapolation strategy (e.g. `Adaptive`'s current A) or the pressure route
    (the FEM compliance) keeps between slots, by name."""

    h: Float[Array, " n"]               # wear depth on the profile grid [m]
    y: Float[Array, " s"]               # mechanism state
    t: Float[Array, ""]                 # simulated time [s]
    n: Float[Array, ""]                 # real cycles represented
    dyn: Array                          # dynamic cycles simulated (incl. warm-up)
    ls: Float[Array, ""]                # A-weighted sum of int N ds [N m]
    status: Array                       # `wear.status` code
    fail_n: Float[Array, ""]            # cycles when it stopped (0 while running)
    fail_h: Float[Array, ""]            # max depth when it stopped [m]
    memory: dict = eqx.field(default_factory=dict)

    def replace(self, **changes) -> EvolutionState:
        """A copy with the named fields changed; memory entries by their names."""
        memory = {k: changes.pop(k) for k in list(changes) if k not in _STATE_FIELDS}
        if memory:
            changes["memory"] = {**self.memory, **memory}
        return dataclasses.replace(self, **changes)

    def as_dict(self) -> dict:
        """Flat name -> array (fields, then memory): the checkpoint's layout."""
        return {**{k: getattr(self, k) for k in _STATE_FIELDS}, **self.memory}

    @classmethod
    def from_dict(cls, d: dict) -> EvolutionState:
        missing = [k for k in _STATE_FIELDS if k not in d]
        if missing:
            raise InputError(f"evolution state without {missing}")
        return cls(**{k: d[k] for k in _STATE_FIELDS},
                   memory={k: v for k, v in d.items() if k not in _STATE_FIELDS})


_STATE_FIELDS = ("h", "y", "t", "n", "dyn", "ls", "status", "fail_n", "fail_h")


__all__ = ["EvolutionState"]
