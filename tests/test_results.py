"""The wear results' outcome, `diffwear.wear.RESULTS`: its members and their
stored codes, the helpers that read it (through jit and vmap), and the
status of a checkpoint."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from diffwear.errors import InputError
from diffwear.wear import WearState
from diffwear.wear.status import (
    RESULTS,
    at,
    code,
    from_code,
    members,
    message,
    name,
    not_computed,
    stack,
    words,
    worst,
)

# the codes results stored before the enumeration hold (summary.json,
# life_viscosity.json, checkpoints, sweep tables): they must read the same
STORED = {"ok": 0, "wall_reached": 1, "cycle_model_failed": 2, "run_ended_early": 3,
          "contact_lost": 4}


def test_each_member_keeps_its_stored_code_and_reads_back():
    assert [name(m) for m in members()] == list(STORED)
    assert len(RESULTS) == len(STORED)  # type: ignore[arg-type]  # (the metaclass's len)
    for key, value in STORED.items():
        member = getattr(RESULTS, key)
        assert int(code(member)) == value and name(member) == key
        assert bool(from_code(value) == member) and bool(from_code(float(value)) == member)
        assert message(from_code(value)) == RESULTS[member]
    assert message(RESULTS.ok) == "ok" and words(RESULTS.wall_reached) == "wall reached"


@pytest.mark.parametrize("bad", [-1, 5, 1.5, np.nan])
def test_a_code_that_names_no_member_is_refused(bad):
    with pytest.raises(ValueError, match="status code"):
        from_code(bad)


def test_an_integer_is_not_a_status():
    with pytest.raises(TypeError, match="RESULTS"):
        not_computed(jnp.asarray(2))
    with pytest.raises(ValueError):  # the enumeration itself refuses the comparison
        _ = RESULTS.ok == 0


def test_the_worst_joint_is_the_highest_code_and_each_joint_is_kept():
    joints = stack([RESULTS.ok, RESULTS.contact_lost, RESULTS.wall_reached])
    assert bool(worst(joints) == RESULTS.contact_lost)
    assert bool(at(joints, 2) == RESULTS.wall_reached)
    assert np.asarray(code(joints)).tolist() == [0, 4, 1]


def test_statuses_pass_jit_and_vmap():
    """A batch of points, each failing where x < 0 and reaching the wall
    where x > 1: the members chosen point by point, `not_computed` per point."""
    def one(x):
        return RESULTS.where(x < 0.0, RESULTS.cycle_model_failed,
                             RESULTS.where(x > 1.0, RESULTS.wall_reached, RESULTS.ok))

    status = jax.jit(jax.vmap(one))(jnp.array([-1.0, 0.5, 2.0]))
    assert np.asarray(code(status)).tolist() == [2, 0, 1]
    assert np.asarray(not_computed(status)).tolist() == [True, False, False]


def test_a_checkpoint_keeps_the_status_as_its_code():
    state = WearState.initial((jnp.zeros(3),), {}, ok=False)
    assert bool(state.status == RESULTS.cycle_model_failed)
    flat = state.as_dict()
    assert np.asarray(flat["status"]).tolist() == 2
    back = WearState.from_dict({**flat, "status": np.asarray(2, dtype=np.int64)})
    assert bool(back.status == RESULTS.cycle_model_failed)
    with pytest.raises(InputError, match="status code 7"):
        WearState.from_dict({**flat, "status": np.asarray(7)})
