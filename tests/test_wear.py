"""Wear cycle and wear evolution: bookkeeping, convergence, gradients, failures.

Reduced problem: the Table 2-1 slider-crank with the wear-5000 joint on a
coarse grid (n_theta = 36) and a wear coefficient amplified 100x
(K_FAST), so that a few cycles change the profile by many clearances and the
extrapolation error is visible.
"""

import math

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from diffwear.cli.objects import extrapolation_method
from diffwear.errors import InputError
from diffwear.presets import WEAR_5000, WearJointDesign, slider_crank, with_wear_joint
from diffwear.studies import _wear_common as common
from diffwear.wear import (
    ArchardWear,
    Constant,
    CycleSettings,
    WearLimitError,
    evolve,
    smooth_max,
    worn_volume,
)
from diffwear.wear.status import RESULTS

N_THETA = 36
PERIOD = 2.0
K_FAST = WEAR_5000.k * 100.0


def _design(p):
    return WearJointDesign(p[0], p[1], p[2], p[3], WEAR_5000.wall)


@pytest.fixture(scope="module")
def problem():
    mech0, qg = slider_crank()
    p = jnp.stack([K_FAST, WEAR_5000.clearance, WEAR_5000.depth, WEAR_5000.diameter])

    def mech_of(p):
        return with_wear_joint(mech0, _design(p), n_theta=N_THETA)

    y0 = common.initial_state(mech0, qg, mech_of(p))
    return mech_of, p, y0


def _metrics(mech_of, p, res):
    el = mech_of(p).element("crank_rod")
    vol = worn_volume(res.depth[0], el.bushing_radius, el.law.depth)
    return jnp.max(res.depth[0]), vol


@pytest.fixture(scope="module")
def short_run(problem):
    """One jitted evolution (6 real cycles, A = 2) with the wall thickness traced,
    shared by the bookkeeping and wear-through tests (one compilation)."""
    mech_of, p, y0 = problem
    return jax.jit(lambda p, y, wall: evolve(mech_of(p), "crank_rod", y, 6, period=PERIOD,
                                             method=Constant(2.0), wall_thickness=wall))


def test_archard_bookkeeping(problem, short_run):
    """Worn volume from the profile == k x sum over cycles of A x int N ds (rel 1e-3)."""
    mech_of, p, y0 = problem
    res = short_run(p, y0, jnp.inf).check()
    _, vol = _metrics(mech_of, p, res)
    assert int(res.stats["dynamic_cycles"]) == 1 + 3
    assert float(res.cycles) == 6.0
    np.testing.assert_allclose(float(vol), float(p[0] * res.state.load_sliding[0]), rtol=1e-3)
    assert float(vol) > 0


@pytest.mark.slow
def test_extrapolation_converges(problem):
    """A = 4 and the error-controlled scheme agree with every-cycle within 1 %."""
    mech_of, p, y0 = problem
    n = 16

    def run(method, a, max_dyn=None):
        solver = extrapolation_method(method, extrapolation=a, rtol=2e-3, atol=1e-8)
        f = jax.jit(lambda p, y: evolve(mech_of(p), "crank_rod", y, n, period=PERIOD,
                                        method=solver, max_dynamic=max_dyn))
        r = f(p, y0).check()
        return r, [float(v) for v in _metrics(mech_of, p, r)]

    ref, (d_ref, v_ref) = run("constant", 1.0)
    assert d_ref > 10 * float(p[1])  # the profile changed a lot: a real test
    for method, a in (("constant", 4.0), ("error", 2.0), ("adaptive", 2.0)):
        r, (d, v) = run(method, a, 16)
        assert float(r.cycles) == pytest.approx(n)
        if method != "error":  # at this tight tolerance on 16 cycles the error-
            # controlled scheme may need more dynamic cycles than it saves
            assert int(r.stats["dynamic_cycles"]) < int(ref.stats["dynamic_cycles"]), method
        assert d == pytest.approx(d_ref, rel=1e-2), method
        assert v == pytest.approx(v_ref, rel=1e-2), method


