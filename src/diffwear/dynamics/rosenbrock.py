"""Linearly implicit (Rosenbrock) diffrax solvers with a structured Jacobian.

The stiffness of a mechanism with penalty contact lies in the few states the
contact forces read back: the coordinates and velocities (and a contact law's
memory).  The wear accumulators of a clearance joint are integrals of the
contact: they never feed back into the right-hand side within a cycle, so their
Jacobian columns are exactly zero.  These solvers form the Jacobian only over
the states that feed back (``jacobian_states``; `simulate` fills them in from
`Mechanism.feedback_states`), which makes the step matrix one small LU (18 x 18
on the three-body rig) plus a back-substitution for the other rows.

Methods, each with an embedded solution one order lower for the step
controller:

* `ROS3P` (Lang and Verwer 2001, BIT 41, 731-738): three stages, third
  order, A-stable (R(-inf) = 1 - sqrt(3) = -0.73: stiff modes alternate and
  decay slowly), an exact Jacobian at every step.
* `ROS34PW2` (Rang and Angermann 2005, BIT 45, 761-787): four stages, third
  order, L-stable, stiffly accurate and a W-method: it keeps its order with any
  approximation of the Jacobian, so the linearisation may be reused over
  ``jacobian_every`` steps.
* `Rodas4` (Hairer and Wanner, Solving ODEs II, Sec. VI.4): six stages,
  fourth order, L-stable and stiffly accurate, an exact Jacobian at every
  step.

All are written in the transformed form of Hairer and Wanner (Solving ODEs
II, 2nd ed., Sec. IV.7, Eq. 7.25) so that each stage is one back-substitution
and no product with J.  Dense output: the cubic Hermite interpolant of the
step's end values and slopes.  With the Jacobian in hand there is no Newton
iteration and no convergence test; the step is set by accuracy, not by the
stability limit of the contact stiffness that bounds explicit methods (the
performance docs give the measured step counts).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, ClassVar, NamedTuple

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import jax.scipy.linalg as jsl
import numpy as np

from ..errors import InputError
from .fused import t_times


class RosenbrockTableau(NamedTuple):
    """Coefficients in the transformed form (Hairer-Wanner Eq. IV.7.25):

        W = I / (h gamma) - J,
        W u_i = f(t + alpha_i h, y + sum_j a_ij u_j) + sum_j (c_ij / h) u_j
                + gamma_i h f_t,
        y1 = y + sum_i m_i u_i,  error = sum_i (m_i - m_embedded_i) u_i.
    """

    gamma: float
    a: tuple[tuple[float, ...], ...]
    c: tuple[tuple[float, ...], ...]
    alpha: tuple[float, ...]
    gammas: tuple[float, ...]
    m: tuple[float, ...]
    m_embedded: tuple[float, ...]
    order: int = 3

    @classmethod
    def from_standard(cls, gamma, alpha, gamma_offdiag, b, b_embedded,
                      order: int = 3) -> "RosenbrockTableau":
        """From the standard form (Hairer-Wanner Eq. IV.7.4: stage matrix
        I - h gamma J, strictly lower alpha_ij and gamma_ij, weights b, b^) by
        a = alpha Gamma^-1, c = diag(1 / gamma) - Gamma^-1, m = b Gamma^-1 with
        Gamma = gamma_ij + gamma I."""
        al, g_off = np.asarray(alpha, float), np.asarray(gamma_offdiag, float)
        s = al.shape[0]
        big_gamma = g_off + gamma * np.eye(s)
        inv = np.linalg.inv(big_gamma)
        a, c = al @ inv, np.eye(s) / gamma - inv
        return cls(
            gamma=float(gamma),
            a=tuple(tuple(float(a[i, j]) for j in range(i)) for i in range(s)),
            c=tuple(tuple(float(c[i, j]) for j in range(i)) for i in range(s)),
            alpha=tuple(float(x) for x in al.sum(axis=1)),
            gammas=tuple(float(x) for x in big_gamma.sum(axis=1)),
            m=tuple(float(x) for x in np.asarray(b, float) @ inv),
            m_embedded=tuple(float(x) for x in np.asarray(b_embedded, float) @ inv),
            order=order,
        )


# ROS3P (Lang and Verwer 2001) in transformed form, gamma = 1/2 + sqrt(3)/6.
# tests/test_rosenbrock.py checks them: order 3 observed, R(-inf) = 1 - sqrt(3)
# (the published stability limit).
_ROS3P_GAMMA = 0.5 + math.sqrt(3.0) / 6.0
ROS3P_TABLEAU = RosenbrockTableau(
    gamma=_ROS3P_GAMMA,
    a=((), (1.0 / _ROS3P_GAMMA,), (1.0 / _ROS3P_GAMMA, 0.0)),
    c=((), (-1.607695154586736,), (-3.464101615137755, -1.732050807568877)),
    alpha=(0.0, 1.0, 1.0),
    gammas=(_ROS3P_GAMMA, -0.2113248654051871, -1.077350269189626),
    m=(2.0, 0.5773502691896258, 0.4226497308103742),
    m_embedded=(2.113248654051871, 1.0, 0.4226497308103742),
)

# ROS34PW2 (Rang and Angermann 2005) in standard form.  tests/test_rosenbrock.py
# checks them: order 3 observed with the exact and with a stale Jacobian (the
# W-property), R(-inf) = 0 (L-stable).
_PW2_GAMMA = 4.3586652150845900e-01
ROS34PW2_TABLEAU = RosenbrockTableau.from_standard(
    gamma=_PW2_GAMMA,
    alpha=[[0.0, 0.0, 0.0, 0.0],
           [8.7173304301691801e-01, 0.0, 0.0, 0.0],
           [8.4457060015369423e-01, -1.1299064236397981e-01, 0.0, 0.0],
           [0.0, 0.0, 1.0, 0.0]],
    gamma_offdiag=[[0.0, 0.0, 0.0, 0.0],
                   [-8.7173304301691801e-01, 0.0, 0.0, 0.0],
                   [-9.0338057013044082e-01, 5.4180672388095326e-02, 0.0, 0.0],
                   [2.4212380706095346e-01, -1.2232505839045147e00, 5.4526025533510214e-01, 0.0]],
    b=[2.4212380706095346e-01, -1.2232505839045147e00, 1.5452602553351023e00,
       4.3586652150845900e-01],
    b_embedded=[3.7810903145819369e-01, -9.6042292212423178e-02, 0.5,
                2.1793326075422950e-01],
)

# RODAS4: Hairer and Wanner's RODAS (Solving ODEs II, 2nd ed., Sec. VI.4; the
# coefficients of their code rodas.f, coefficient set 1), given there in the
# transformed form.  Stiffly accurate: the last two stages are the embedded and
# the final solution (m = last row of a, then 1), so the error estimate is the
# last increment.  tests/test_rosenbrock.py checks them: order 4 observed,
# R(-inf) = 0 (L-stable).
_RODAS4_A5 = (1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950)
RODAS4_TABLEAU = RosenbrockTableau(
    gamma=0.25,
    a=((), (1.544,), (0.9466785280815826, 0.2557011698983284),
       (3.314825187068521, 2.896124015972201, 0.9986419139977817),
       _RODAS4_A5, _RODAS4_A5 + (1.0,)),
    c=((), (-5.6688,), (-2.430093356833875, -0.2063599157091915),
       (-0.1073529058151375, -9.594562251023355, -20.47028614809616),
       (7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160),
       (8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136,
        -6.058818238834054)),
    alpha=(0.0, 0.386, 0.21, 0.63, 1.0, 1.0),
    gammas=(0.25, -0.1043, 0.1035, -0.0362, 0.0, 0.0),
    m=_RODAS4_A5 + (1.0, 1.0),
    m_embedded=_RODAS4_A5 + (1.0, 0.0),
    order=4,
)


SENSITIVITIES = ("discrete", "ros2")
"""How a step's derivative is formed (`AbstractRosenbrock`'s ``sensitivity``)."""


class Linearisation(NamedTuple):
    """The solver state: f(t0, y0), the columns [f_t, J[:, jacobian_states]]
    of the last linearisation (rows: f_t, then one per Jacobian state) and the
    number of steps it has served."""

    f0: jax.Array
    columns: jax.Array
    age: jax.Array


class AbstractRosenbrock(diffrax.AbstractAdaptiveSolver):
    """A Rosenbrock method for a state that is one 1-D array, with the Jacobian
    formed only over ``jacobian_states`` (see the module notes).

    ``jacobian_states``: indices of the states the vector field reads (its
    Jacobian columns); every other state must not feed back (its column is
    taken as zero; its rows stay exact).  ``None``: all states (a dense
    Jacobian).  Passed to `diffwear.dynamics.simulate`, a solver without them
    gets the mechanism's `Mechanism.feedback_states`.

    ``differentiate_jacobian``: derivatives of the solution go through the
    Jacobian (the exact derivative of the discrete solution; second
    derivatives of the vector field) or hold it at the unperturbed run
    (cheaper; keeps the method's order only for a W-method).
    ``sensitivity``: how a step's derivative is formed.  ``"discrete"``: the
    derivative of the step itself, its stage equations differentiated (with
    or without the Jacobian's change, per ``differentiate_jacobian``); one
    evaluation of f with its tangents per stage.  ``"ros2"``: the
    sensitivity equation dS/dt = f_y S + f_p dp stepped along each step's
    solution by ROS2 (second order with any Jacobian, L-stable), the step's
    linearisation in its step matrix: two evaluations of f with their
    tangents per step whatever the number of stages, the Jacobian never
    differentiated (``differentiate_jacobian`` has no effect; a solver that
    reuses a linearisation over several steps refuses it).  The tangents
    are then second order in the step and not error-controlled, like the
    held route's (first order).  For settled contact only: where a pin
    impacts, steps that resolve the solution's stiff modes in part leave
    second-order tangents tens of percent off (the performance docs give
    the three routes on the rig and on an impacting slider-crank); check
    with `diffwear.gradcheck`.
    ``dense_output``: the cubic Hermite interpolant between steps (one more
    evaluation per step); without it, the chord (`simulate` drops it when
    only the end state is saved: the end values are exact either way).
    ``jacobian_args``: a map of the vector field's ``args`` to args with the
    same values that are cheaper to form the Jacobian's columns with (many
    directions at once), used for the linearisation only; the stages and
    their tangents (a few directions) evaluate the vector field with
    ``args`` themselves.  `simulate` passes `Mechanism.for_state_jacobian`
    (contact laws differentiated once in the pin's motion): a stage's
    4-parameter tangent on the rig costs a third less through the plain law.
    Give a module-level function: the solver is a static part of the
    compiled integration, so a new lambda per call recompiles.
    """

    jacobian_states: eqx.AbstractVar[tuple[int, ...] | None]
    jacobian_args: eqx.AbstractVar[Callable[[Any], Any] | None]
    differentiate_jacobian: eqx.AbstractVar[bool]
    dense_output: eqx.AbstractVar[bool]
    sensitivity: eqx.AbstractVar[str]
    tableau: eqx.AbstractClassVar[RosenbrockTableau]

    term_structure: ClassVar = diffrax.AbstractTerm
    interpolation_cls: ClassVar[
        Callable[..., diffrax.ThirdOrderHermitePolynomialInterpolation]
    ] = diffrax.ThirdOrderHermitePolynomialInterpolation

    def __check_init__(self):
        if self.sensitivity not in SENSITIVITIES:
            raise InputError(f"{type(self).__name__}: sensitivity must be one of "
                             f"{', '.join(map(repr, SENSITIVITIES))}, got {self.sensitivity!r}")
        js = self.jacobian_states
        if js is not None and (len(js) == 0 or min(js) < 0 or len(set(js)) != len(js)):
            raise InputError(f"{type(self).__name__}: jacobian_states must be distinct "
                             f"non-negative state indices, got {js!r}")

    @property
    def reuse(self) -> int:
        """Steps one linearisation serves (1: an exact Jacobian at every step)."""
        return 1

    def order(self, terms):
        return self.tableau.order

    def func(self, terms, t0, y0, args):
        return terms.vf(t0, y0, args)

    def _blocks(self, y0) -> tuple[np.ndarray | slice, np.ndarray | slice]:
        """(states with Jacobian columns, the others), checked against ``y0``:
        slices when the former are a leading block (a mechanism's q, qd and
        contact memory usually are), else index arrays."""
        if not (isinstance(y0, jax.Array) and y0.ndim == 1):
            structure = jax.tree_util.tree_structure(y0)
            raise InputError(f"{type(self).__name__} integrates a state that is one 1-D array "
                             f"(the mechanism's packed state), got {structure}")
        n = y0.shape[0]
        js = np.arange(n) if self.jacobian_states is None else np.asarray(self.jacobian_states)
        if js.max() >= n:
            raise InputError(f"{type(self).__name__}: jacobian_states index {int(js.max())} is "
                             f"outside the state (size {n})")
        if np.array_equal(js, np.arange(js.size)):
            return slice(0, js.size), slice(js.size, n)
        return js, np.setdiff1d(np.arange(n), js)

    def _args_for_jacobian(self, args):
        return args if self.jacobian_args is None else self.jacobian_args(args)

    def _linearise(self, terms, t0, y0, args) -> Linearisation:
        stiff, _ = self._blocks(y0)
        args = self._args_for_jacobian(args)
        index, dtype = np.arange(y0.shape[0])[stiff], y0.dtype
        k = index.size
        f0, linear = jax.linearize(lambda t, y: terms.vf(t, y, args), jnp.asarray(t0, dtype), y0)
        dts = jnp.zeros(k + 1, dtype).at[0].set(1.0)
        dys = jnp.zeros((k + 1, y0.shape[0]), dtype).at[1 + np.arange(k), index].set(1.0)
        columns = jax.vmap(linear)(dts, dys)
        if not self.differentiate_jacobian:
            columns = jax.lax.stop_gradient(columns)
        return Linearisation(f0, columns, jnp.zeros((), jnp.int32))

    def init(self, terms, t0, t1, y0, args):
        if self.reuse == 1:
            return None
        return self._linearise(terms, t0, y0, args)

    def _w_solve(self, lin: Linearisation, h, y0,
                 gamma: float | None = None) -> Callable[[jax.Array], jax.Array]:
        """x -> W^-1 x with W = I / (h gamma) - J, J the linearisation's
        columns (zero in the other states); gamma the tableau's unless given."""
        stiff, free = self._blocks(y0)
        jac = lin.columns[1:].T
        hg = h * (self.tableau.gamma if gamma is None else gamma)
        lu = jsl.lu_factor(jnp.eye(jac.shape[1], dtype=y0.dtype) / hg - jac[stiff])
        j_free = jac[free]

        def w_solve(rhs):
            # W = [[I/hg - J_ss, 0], [-J_fs, I/hg]] in (stiff, free) order
            top = jsl.lu_solve(lu, rhs[stiff])
            rest = hg * (rhs[free] + j_free @ top)
            if isinstance(stiff, slice):
                return jnp.concatenate([top, rest])
            return jnp.zeros_like(rhs).at[stiff].set(top).at[free].set(rest)

        return w_solve

    def _coefficients(self, dtype) -> "_Coefficients":
        """The tableau as arrays: a stage's combinations are one weighted sum
        of the stacked increments, so the stages run as one `jax.lax.scan`
        (the vector field traced once, not once per stage: half the compile
        time of a rig cycle on Rodas4)."""
        tab = self.tableau
        s = len(tab.m)
        a, c = np.zeros((s, s)), np.zeros((s, s))
        for i in range(s):
            a[i, :i], c[i, :i] = tab.a[i], tab.c[i]
        m, m_hat = np.asarray(tab.m), np.asarray(tab.m_embedded)
        return _Coefficients(*(jnp.asarray(x, dtype) for x in (
            a, c, tab.alpha, tab.gammas, m, m - m_hat)))

    def _stages(self, terms, args, t0, h, y0, lin: Linearisation):
        """(y1, error estimate, the stacked stage increments u_i) of one step."""
        co = self._coefficients(y0.dtype)
        w_solve = self._w_solve(lin, h, y0)
        f_t = lin.columns[0]

        def stage(us, i):
            f_stage = terms.vf(t0 + co.alpha[i] * h, y0 + t_times(us, co.a[i]), args)
            u = w_solve(f_stage + t_times(us, co.c[i]) / h + co.gammas[i] * h * f_t)
            return us.at[i].set(u), None

        # stage 0 evaluates f at (t0, y0): the linearisation's f0
        us = jnp.zeros((co.m.size,) + y0.shape, y0.dtype)
        us = us.at[0].set(w_solve(lin.f0 + co.gammas[0] * h * f_t))
        us, _ = jax.lax.scan(stage, us, jnp.arange(1, co.m.size))
        return (*co.solution(y0, us), us)

    def _stage_rhs(self, i, f_stage, us, h, f_t):
        """The right-hand side of stage i, W u_i = f_stage + sum_j (c_ij / h) u_j
        + gamma_i h f_t, from the increments ``us`` of the stages before it."""
        tab = self.tableau
        rhs = f_stage + _combine(tab.c[i], us, f_stage) / h
        if tab.gammas[i] != 0.0:  # Rodas4's last two stages have no f_t term
            rhs = rhs + tab.gammas[i] * h * f_t
        return rhs

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        dtype = y0.dtype if isinstance(y0, jax.Array) else float
        t0 = jnp.asarray(t0, dtype)
        h = jnp.asarray(t1, dtype) - t0
        if solver_state is None:
            y1, y_error, f0 = _fresh_step(self, terms, args, t0, h, y0)
        else:
            # reuse the linearisation for ``reuse`` steps; f0 is the last step's
            # end slope (a rejected step keeps the state it started from)
            fresh = (solver_state.age >= self.reuse) | jnp.asarray(made_jump)
            lin = jax.lax.cond(fresh, lambda: self._linearise(terms, t0, y0, args),
                               lambda: solver_state)
            y1, y_error, _ = self._stages(terms, args, t0, h, y0, lin)
            f0 = lin.f0
        if self.dense_output or solver_state is not None:
            f1 = terms.vf(t0 + h, y1, args)  # the Hermite slope; the next f0 when reused
        if self.dense_output:
            dense_info = dict(y0=y0, y1=y1, k0=h * f0, k1=h * f1)
        else:  # equal slopes: the cubic is the chord, exact at both ends
            dense_info = dict(y0=y0, y1=y1, k0=y1 - y0, k1=y1 - y0)
        state = None if solver_state is None else Linearisation(f1, lin.columns, lin.age + 1)
        return y1, y_error, dense_info, state, diffrax.RESULTS.successful


class _Coefficients(NamedTuple):
    """A tableau's coefficients as arrays (`AbstractRosenbrock._coefficients`):
    a and c strictly lower triangular, m - m_hat the error weights."""

    a: jax.Array
    c: jax.Array
    alpha: jax.Array
    gammas: jax.Array
    m: jax.Array
    error_weights: jax.Array

    def solution(self, y0, us):
        """(y1, error estimate) from the stacked stage increments."""
        return y0 + t_times(us, self.m), t_times(us, self.error_weights)


def _combine(coeffs, vectors, like):
    """sum_i coeffs[i] vectors[i] (zero coefficients skipped)."""
    return sum((c * v for c, v in zip(coeffs, vectors) if c != 0.0), jnp.zeros_like(like))


def _plain_fresh_step(solver: AbstractRosenbrock, terms, args, t0, h, y0):
    """(y1, error estimate, f(t0, y0)) of a step with a fresh linearisation."""
    lin = solver._linearise(terms, t0, y0, args)
    y1, y_error, _ = solver._stages(terms, args, t0, h, y0, lin)
    return y1, y_error, lin.f0


_fresh_step = eqx.filter_custom_jvp(_plain_fresh_step)


@_fresh_step.def_jvp
def _fresh_step_jvp(primals, tangents):
    """The step's derivative along (y0, args) by differentiating the stage
    equations W u_i = r_i themselves: W du_i = dr_i + (dJ) u_i, with the
    Jacobian's change along the tangent applied to u_i as one second-order
    directional derivative (and likewise for f_t), instead of differentiating
    the formation of all of J's columns.  The factorised W serves the
    tangents.  Each stage's f is evaluated once for its value and its
    tangents (linearised where (dJ) u_i needs every stage first).  A Jacobian
    held at the unperturbed run drops the dJ terms."""
    solver, terms, args, t0, h, y0 = primals
    _, _, t_args, t_t0, t_h, t_y0 = tangents
    if t_t0 is not None or t_h is not None:  # step times depend on the parameters
        return eqx.filter_jvp(_plain_fresh_step, primals, tangents)
    lin = solver._linearise(terms, t0, y0, args)
    dy0 = jnp.zeros_like(y0) if t_y0 is None else t_y0
    if solver.sensitivity == "ros2":
        y1, y_error, _ = solver._stages(terms, args, t0, h, y0, lin)
        dy1, df0 = _ros2_tangent(solver, terms, args, t0, h, y0, y1, lin, dy0, t_args)
        return (y1, y_error, lin.f0), (dy1, jnp.zeros_like(y_error), df0)
    w_solve = solver._w_solve(lin, h, y0)

    stage_tangents = _exact_tangents if solver.differentiate_jacobian else _held_tangents
    us, dus, df0 = stage_tangents(solver, terms, args, t0, h, y0, lin, w_solve, dy0, t_args)
    co = solver._coefficients(y0.dtype)
    return (*co.solution(y0, jnp.stack(us)), lin.f0), (*co.solution(dy0, jnp.stack(dus)), df0)


def _jvp(fn, primals, tangents):
    """`eqx.filter_jvp`, with the output's tangent as zeros where it depends on
    none of the tangents' inputs (filter_jvp gives None there: a vector field
    that reads neither the state nor the args, or a linear one's Jacobian)."""
    out, t_out = eqx.filter_jvp(fn, primals, tangents)
    return out, jnp.zeros_like(out) if t_out is None else t_out


def _vf_jvp(terms, t, y, args, dy, t_args):
    """(f(t, y), its tangent along (dy, t_args))."""
    return _jvp(lambda z, a: terms.vf(t, z, a), (y, args), (dy, t_args))


def _exact_tangents(solver, terms, args, t0, h, y0, lin, w_solve, dy0, t_args):
    """(stage increments u_i, their tangents, d f(t0, y0)).  The stages
    first, each linearised: d/de [f_t, J u_1 .. J u_s] at (y0 + e dy0,
    args + e dargs) is then one batched derivative, J over the Jacobian
    states only (the others' columns are taken as zero).  The args'
    leaves with a tangent are the linear maps' inputs.  Unrolled: a stage's
    linear map cannot be carried through a scan, and evaluating f again for
    the tangents cost 1.3x."""
    tab = solver.tableau
    stiff, _ = solver._blocks(y0)
    d_args_tangent = jax.tree_util.tree_map(lambda _: None, args) if t_args is None else t_args
    has_tangent = jax.tree_util.tree_map(lambda t: t is not None, d_args_tangent,
                                         is_leaf=lambda t: t is None)
    d_args, const_args = eqx.partition(args, has_tangent)
    us, f_lins = [], []
    for i in range(len(tab.m)):
        f_stage, f_lin = jax.linearize(
            lambda z, a, t=t0 + tab.alpha[i] * h: terms.vf(t, z, eqx.combine(a, const_args)),
            y0 + _combine(tab.a[i], us, y0), d_args)
        f_lins.append(f_lin)
        us.append(w_solve(solver._stage_rhs(i, lin.f0 if i == 0 else f_stage, us, h,
                                            lin.columns[0])))
    inner_t = jnp.zeros(len(us) + 1, y0.dtype).at[0].set(1.0)
    inner_y = jnp.stack([jnp.zeros_like(y0)] + [
        jnp.zeros_like(u).at[stiff].set(u[stiff]) for u in us])

    def directional(z, a):
        a = solver._args_for_jacobian(a)
        return jax.vmap(lambda dt, dz: jax.jvp(lambda s, x: terms.vf(s, x, a), (t0, z),
                                               (dt, dz))[1])(inner_t, inner_y)

    d_lin = _jvp(directional, (y0, args), (dy0, t_args))[1]  # [d f_t, (dJ) u_1, ..]
    dus: list[jax.Array] = []
    for i in range(len(tab.m)):
        df_stage = f_lins[i](dy0 + _combine(tab.a[i], dus, y0), d_args_tangent)
        dus.append(w_solve(solver._stage_rhs(i, df_stage + d_lin[1 + i], dus, h, d_lin[0])))
        if i == 0:
            df0 = df_stage
    return us, dus, df0


def _held_tangents(solver, terms, args, t0, h, y0, lin, w_solve, dy0, t_args):
    """(stage increments u_i, their tangents, d f(t0, y0)).  Each stage with
    its tangent, one evaluation of f serving both; the held Jacobian has no
    dJ terms.  Unrolled: as one scan over the stages, the
    4-parameter Jacobian of a settled rig cycle took 1.5x as long."""
    tab = solver.tableau
    us: list[jax.Array] = []
    dus: list[jax.Array] = []
    for i in range(len(tab.m)):
        f_stage, df_stage = _vf_jvp(terms, t0 + tab.alpha[i] * h, y0 + _combine(tab.a[i], us, y0),
                                    args, dy0 + _combine(tab.a[i], dus, y0), t_args)
        us.append(w_solve(solver._stage_rhs(i, lin.f0 if i == 0 else f_stage, us, h,
                                            lin.columns[0])))
        dus.append(w_solve(solver._stage_rhs(i, df_stage, dus, h, 0.0)))
        if i == 0:
            df0 = df_stage
    return us, dus, df0


# ROS2 (Verwer, Spee, Blom and Hundsdorfer 1999, SIAM J. Sci. Comput. 20,
# 1456-1480): two stages, second order with any matrix in place of the
# Jacobian (a W-method, so the time derivative may be left out) and L-stable
# for gamma = 1 + 1/sqrt(2).  tests/test_rosenbrock.py checks both.
_ROS2_GAMMA = 1.0 + 1.0 / math.sqrt(2.0)


def _ros2_tangent(solver, terms, args, t0, h, y0, y1, lin, dy0, t_args):
    """(tangent of y1, d f(t0, y0)): the sensitivity equation
    dS/dt = f_y(y(t)) S + f_p(y(t)) dp stepped from t0 to t0 + h by ROS2 along
    the step's own solution (its ends y0, y1), with the linearisation's
    Jacobian in the step matrix.  Two evaluations of f with their tangents a
    step, whatever the method's number of stages."""
    gamma = _ROS2_GAMMA
    w_solve = solver._w_solve(lin, h, y0, gamma)  # W = I / (h gamma) - J
    # increments K_i = h k_i of (I - gamma h J) k_1 = F(t0, S0),
    # (I - gamma h J) k_2 = F(t0 + h, S0 + h k_1) - 2 k_1, S1 = S0 + 3/2 K_1 + 1/2 K_2
    df0 = _vf_jvp(terms, t0, y0, args, dy0, t_args)[1]
    k1 = w_solve(df0) / gamma
    k2 = w_solve(_vf_jvp(terms, t0 + h, y1, args, dy0 + k1, t_args)[1] - 2.0 * k1 / h) / gamma
    return dy0 + 1.5 * k1 + 0.5 * k2, df0


class ROS3P(AbstractRosenbrock):
    """ROS3P (Lang and Verwer 2001): three stages, third order, A-stable, an
    exact Jacobian at every step.  Cost per step: one linearisation (the
    vector field and len(jacobian_states) + 1 tangents, batched), one LU of
    that size, two more evaluations and one at the step's end (dense output).
    Derivatives (forward and reverse, diffrax's adjoints) are exact for the
    discrete solution: the step's rule solves the differentiated stage
    equations with the factorised step matrix."""

    jacobian_states: tuple[int, ...] | None = eqx.field(static=True, default=None)
    jacobian_args: Callable[[Any], Any] | None = eqx.field(static=True, default=None)
    differentiate_jacobian: bool = eqx.field(static=True, default=True)
    dense_output: bool = eqx.field(static=True, default=True)
    sensitivity: str = eqx.field(static=True, default="discrete")
    tableau: ClassVar[RosenbrockTableau] = ROS3P_TABLEAU


class ROS34PW2(AbstractRosenbrock):
    """ROS34PW2 (Rang and Angermann 2005): four stages, third order, L-stable,
    stiffly accurate, and a W-method: its order holds with any Jacobian, so a
    linearisation serves ``jacobian_every`` steps (1: fresh at every step).
    Between linearisations a step costs four evaluations of the vector field
    and an LU of the Jacobian block; the step controller sees the price of a
    stale Jacobian as a smaller step."""

    jacobian_states: tuple[int, ...] | None = eqx.field(static=True, default=None)
    jacobian_args: Callable[[Any], Any] | None = eqx.field(static=True, default=None)
    differentiate_jacobian: bool = eqx.field(static=True, default=False)
    dense_output: bool = eqx.field(static=True, default=True)
    sensitivity: str = eqx.field(static=True, default="discrete")
    jacobian_every: int = eqx.field(static=True, default=1)
    tableau: ClassVar[RosenbrockTableau] = ROS34PW2_TABLEAU

    def __check_init__(self):
        if not (isinstance(self.jacobian_every, int) and self.jacobian_every >= 1):
            raise InputError(f"ROS34PW2: jacobian_every must be an integer >= 1, got "
                             f"{self.jacobian_every!r}")
        if self.sensitivity == "ros2" and self.jacobian_every != 1:
            raise InputError("ROS34PW2: sensitivity='ros2' takes its step matrix from each "
                             "step's own linearisation, so it needs jacobian_every=1, got "
                             f"{self.jacobian_every}")

    @property
    def reuse(self) -> int:
        return self.jacobian_every


class Rodas4(AbstractRosenbrock):
    """RODAS4 (Hairer and Wanner, Solving ODEs II, Sec. VI.4): six stages,
    fourth order with a third-order embedded solution, L-stable and stiffly
    accurate, an exact Jacobian at every step.  A step costs one
    linearisation, one LU and five more evaluations (six with dense output);
    at the loose tolerances of a wear cycle it takes about a third of ROS3P's
    steps on the rig (the performance docs give the counts).  A step's
    derivative is exact for the discrete solution, as for `ROS3P`.  The
    tangents are not error-controlled: at the loose tolerance of a wear cycle
    (1e-4) they are ~15 % off on the rig, at rtol 1e-6 within 2e-5 (measured
    in the performance docs), so take gradients at the tighter tolerance.
    ``Rodas4(differentiate_jacobian=False)`` is the cheaper gradient route: no
    second derivatives, one evaluation per stage for the value and its
    tangents; the tangents are then first order in the step (Rodas4 is not a
    W-method), 4e-6 off the exact ones on a settled rig cycle at rtol 1e-6,
    for ~3 forward runs per 4-parameter Jacobian instead of ~7.
    ``Rodas4(sensitivity="ros2")`` is the cheapest: two evaluations with
    tangents a step instead of six, second-order tangents, 6e-6 off the exact
    ones there, for 1.6-2.0 forward runs; on settled contact only (through
    impacts they can be tens of percent off)."""

    jacobian_states: tuple[int, ...] | None = eqx.field(static=True, default=None)
    jacobian_args: Callable[[Any], Any] | None = eqx.field(static=True, default=None)
    differentiate_jacobian: bool = eqx.field(static=True, default=True)
    dense_output: bool = eqx.field(static=True, default=True)
    sensitivity: str = eqx.field(static=True, default="discrete")
    tableau: ClassVar[RosenbrockTableau] = RODAS4_TABLEAU
