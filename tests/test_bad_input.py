"""Bad input: every case raises `InputError` / `SolverError` with a
message that says what is wrong, never NaN or a bare NumPy/JAX error."""

import math
import re

import jax.numpy as jnp
import numpy as np
import pytest
from linkages import four_bar

from diffwear import InputError, SolverError
from diffwear.dynamics import check_assembly, consistent_state, simulate
from diffwear.mechanism import Body, Driver, Gravity, Mechanism, RevoluteJoint
from diffwear.presets import slider_crank


def test_no_bodies():
    with pytest.raises(InputError, match="at least one body"):
        Mechanism([])


@pytest.mark.parametrize("mass, inertia, what, why", [
    (0.0, 1.0, r"mass \[kg\]", "> 0"),
    (-2.0, 1.0, r"mass \[kg\]", "> 0"),
    (1.0, 0.0, r"inertia \[kg m\^2\]", "> 0"),
    (1.0, -1e-3, r"inertia \[kg m\^2\]", "> 0"),
    (math.nan, 1.0, r"mass \[kg\]", "finite"),
    (1.0, jnp.inf, r"inertia \[kg m\^2\]", "finite"),
])
def test_bad_mass_or_inertia(mass, inertia, what, why):
    with pytest.raises(InputError, match=rf"body 'link': {what} must be .*{why[-1]}") as err:
        Body("link", mass, inertia)
    assert why in str(err.value)


def test_reserved_body_name():
    with pytest.raises(InputError, match="reserved"):
        Body("ground", 1.0, 1.0)


def test_joint_names_unknown_body():
    with pytest.raises(InputError, match=r"'pin' names unknown body 'rod'.*known bodies"):
        Mechanism([Body("crank", 1.0, 1.0)],
                  [RevoluteJoint("pin", "crank", "rod", (0.5, 0.0), (0.0, 0.0))])


def test_duplicate_body_names():
    with pytest.raises(InputError, match=r"body names must be unique.*'crank'"):
        Mechanism([Body("crank", 1.0, 1.0), Body("crank", 2.0, 1.0)])


def test_duplicate_joint_names():
    mech, _ = slider_crank()
    with pytest.raises(InputError, match=r"names must be unique.*'driver'"):
        Mechanism(mech.bodies, mech.constraints + (Driver("driver", "rod", 1.0),))


def _with_extra(constraint):
    mech, q_guess = slider_crank()
    return Mechanism(mech.bodies, mech.constraints + (constraint,), mech.forces), q_guess


@pytest.mark.parametrize("extra, culprit", [
    # the crank pivot a second time
    (RevoluteJoint("ground_crank_again", "crank", "ground", (-1.0, 0.0), (0.0, 0.0)),
     "ground_crank_again"),
    # a second driver on the crank: same speed (redundant) and another speed (inconsistent)
    (Driver("driver_again", "crank", math.pi), "driver_again"),
    (Driver("driver_fast", "crank", 2 * math.pi), "driver_fast"),
])
def test_redundant_constraints_are_singular(extra, culprit):
    mech, q_guess = _with_extra(extra)
    with pytest.raises(InputError, match="singular") as err:
        consistent_state(mech, q_guess)
    assert "redundant" in str(err.value) and culprit in str(err.value)


def test_four_bar_that_cannot_close():
    # coupler + rocker = 0.2 m cannot span the 0.3 m from the crank pin to O4
    mech, q_guess = four_bar(a=0.1, b=0.1, c=0.1, d=0.4)
    with pytest.raises(InputError, match="cannot be assembled") as err:
        consistent_state(mech, q_guess)
    assert "t = 0" in str(err.value) and "lengths" in str(err.value)


def test_four_bar_that_cannot_close_from_a_collinear_guess():
    # all links guessed on the x axis, where the Jacobian is singular: still a
    # geometry error, not a "redundant constraints" one
    mech, _ = four_bar(a=0.1, b=0.1, c=0.1, d=0.4)
    q_guess = jnp.array([0.05, 0.0, 0.0, 0.15, 0.0, 0.0, 0.35, 0.0, 0.0])
    with pytest.raises(InputError, match="cannot be assembled"):
        consistent_state(mech, q_guess)


def test_check_assembly_of_a_failed_solve_without_guess():
    mech, _ = slider_crank()
    q = jnp.full(mech.n_coords, jnp.nan)  # what assemble returns for a singular Newton matrix
    with pytest.raises(InputError, match="cannot be assembled.*non-finite"):
        check_assembly(mech, q, False)


def test_too_few_steps_raise_solver_error():
    # a pendulum (crank pinned to the ground, no driver): cheap to compile
    mech = Mechanism([Body("bob", 1.0, 0.1)],
                     [RevoluteJoint("pivot", "bob", "ground", (-0.5, 0.0), (0.0, 0.0))],
                     [Gravity()])
    y0 = consistent_state(mech, jnp.array([0.5, 0.0, 0.0]))
    traj = simulate(mech, y0, 1.0, ts=jnp.linspace(0.0, 1.0, 5), max_steps=10)
    with pytest.raises(SolverError, match="max_steps") as err:
        traj.raise_if_failed("pendulum")
    msg = str(err.value)
    assert msg.startswith("pendulum:") and "10 steps" in msg
    assert "1 of 5 saved times reached" in msg  # only t = 0
    assert not re.search(r"\b(inf|nan)\b", msg)  # unreached times are inf in diffrax