@pytest.mark.slow
def test_gradients_match_finite_differences(problem):
    """d/dp of a smooth max depth (logsumexp, temperature 1 % of the max depth of
    the reference run) and of the volume, p = (k, clearance, depth, diameter),
    through warm-up + 2 dynamic cycles, against central differences."""
    mech_of, p, y0 = problem

    def outputs(p, temperature):
        r = evolve(mech_of(p), "crank_rod", y0, 4, period=PERIOD, method=Constant(2.0),
                   cycle=CycleSettings(1e-9, 1e-9, adjoint=diffrax.ForwardMode()))
        el = mech_of(p).element("crank_rod")
        return jnp.stack([smooth_max(r.depth[0], temperature) * 1e6,
                          worn_volume(r.depth[0], el.bushing_radius, el.law.depth) * 1e9])

    f = jax.jit(outputs)
    base = f(p, 1.0)
    temperature = 0.01 * float(jnp.max(base[0])) * 1e-6
    jac = np.asarray(jax.jit(jax.jacfwd(outputs))(p, temperature))
    for i in range(4):
        h = 1e-4 * float(p[i])
        e = jnp.zeros(4).at[i].set(h)
        fd = (np.asarray(f(p + e, temperature)) - np.asarray(f(p - e, temperature))) / (2 * h)
        scale = np.abs(np.asarray(base)) / float(p[i])  # output per unit relative change
        np.testing.assert_allclose(jac[:, i], fd, rtol=2e-3, atol=1e-3 * scale.max(),
                                   err_msg=f"parameter {i}")


def test_negative_wear_coefficient_rejected():
    with pytest.raises(InputError, match="wear coefficient"):
        ArchardWear(-1e-13)
    with pytest.raises(InputError, match="wear coefficient"):
        ArchardWear.from_mm3_per_Nm(-5.05e-4)


def test_bad_evolution_options(problem):
    mech_of, p, y0 = problem
    with pytest.raises(InputError, match="extrapolation"):
        evolve(mech_of(p), "crank_rod", y0, 4, period=PERIOD, method=Constant(0.5))
    with pytest.raises(InputError, match="method"):
        evolve(mech_of(p), "crank_rod", y0, 4, period=PERIOD, method="bogus")
    with pytest.raises(InputError, match="method"):
        extrapolation_method("bogus")
    with pytest.raises(InputError, match="crank_rod|ClearanceJoint"):
        evolve(slider_crank()[0], "crank_rod", y0, 4, period=PERIOD)


def test_wear_through_wall_stops_with_message(problem, short_run):
    """A wall thinner than the wear of a few cycles: the run stops, names the cycle
    and the depth, and keeps the profile at the wall: the piercing step is cut
    to the fraction of it that reaches the wall (its cycles likewise)."""
    mech_of, p, y0 = problem
    full = short_run(p, y0, jnp.inf)
    wall = 0.5 * float(jnp.max(full.depth[0]))  # pierced half-way through the run
    res = short_run(p, y0, wall)
    with pytest.raises(WearLimitError, match=r"bushing wall after \d+ cycles \(max depth") as err:
        res.check("test")
    kept = err.value.result
    assert 0 < float(kept.cycles) < 6
    assert math.isclose(float(jnp.max(kept.depth[0])), wall, rel_tol=1e-12)
    assert float(kept.state.fail_h) == float(jnp.max(kept.depth[0]))
    assert float(kept.state.fail_n) == float(kept.cycles)
    # the wear of a constant-A step is linear in its length: the cut step's
    # cycles and depth are in proportion
    steps = np.asarray(kept.slots["cycles"])[np.asarray(kept.slots["valid"])]
    depths = np.asarray(kept.slots["max_depth"])[np.asarray(kept.slots["valid"])]
    before_n, before_h = (steps[-2], depths[-2]) if len(steps) > 1 else (0.0, 0.0)
    full_step = np.asarray(full.slots["max_depth"])[len(steps) - 1]
    fraction = (float(kept.cycles) - before_n) / 2.0
    assert math.isclose(before_h + fraction * (full_step - before_h), wall, rel_tol=1e-9)


