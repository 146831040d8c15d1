"""`WearSolution`: every wear model's `solve` returns one result; `evolve`
and `life` are calls of it.  The quasi-static model under a given constant
load (no ideal-mechanism solve: seconds) checks that a run and a life of one
traced program give the numbers of the separate calls, and that the fields
agree with each other (the final profile's peak, `peak_depth`, is the history's last,
``cycles`` the least of ``joint_cycles``); the dynamic models' argument
checks need no integration."""

import math
from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

from diffwear.errors import InputError
from diffwear.models import MAX_CYCLES, Dynamic, QuasiStatic, WearSolution
from diffwear.wear import peak_depth
from diffwear.wear.status import RESULTS, at

FOUR_BAR = (Path(__file__).resolve().parents[1] / "src" / "diffwear" / "config" / "mechanisms"
            / "four_bar_wear.toml")
JOINT = ("coupler_rocker",)
SAMPLES = 36


@pytest.fixture(scope="module")
def setup():
    from diffwear.config.loader import loads
    from diffwear.quasistatic.loads import CycleLoads, JointLoads

    # a coarse grid and few steps: the point is the result's shape, not accuracy
    mfile = loads(FOUR_BAR.read_text().replace("n_theta = 90", "n_theta = 24"))
    # a constant 100 N load in the bushing frame, the pin turning once a second
    force = jnp.broadcast_to(jnp.array([0.0, -100.0]), (SAMPLES, 2))
    lo = CycleLoads(joints=(JointLoads(force=force, omega=jnp.full(SAMPLES, 2 * jnp.pi),
                                       period=jnp.asarray(1.0)),), ok=jnp.asarray(True))
    model = QuasiStatic(samples=SAMPLES, steps=4).with_loads(lo)

    @eqx.filter_jit
    def solve(cycles, limit):
        return model.solve(mfile.mechanism, JOINT, jnp.zeros(1), period=1.0, cycles=cycles,
                           limit=limit)

    return model, mfile.mechanism, solve


def test_a_run_and_a_life_of_one_program_are_evolve_and_life(setup):
    model, mech, solve = setup
    cycles, limit = 200.0, 1e-5
    run = eqx.filter_jit(lambda: model.evolve(mech, JOINT, jnp.zeros(1), period=1.0,
                                              cycles=cycles))()
    life = eqx.filter_jit(lambda: model.life(mech, JOINT, jnp.zeros(1), period=1.0,
                                             limit=limit))()
    assert isinstance(run, WearSolution) and isinstance(life, WearSolution)
    both_run = solve(jnp.asarray(cycles), jnp.asarray(jnp.inf))
    both_life = solve(jnp.asarray(MAX_CYCLES), jnp.asarray(limit))
    np.testing.assert_array_equal(np.asarray(both_run.depth[0]), np.asarray(run.depth[0]))
    np.testing.assert_array_equal(np.asarray(both_life.life), np.asarray(life.life))

    # a run of fixed length: the cycles asked, no life
    assert bool(run.result == RESULTS.ok) and bool(at(run.joint_result, 0) == RESULTS.ok)
    assert float(run.cycles) == pytest.approx(cycles, rel=1e-14)
    assert float(run.cycles) == float(jnp.min(run.joint_cycles))
    assert math.isnan(float(run.life[0]))
    # a life: a finite cycle count, inside the last step, whose peak depth
    # crosses the limit there
    assert bool(life.result == RESULTS.ok)
    h = life.history[0]
    n, peak = (np.asarray(v)[np.asarray(h.valid)] for v in (h.cycles, h.peak))
    assert peak[-2] < limit <= peak[-1]
    assert n[-2] < float(life.life[0]) <= n[-1]
    # the history ends where the solution does
    for sol in (run, life):
        h = sol.history[0]
        valid = np.asarray(h.valid)
        assert float(np.asarray(h.peak)[valid][-1]) == pytest.approx(
            float(peak_depth(sol.depth[0])), rel=1e-12)
        assert float(np.asarray(h.cycles)[valid][-1]) == pytest.approx(
            float(sol.joint_cycles[0]), rel=1e-12)
        np.testing.assert_array_equal(np.asarray(h.depth)[valid][-1], np.asarray(sol.depth[0]))
        # the steps taken are the history's valid slots after the start
        assert int(sol.stats["steps"][0]) == int(valid.sum()) - 1
        assert int(sol.stats["evaluations"][0]) >= int(sol.stats["steps"][0])
        assert "dynamic_cycles" not in sol.stats and sol.state is None and sol.slots is None
    assert float(run.contact_margin[0]) > 0.0


def test_check_names_where_a_run_stopped_at_its_wall(setup):
    """A run whose wall is thinner than the wear of its cycles stops there:
    `WearSolution.check` raises `WearLimitError` (carrying the solution)
    with the cycles and the peak depth it reached, the history's last; a run
    that ends as asked passes through."""
    from diffwear.wear import WearLimitError

    model, mech, _ = setup
    run = eqx.filter_jit(lambda: model.evolve(mech, JOINT, jnp.zeros(1), period=1.0,
                                              cycles=200.0))()
    assert run.check() is run
    wall = 0.5 * float(peak_depth(run.depth[0]))
    cut = eqx.filter_jit(lambda: model.evolve(mech, JOINT, jnp.zeros(1), period=1.0,
                                              cycles=200.0, wall_thickness=wall))()
    assert bool(cut.result == RESULTS.wall_reached) and float(cut.cycles) < 200.0
    with pytest.raises(WearLimitError) as err:
        cut.check("wall test")
    assert err.value.result is cut
    h = cut.history[0]
    valid = np.asarray(h.valid)
    assert str(err.value) == (
        f"wall test: the wear reached the bushing wall after {float(cut.cycles):.0f} cycles "
        f"(max depth {float(np.asarray(h.peak)[valid][-1]) * 1e3:.4f} mm); "
        "stopped, results so far kept")
    assert float(np.asarray(h.peak)[valid][-1]) == pytest.approx(wall, rel=1e-9)


def test_the_dynamic_models_take_cycles_or_a_limit():
    mech = None  # refused before the mechanism is read
    for kwargs in ({}, {"cycles": 10.0, "limit": 1e-4}):
        with pytest.raises(InputError, match="cycles= .* or limit="):
            Dynamic().solve(mech, JOINT, jnp.zeros(1), period=1.0, **kwargs)
    with pytest.raises(InputError, match="wall_thickness"):
        Dynamic().solve(mech, JOINT, jnp.zeros(1), period=1.0, limit=1e-4,
                        wall_thickness=1e-3)


def test_the_fem_route_takes_cycles_only():
    from diffwear.models import FemRoute
    from diffwear.presets import RIG_JOINT
    from diffwear.wear.fem_route import default_model

    with pytest.raises(InputError, match="lives to a depth limit come from Dynamic"):
        FemRoute(fem=default_model(RIG_JOINT)).solve(None, JOINT, jnp.zeros(1), period=1.0,
                                                     limit=1e-4)
