"""Status codes shared by the wear results (evolutions, lives), their meaning,
and `not_an_answer`: a result that was not computed, NaN with NaN derivatives."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

STATUS_OK, STATUS_PIERCED, STATUS_SOLVER, STATUS_INCOMPLETE, STATUS_CONTACT_LOSS = 0, 1, 2, 3, 4

STATUS_TEXT = {
    STATUS_OK: "ok",
    STATUS_PIERCED: "the wear reached the bushing wall",
    STATUS_SOLVER: "the cycle model failed (integrator or equilibrium solve)",
    STATUS_INCOMPLETE: "the run ended (steps or cycles) before the wear limit was reached",
    STATUS_CONTACT_LOSS: ("the pin leaves the bushing wall during the cycle, where the "
                          "quasi-static model does not hold (use the dynamic model)"),
}


def not_computed(status):
    """Where ``status`` says there is no answer: the cycle model failed
    (`STATUS_SOLVER`) or the run ended before its target (`STATUS_INCOMPLETE`).
    A wall reached (`STATUS_PIERCED`) and a contact warning
    (`STATUS_CONTACT_LOSS`) still come with an answer."""
    status = jnp.asarray(status)
    return (status == STATUS_SOLVER) | (status == STATUS_INCOMPLETE)


def not_an_answer(value, failed, inputs):
    """``value`` with NaN, and NaN derivatives by every float leaf of
    ``inputs``, where ``failed`` (broadcast against ``value``); elsewhere the
    value and its derivatives unchanged.

    Why not ``jnp.where(failed, nan, value)``: its derivative is 0 where
    failed (the select passes no tangent from the NaN constant), which an
    optimiser reads as a flat optimum and stops.  A NaN scaled into the
    tangent alone does not survive the selects upstream in reverse mode
    either.  So a term ``NaN x p`` is added where failed, with ``p`` the sum
    of the finite entries of every float leaf of ``inputs`` (``0 x p``
    elsewhere): forward and reverse derivatives by any of them are then NaN
    there.  In a vmapped batch each point's ``p`` is its own, so a failing
    point leaves the others' values and per-point derivatives as they were.
    As for any NaN in JAX (0 x NaN is NaN), a reverse-mode derivative of
    another output of the same call by an input they share is NaN too (the
    other joint's life of a two-joint life by the mechanism's parameters;
    the failing point's column of a Jacobian of a whole batch)."""
    value = jnp.asarray(value)
    leaves = [jnp.ravel(v).astype(value.dtype)
              for v in jax.tree.leaves(eqx.filter(inputs, eqx.is_inexact_array))
              if jnp.issubdtype(v.dtype, jnp.floating)]
    # one concatenation and one sum, whatever the number of leaves (a large
    # mechanism has thousands: the traced program stays small)
    flat = jnp.concatenate(leaves) if leaves else jnp.zeros(0, value.dtype)
    probe = jnp.sum(jnp.where(jnp.isfinite(flat), flat, 0.0))
    poison = jnp.where(jnp.broadcast_to(failed, jnp.shape(value)), jnp.nan, 0.0)
    return jnp.where(jnp.broadcast_to(failed, jnp.shape(value)), jnp.nan, value) + poison * probe