def test_running_out_of_slots_is_an_error_not_a_short_answer(problem):
    """An adaptive run whose scan slots end before the requested cycles reports
    `RESULTS.run_ended_early` and raises, instead of returning the wear of
    fewer cycles; asked to (``throw=True``), inside the computation."""
    mech_of, p, y0 = problem
    res = evolve(mech_of(p), "crank_rod", y0, 6, period=PERIOD,
                 method=extrapolation_method("adaptive", extrapolation=1.0), max_dynamic=2)
    assert bool(res.result == RESULTS.run_ended_early) and float(res.cycles) < 6
    with pytest.raises(WearLimitError, match="slots"):
        res.check()
    with pytest.raises(eqx.EquinoxRuntimeError, match="the run ended"):
        evolve(mech_of(p), "crank_rod", y0, 6, period=PERIOD, throw=True,
               method=extrapolation_method("adaptive", extrapolation=1.0), max_dynamic=2)


def test_a_checkpoint_write_cut_short_keeps_the_previous_one_and_leaves_no_file(tmp_path,
                                                                               monkeypatch):
    """Ctrl-C while the checkpoint is written: the previous checkpoint stays
    whole and readable, and no temporary file is left in the folder (which
    the next run would otherwise find there)."""
    from diffwear.models import Checkpoint, WearState, load_checkpoint, save_checkpoint

    path = tmp_path / "checkpoint.npz"
    state = jax.tree.map(np.asarray, WearState.initial((np.zeros(3),),
                                                   {"y": np.zeros(2), "t": np.asarray(0.0)}))
    ck = Checkpoint(state, {"cycles": np.zeros(1)}, 1)
    save_checkpoint(path, ck, {"cycles": 1})

    def interrupted(f, **arrays):
        f.write(b"PK half a file")
        raise KeyboardInterrupt

    monkeypatch.setattr(np, "savez", interrupted)
    with pytest.raises(KeyboardInterrupt):
        save_checkpoint(path, ck, {"cycles": 2})
    monkeypatch.undo()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["checkpoint.npz"]
    assert load_checkpoint(path)[1] == {"cycles": 1}


def _chunked(problem, cycles=6, a=2.0, chunk_slots=2, **kw):
    from diffwear.models import ChunkedEvolution
    from diffwear.wear import Evolver

    mech_of, p, y0 = problem
    return ChunkedEvolution(
        lambda p: Evolver(mech_of(p), "crank_rod", cycles, period=PERIOD, method=Constant(a),
                          **kw),
        p, y0, chunk_slots)


def test_interrupted_chunked_run_resumes_to_the_same_result(problem, short_run, tmp_path):
    """6 cycles at A = 2 (3 scan slots) in chunks of 2 slots: interrupted after
    the first chunk (checkpoint saved), resumed from the file: profile, volume,
    cycles, state and history equal those of the single scan (1e-12)."""
    from diffwear.models import load_checkpoint, save_checkpoint

    mech_of, p, y0 = problem
    ref = short_run(p, y0, jnp.inf).check()
    path = tmp_path / "checkpoint.npz"
    seen = []

    def interrupt(ck):
        save_checkpoint(path, ck, {"cycles": 6})
        seen.append(ck.slots_done)
        raise KeyboardInterrupt

    run = _chunked(problem)
    run.compile()
    with pytest.raises(KeyboardInterrupt):
        run.run(on_chunk=interrupt)
    ck, meta = load_checkpoint(path)
    assert seen == [2] and ck.slots_done == 2 and meta == {"cycles": 6}
    assert float(ck.state.n) == 4.0 and ck.history["cycles"].shape == (2,)
    assert not list(tmp_path.glob(".*.partial"))
    res = run.run(start=ck).check()
    assert bool(res.result == ref.result)
    for name, value in (("depth", lambda r: r.depth[0]), ("y", lambda r: r.state.memory["y"]),
                        ("t", lambda r: r.state.memory["t"]), ("cycles", lambda r: r.cycles),
                        ("dynamic_cycles", lambda r: r.stats["dynamic_cycles"]),
                        ("load_sliding", lambda r: r.state.load_sliding)):
        np.testing.assert_allclose(np.asarray(value(res)), np.asarray(value(ref)), rtol=1e-12,
                                   atol=0, err_msg=name)
    for key in ref.slots:
        np.testing.assert_allclose(np.asarray(res.slots[key]),
                                   np.asarray(ref.slots[key]), rtol=1e-12, err_msg=key)
    np.testing.assert_allclose(float(_metrics(mech_of, p, res)[1]),
                               float(_metrics(mech_of, p, ref)[1]), rtol=1e-12)
    for k, v in ref.state.as_dict().items():
        np.testing.assert_allclose(np.asarray(res.state.as_dict()[k]), np.asarray(v), rtol=1e-12,
                                   err_msg=k)


