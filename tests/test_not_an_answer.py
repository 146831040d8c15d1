"""A result that was not computed is NaN, and so are its derivatives, forward
and reverse: a 0 would read to an optimiser as a flat optimum.  Each test
puts a failing point in a vmapped batch beside computed ones, whose values and
derivatives must be those they have alone (central differences and closed
forms beside them)."""

import math
from pathlib import Path
from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from diffwear.wear.status import RESULTS, code, members, not_an_answer, not_computed, stack

FOUR_BAR = (Path(__file__).resolve().parents[1] / "src" / "diffwear" / "config" / "mechanisms"
            / "four_bar_wear.toml")


def _life(k):
    """A closed form with a failure: 3 / k for k < 1, else not computed."""
    return not_an_answer(3.0 / k, k >= 1.0, (k,))


def test_not_computed_names_the_failures_only():
    status = stack(list(members()))  # ok, wall, cycle model, run ended, contact lost
    assert np.asarray(not_computed(status)).tolist() == [False, False, True, True, False]


def test_a_failing_point_in_a_batch_is_nan_with_nan_derivatives_the_others_exact():
    """d(3/k)/dk = -3/k^2: -12 at 0.5, -48 at 0.25; the point at k = 2 fails."""
    ks = jnp.array([0.5, 2.0, 0.25])
    value, grad = jax.vmap(jax.value_and_grad(_life))(ks)
    forward = jax.vmap(jax.jacfwd(_life))(ks)
    for got in (value, grad, forward):
        assert math.isnan(float(got[1]))
    assert np.asarray(value)[[0, 2]] == pytest.approx([6.0, 12.0], rel=1e-15)
    assert np.asarray(grad)[[0, 2]] == pytest.approx([-12.0, -48.0], rel=1e-15)
    assert np.asarray(forward)[[0, 2]] == pytest.approx([-12.0, -48.0], rel=1e-15)
    # the gradient of the batch's sum: NaN at the failing point only
    total = np.asarray(jax.grad(lambda k: jnp.sum(jax.vmap(_life)(k)))(ks))
    assert math.isnan(total[1]) and total[[0, 2]] == pytest.approx([-12.0, -48.0], rel=1e-15)


def test_a_failed_value_that_is_finite_is_made_nan_too():
    """A failure whose raw value is finite (the last profile an evolution
    reached) is not an answer either."""
    def depth(k):
        return not_an_answer(jnp.array([1.0, 2.0]) * k, jnp.array([False, True]), (k,))

    value = np.asarray(depth(2.0))
    assert value[0] == 2.0 and math.isnan(value[1])
    jac = np.asarray(jax.jacfwd(depth)(2.0))
    assert jac[0] == 1.0 and math.isnan(jac[1])
    assert math.isnan(float(jax.grad(lambda k: depth(k)[1])(2.0)))


def _zero_load_setup():
    from diffwear.config.loader import loads
    from diffwear.models import QuasiStatic
    from diffwear.quasistatic.loads import CycleLoads, JointLoads

    # a coarse grid and few steps: the point is the failure, not the life's accuracy
    mfile = loads(FOUR_BAR.read_text().replace("n_theta = 90", "n_theta = 24"))
    samples = 36

    def model(scale):
        """The quasi-static model given a constant 100 N load in the bushing
        frame times ``scale`` (0: a joint that carries no load), the pin
        turning once a second."""
        force = jnp.broadcast_to(scale * jnp.array([0.0, -100.0]), (samples, 2))
        lo = CycleLoads(joints=(JointLoads(force=force, omega=jnp.full(samples, 2 * jnp.pi),
                                           period=jnp.asarray(1.0)),), ok=jnp.asarray(True))
        return QuasiStatic(samples=samples, steps=4).with_loads(lo)

    def life(scale, limit=1e-5):
        """The coupler-rocker joint's cycles to ``limit`` [m] of wear."""
        res = model(scale).life(mfile.mechanism, ("coupler_rocker",), jnp.zeros(1), period=1.0,
                                limit=limit)
        return res.life[0], res.result

    def evolve(scale, cycles=200.0):
        """Its peak wear depth [m] after ``cycles``."""
        res = model(scale).evolve(mfile.mechanism, ("coupler_rocker",), jnp.zeros(1),
                                  period=1.0, cycles=cycles)
        return jnp.max(res.depth[0]), res.result

    def run(scale, cycles=200.0):
        """The run of a report: (the evolution as far as it got, its status)."""
        from diffwear.models import run_model

        res, _ = run_model(model(scale), lambda _: mfile.mechanism, jnp.zeros(()),
                           ("coupler_rocker",), jnp.zeros(1), period=1.0, cycles=cycles)
        return res.depth[0], res.result

    life.evolve = evolve
    life.run = run
    return life


