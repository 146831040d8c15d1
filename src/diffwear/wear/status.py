"""The wear results' outcome, `RESULTS` (an `eqx.Enumeration`: each member
with its message, as diffrax's and optimistix's `RESULTS`), the helpers
that read it (`not_computed`, `worst`, `stack`, `at`, `code`, `from_code`,
`members`, `name`, `message`, `words`), and `not_an_answer`: a result that
was not computed, NaN with NaN derivatives.

A result (an evolution, a life, one joint's part of them) carries one member
of `RESULTS` as its ``status``, through `jax.jit`, `jax.vmap` and the scan of
the wear engine (`diffwear.wear._engine`).  Outside jit a status is written as
its member's integer `code` (summary.json, checkpoints, the sweep tables):
the members are declared in the order of those codes, 0 to 4, so results
stored before the enumeration read the same."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, ClassVar, cast

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np


class RESULTS(eqx.Enumeration):
    """How a wear result ended.  Declared in the order of the stored codes
    (`code`): ``ok`` 0, ``wall_reached`` 1, ``cycle_model_failed`` 2,
    ``run_ended_early`` 3, ``contact_lost`` 4; `worst` over joints takes the
    highest."""

    if TYPE_CHECKING:  # what the metaclass makes of the messages below
        ok: ClassVar["RESULTS"]
        wall_reached: ClassVar["RESULTS"]
        cycle_model_failed: ClassVar["RESULTS"]
        run_ended_early: ClassVar["RESULTS"]
        contact_lost: ClassVar["RESULTS"]
    else:
        ok = "ok"
        wall_reached = "the wear reached the bushing wall"
        cycle_model_failed = "the cycle model failed (integrator or equilibrium solve)"
        run_ended_early = ("the run ended (steps or cycles) before the wear limit or the "
                           "requested cycles were reached")
        contact_lost = ("the pin leaves the bushing wall during the cycle, where the "
                        "quasi-static model does not hold (use the dynamic model)")


def code(status) -> jax.Array | np.ndarray:
    """The integer of ``status`` (any shape), as results outside jit store it:
    0 `RESULTS.ok` ... 4 `RESULTS.contact_lost` (the declaration order)."""
    _check(status)
    (value,) = jax.tree.leaves(status)  # the member's index, its only leaf
    return value


def from_code(codes) -> RESULTS:
    """The `RESULTS` member(s) of stored integer ``codes`` (any shape; a
    float array of whole numbers, as a sweep table holds them, too).  Codes
    outside 0 .. len(RESULTS) - 1 raise ValueError when concrete."""
    if isinstance(codes, jax.core.Tracer):
        return _with_code(jnp.asarray(codes).astype(jnp.int32))
    values = np.asarray(codes)
    if values.size and (not np.all(np.isfinite(values)) or np.any(values != np.round(values))
                        or values.min() < 0 or values.max() >= len(members())):
        raise ValueError(f"status code {codes} is not one of 0 .. {len(members()) - 1}")
    return _with_code(values.astype(np.int32))


# the members' names in the order of their codes (equinox keeps its own
# table private; the names are read through the public attribute lookup, and
# a test checks that they are all of its members)
_NAMES = ("ok", "wall_reached", "cycle_model_failed", "run_ended_early", "contact_lost")


def members() -> tuple[RESULTS, ...]:
    """Every member, in the order of their codes."""
    return tuple(cast(RESULTS, getattr(RESULTS, n)) for n in _NAMES)


def name(status) -> str:
    """The member's name of a concrete scalar ``status`` ("ok", "wall_reached", ...)."""
    return _NAMES[int(code(status))]


def message(status) -> str:
    """The member's message of a concrete scalar ``status``."""
    return RESULTS[status]  # type: ignore[misc]  # (the metaclass's item lookup)


def words(status) -> str:
    """The member's name in words ("wall reached"): a plot title's short form."""
    return name(status).replace("_", " ")


def stack(statuses: Sequence) -> RESULTS:
    """One status of shape (J,) from J scalar ones (per joint)."""
    for s in statuses:
        _check(s)
    return jax.tree.map(lambda *v: jnp.stack(v), *statuses)


def at(status, index) -> RESULTS:
    """The member at ``index`` of a status of shape (J,) (one joint's)."""
    _check(status)
    return jax.tree.map(lambda v: v[index], status)


def worst(status) -> RESULTS:
    """The worst (highest `code`) of a status of shape (J,): a whole result's
    status from its joints'."""
    return _with_code(jnp.max(code(status)))


def not_computed(status):
    """Where ``status`` says there is no answer: the cycle model failed
    (`RESULTS.cycle_model_failed`) or the run ended before its target
    (`RESULTS.run_ended_early`).  A wall reached (`RESULTS.wall_reached`) and
    a contact warning (`RESULTS.contact_lost`) still come with an answer."""
    _check(status)
    return (status == RESULTS.cycle_model_failed) | (status == RESULTS.run_ended_early)


def _with_code(values) -> RESULTS:
    """A status holding the codes ``values`` (int32, any shape)."""
    return jax.tree.map(lambda _: values, RESULTS.ok)


def _check(status) -> None:
    if not isinstance(status, RESULTS):
        raise TypeError(f"a wear status is a member of diffwear.wear.RESULTS, got {status!r}")


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