@pytest.mark.parametrize("value, high, message", [
    (0, 10, "--n must be an integer in [1, 10], got 0"),
    (11, 10, "--n must be an integer in [1, 10], got 11"),
    (2.0, 10, "--n must be an integer in [1, 10], got 2.0"),
    (True, 10, "--n must be an integer in [1, 10], got True"),
    (0, None, "--n must be an integer >= 1, got 0"),
    ("3", None, "--n must be an integer >= 1, got '3'"),
])
def test_integer_option_names_option_range_and_value(value, high, message):
    from diffwear._checks import check_int_option

    with pytest.raises(InputError) as err:
        check_int_option("--n", value, 1, high)
    assert str(err.value) == message
    check_int_option("--n", 10**9 if high is None else high, 1, high)  # the bound itself passes


def test_cli_and_engine_share_the_wear_choices():
    from diffwear.choices import WEAR_CONTACTS, WEAR_METHODS
    from diffwear.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    study = sub.choices["study"]
    choices = {a.dest: tuple(a.choices) for a in study._actions if a.choices}
    assert choices["contact"] == WEAR_CONTACTS and choices["method"] == WEAR_METHODS


def _cycle(mech, q_guess):
    from diffwear.dynamics.kinematics import check_cycle_motion

    q0 = mech.split(consistent_state(mech, q_guess))[0]
    check_cycle_motion(mech, q0, np.linspace(0.0, 1.0, 73), what="four-bar")


def test_a_crank_that_cannot_turn_fully_is_refused_at_the_angle_it_stops():
    """Non-Grashof (s + l = 0.3 + 0.4 > 0.35 + 0.3): the crank pin can reach
    O4 only while |A - O4| <= b + c = 0.65, i.e. cos(phi) >= (0.09 + 0.16 -
    0.4225) / 0.24 = -0.719, phi <= 136 deg: the first sample beyond is 140 deg."""
    mech, q_guess = four_bar(a=0.3, b=0.35, c=0.30, d=0.40)
    with pytest.raises(InputError, match=r"cannot move through its cycle: at t = 0\.3889 s "
                                         r"\(the driver at 140 deg"):
        _cycle(mech, q_guess)


def test_a_grashof_crank_rocker_moves_through_its_cycle():
    mech, q_guess = four_bar()
    _cycle(mech, q_guess)


# ------------------------------------------------ the Python API refuses what the CLI refuses
@pytest.fixture(scope="module")
def crank():
    mech, q_guess = slider_crank()
    return mech, consistent_state(mech, q_guess)


@pytest.mark.parametrize("y0, t1, match", [
    (lambda y: y[:-1], 0.01, r"y0 has shape \(\d+,\); expected \(\d+,\)"),
    (lambda y: y.astype(jnp.float32), 0.01, "y0 is float32; expected float64"),
    (lambda y: y.at[0].set(jnp.nan), 0.01, "y0 must be finite"),
    (lambda y: y, math.nan, "t1 must be finite"),
    (lambda y: y, -0.01, r"t1 = -0.01 s must be after t0 = 0 s"),
])
def test_simulate_refuses_a_bad_state_or_time(crank, y0, t1, match):
    mech, y = crank
    with pytest.raises(InputError, match=match):
        simulate(mech, y0(y), t1)


def test_two_joint_life_refuses_a_non_finite_or_short_design():
    """Eagerly an `InputError`; inside jit the program stops with the same
    words (never a NaN life beside a finite one)."""
    import jax

    from diffwear.design import TwoJointLife

    model = TwoJointLife()
    with pytest.raises(InputError, match=r"design must be finite, got \[nan"):
        model(np.array([np.nan, 0.02, 0.02, 0.02]))
    with pytest.raises(InputError, match=r"expected 4 values .* got shape \(3,\)"):
        model(np.array([0.02, 0.02, 0.02]))
    with pytest.raises(InputError, match=r"got shape \(3,\)"):
        jax.jit(lambda x: model(x))(jnp.array([0.02, 0.02, 0.02]))
    with pytest.raises(Exception, match="every value of .* must be finite"):
        jax.jit(lambda x: model(x))(jnp.array([jnp.nan, 0.02, 0.02, 0.02]))


def test_a_life_not_computed_has_a_nan_derivative_not_zero():
    """`jnp.where(ok, life, nan)` has derivative 0 where not ok; the life's
    NaN carries into the derivative instead (closed form beside it)."""
    import jax

    from diffwear.wear.life import not_computed_is_nan

    def life(k):
        return not_computed_is_nan(jnp.where(k < 1.0, 3.0 / k, jnp.nan), (k,))

    assert jax.grad(life)(0.5) == pytest.approx(-12.0)  # d(3/k)/dk = -3/k^2
    assert jax.jacfwd(life)(0.5) == pytest.approx(-12.0)
    for derivative in (jax.grad, jax.jacfwd):
        assert math.isnan(life(2.0)) and math.isnan(derivative(life)(2.0))


@pytest.mark.extended
def test_a_quasi_static_life_cut_short_has_a_nan_gradient():
    """One wear slot cannot reach the limit: status `RESULTS.run_ended_early`, the life
    NaN, and its gradient by the design NaN, never a silent 0."""
    import jax

    from diffwear.design import TwoJointLife
    from diffwear.models import QuasiStatic
    from diffwear.wear.status import RESULTS

    model = TwoJointLife(wear_model=QuasiStatic(samples=36, steps=16, max_steps=1),
                         n_theta=36).prepared()
    x = jnp.array([0.02, 0.02, 0.02, 0.02])
    assert bool(model.evaluate(x).result == RESULTS.run_ended_early)
    value, grad = jax.value_and_grad(lambda v: model(v)[0])(x)
    assert math.isnan(float(value)) and np.all(np.isnan(np.asarray(grad)))