def test_the_life_of_a_joint_that_carries_no_load_is_not_an_answer():
    """No load: the pin's equilibrium has no solution (`RESULTS.cycle_model_failed`), the life is
    NaN; a loaded joint beside it has its life."""
    life = jax.jit(_zero_load_setup())
    cycles, status = life(0.0)
    assert math.isnan(float(cycles)) and bool(status == RESULTS.cycle_model_failed)
    cycles, status = life(1.0)
    assert np.isfinite(float(cycles)) and bool(status == RESULTS.ok)


@pytest.mark.extended
def test_the_zero_load_life_has_nan_derivatives_in_a_batch_beside_loaded_ones():
    """A batch of load scales (1, 0, 2): the unloaded point's life and its
    derivatives (reverse and forward, by the load and by the limit) are NaN;
    the loaded points' lives and derivatives are those they have alone, and
    the derivatives agree with central differences."""
    life = _zero_load_setup()

    def cycles(scale):
        return life(scale)[0]

    scales = jnp.array([1.0, 0.0, 2.0])
    value, grad = jax.jit(jax.vmap(jax.value_and_grad(cycles)))(scales)
    forward = jax.jit(jax.vmap(jax.jacfwd(cycles)))(scales)
    for got in (value, grad, forward):
        assert math.isnan(float(got[1]))
    alone = jax.jit(cycles)
    for i in (0, 2):
        assert float(value[i]) == pytest.approx(float(alone(scales[i])), rel=1e-12)
        eps = 1e-6
        central = (float(alone(scales[i] + eps)) - float(alone(scales[i] - eps))) / (2 * eps)
        assert float(grad[i]) == pytest.approx(central, rel=1e-5)
        assert float(forward[i]) == pytest.approx(float(grad[i]), rel=1e-10)
    by_limit = jax.jit(jax.value_and_grad(lambda lim: life(0.0, lim)[0]))(1e-5)
    assert all(math.isnan(float(v)) for v in by_limit)


@pytest.mark.slow  # a minute: two evolutions compiled (the batch life test covers CI)
def test_the_zero_load_evolution_has_no_final_profile_and_nan_derivatives():
    """The evolution of an unloaded joint (its cycle model failed) has a NaN final
    profile, NaN derivatives forward and reverse; a loaded one beside it in
    the batch keeps its depth, its derivative agreeing with central
    differences.  The run a report makes keeps the profile it reached."""
    depth = _zero_load_setup().evolve

    def peak(scale):
        return depth(scale)[0]

    scales = jnp.array([1.0, 0.0])
    value, grad = jax.jit(jax.vmap(jax.value_and_grad(peak)))(scales)
    forward = jax.jit(jax.vmap(jax.jacfwd(peak)))(scales)
    assert bool(jax.jit(depth)(0.0)[1] == RESULTS.cycle_model_failed)
    for got in (value, grad, forward):
        assert math.isnan(float(got[1])) and np.isfinite(float(got[0]))
    alone = jax.jit(peak)
    eps = 1e-6
    central = (float(alone(1.0 + eps)) - float(alone(1.0 - eps))) / (2 * eps)
    assert float(value[0]) == pytest.approx(float(alone(1.0)), rel=1e-12)
    assert float(grad[0]) == pytest.approx(central, rel=1e-5)
    assert float(forward[0]) == pytest.approx(float(grad[0]), rel=1e-10)
    # the report of a run keeps what it reached: here the unworn profile
    reached, status = _zero_load_setup().run(0.0)
    assert bool(status == RESULTS.cycle_model_failed) and np.all(np.asarray(reached) == 0.0)