def test_an_evolution_cut_after_some_slots_continues_from_its_state(problem, short_run):
    """6 cycles at A = 2 (3 scan slots) stopped after one slot: the run ended
    early (an error, not a short answer), and continued from its
    ``WearSolution.state`` it ends where the single scan ends (1e-12)."""
    from diffwear.wear import Evolver

    mech_of, p, y0 = problem
    ref = short_run(p, y0, jnp.inf).check()

    def evolver(p):
        return Evolver(mech_of(p), "crank_rod", 6, period=PERIOD, method=Constant(2.0))

    part = jax.jit(lambda p, y: evolver(p).solve(y, slots=1))(p, y0)
    assert bool(part.result == RESULTS.run_ended_early) and float(part.cycles) == 2.0
    with pytest.raises(WearLimitError, match=r"after 2 cycles"):
        part.check()
    rest = jax.jit(lambda p, s: evolver(p).solve(None, start=s))(p, part.state).check()
    assert float(rest.cycles) == 6.0
    np.testing.assert_allclose(np.asarray(rest.depth[0]), np.asarray(ref.depth[0]), rtol=1e-12)
    np.testing.assert_allclose(np.asarray(rest.state.load_sliding),
                               np.asarray(ref.state.load_sliding), rtol=1e-12)


def test_contact_loss_over_a_large_part_of_a_cycle_warns():
    from types import SimpleNamespace

    # 30 of 100 samples out of contact (penetration <= 0) in the last cycle
    last = SimpleNamespace(penetration=np.r_[np.full(70, 1e-6), np.full(30, -1e-5)])
    first = SimpleNamespace(penetration=np.r_[np.full(90, 1e-6), np.full(10, -1e-5)])
    warnings = common.contact_loss_warnings({"first": first, "last": last}, 25.0)
    assert len(warnings) == 1
    assert "lost contact over 30% of the last dynamic cycle" in warnings[0]
    assert "A = 25 cycles" in warnings[0]


def test_extrapolation_strategies_are_objects_and_names_map_onto_them(problem):
    """``method=`` takes a strategy object; each name is shorthand for one,
    built with the same settings (so both run the same scan), and bad
    settings are refused when the object is made."""
    from diffwear.wear import Adaptive, Constant, ErrorControlled, Evolver

    mech_of, p, y0 = problem
    mech = mech_of(p)

    def strategy(method, **kw):
        solver = extrapolation_method(method, **kw)
        return Evolver(mech, "crank_rod", 6, period=PERIOD, max_dynamic=4,
                       method=solver).strategy

    assert strategy("constant", extrapolation=2.0) == Constant(2.0)
    assert strategy("adaptive", extrapolation=3.0,
                    adaptive={"criterion": "pressure_jump"}) == \
        Adaptive(a0=3.0, criterion="pressure_jump")
    assert strategy("error", rtol=1e-3, atol=1e-8) == \
        ErrorControlled(rtol=1e-3, atol=1e-8, dn0=1.0)
    # ceil(6 / 2.5) = 3 scan slots for constant A; max_dynamic for the others
    assert Evolver(mech, "crank_rod", 6, period=PERIOD, method=Constant(2.5)).n_slots == 3
    assert Evolver(mech, "crank_rod", 6, period=PERIOD, method=Adaptive(),
                   max_dynamic=4).n_slots == 4
    res = evolve(mech, "crank_rod", y0, 4, period=PERIOD, method=Constant(2.0))
    ref = evolve(mech, "crank_rod", y0, 4, period=PERIOD,
                 method=extrapolation_method("constant", extrapolation=2.0))
    assert float(res.cycles) == 4.0 and int(res.stats["dynamic_cycles"]) == 1 + 2
    np.testing.assert_array_equal(np.asarray(res.depth[0]), np.asarray(ref.depth[0]))
    with pytest.raises(InputError, match="A must be >= 1"):
        Constant(0.5)
    with pytest.raises(InputError, match="criterion"):
        Adaptive(criterion="smoothness")
    with pytest.raises(InputError, match="extrapolation object"):
        strategy("linear")