def test_a_failed_sweep_point_is_nan_with_nan_derivatives_beside_exact_ones():
    """The rig-wear sweep model on a stand-in wear model whose final profile
    is the clearance c everywhere (so max depth = c exactly: the smooth max
    of a constant) and which fails (`RESULTS.cycle_model_failed`) above c = 0.04 mm: in a
    vmapped batch the failed point's outputs and derivatives are NaN, the
    other's depth is 1e3 c mm with derivative 1e3 mm/m."""
    from diffwear.models import AbstractWearModel, WearSolution
    from diffwear.sweep.models import JOINT, RigWear

    class Uniform(AbstractWearModel):
        name: ClassVar[str] = "uniform"
        exact_gradients: ClassVar[bool] = True

        def solve(self, mech, joints, y0, *, period, cycles=None, limit=None,
                  wall_thickness=None):
            el = mech.element(JOINT)
            c = el.bushing_radius - el.pin_radius
            depth = jnp.full(el.profile.n, c)
            status = RESULTS.where(c > 0.04e-3, RESULTS.cycle_model_failed, RESULTS.ok)
            nan = jnp.full(1, jnp.nan)
            return WearSolution(depth=(depth,), joint_cycles=jnp.asarray([cycles]),
                                life=nan, result=status,
                                joint_result=stack([status]), contact_margin=nan,
                                contact_margin_worn=nan, stats={}, history=())

        def joint_force(self, mech, joint, y0, *, period, evolution, samples=180):
            return jnp.full(samples, 100.0)

        def cycle_histories(self, mech, joint, y0, *, period, evolution):
            raise NotImplementedError

    rig = RigWear(wear_model=Uniform(), n_theta=12)
    base = rig.defaults

    def depth_mm(c):
        return rig({**base, "clearance": c})["max_depth_mm"]

    @jax.jit
    def batch(cs):
        value, grad = jax.vmap(jax.value_and_grad(depth_mm))(cs)
        return value, grad, jax.vmap(jax.jacfwd(depth_mm))(cs)

    value, grad, forward = batch(jnp.array([0.02e-3, 0.05e-3]))
    assert float(value[0]) == pytest.approx(0.02, rel=1e-12)
    assert float(grad[0]) == pytest.approx(1e3, rel=1e-9)
    assert float(forward[0]) == pytest.approx(1e3, rel=1e-9)
    for got in (value, grad, forward):
        assert math.isnan(float(got[1]))
    outputs = jax.jit(rig)({**base, "clearance": 0.05e-3})
    # the sweep tables hold the member's code (2: declared third)
    assert float(outputs["status"]) == float(code(RESULTS.cycle_model_failed)) == 2.0
    assert all(math.isnan(float(outputs[k]))
               for k in ("max_depth_mm", "volume_mm3", "mean_joint_force_N"))


def test_a_failed_calibration_prediction_is_nan_with_nan_derivatives():
    """A calibration problem on a stand-in model: the prediction is 1e12 k
    with k = 5e-13 e^x (the fitted unknown x on its log scale), and the model
    fails above k = 1e-12 (x > ln 2).  At x = 0: 0.5, derivative 0.5; at
    x = 1 the prediction and its derivatives are NaN, in one vmapped batch."""
    from typing import NamedTuple

    from diffwear.calibrate.fit import Problem

    class History(NamedTuple):
        value: jnp.ndarray
        ok: jnp.ndarray

    def model(base, effects):
        return History(base["k"] * 1e12, base["k"] < 1e-12)

    problem = Problem(model, (lambda h: jnp.atleast_1d(h.value),), y=np.zeros(1),
                      sigma=np.ones(1), holdout=np.zeros(1, bool), series_of_point=np.zeros(1),
                      fit_names=("k",), base0={"k": jnp.asarray(5e-13)}, tau=np.ones(1))

    def predict(x):
        return problem.predict(jnp.atleast_1d(x), jnp.zeros(2))[0]

    xs = jnp.array([0.0, 1.0])
    value, grad = jax.vmap(jax.value_and_grad(predict))(xs)
    forward = jax.vmap(jax.jacfwd(predict))(xs)
    assert float(value[0]) == pytest.approx(0.5, rel=1e-12)
    assert float(grad[0]) == pytest.approx(0.5, rel=1e-12)
    assert float(forward[0]) == pytest.approx(0.5, rel=1e-12)
    for got in (value, grad, forward):
        assert math.isnan(float(got[1]))
