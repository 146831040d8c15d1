"""Solving the Ch. 8 design problems with optimistix, directly on the model.

Bounds by reparametrisation: each free variable is x = lo + (hi - lo)
sigmoid(u) with u unbounded, so every iterate lies strictly inside the
Table 8-3 box and the solvers need no projection.  Variables not solved for
are held at given values (possibly on a bound).

All three problems are (small) nonlinear least-squares problems solved by
optimistix's Levenberg-Marquardt.  The model's Jacobian comes from automatic
differentiation when the model's derivative is the slope of its life (the
quasi-static model: ``model.exact_gradients``), else from central differences
(`finite_difference_jacobian`, 8 runs: the dynamic model); the
reparametrisation's always from autodiff:

* `equal_life`: r = (cyc1 - cyc2) / mean(cyc1, cyc2) over all 4 variables
  (the thesis's objective (cyc1 - cyc2)^2 is r^2 up to the scale; 1 equation,
  4 unknowns: the damped Gauss-Newton step is a least-change step, so it
  lands near the member of the solution family nearest the start).
* `longest_common_life`: maximise min(cyc1, cyc2).  Life rises with depth and
  falls with diameter (checked on the way: the gradient signs at the corner),
  so the weaker joint takes its life-maximising corner (d = 20 mm, h = 50 mm)
  and the stronger joint's depth is solved for equal life (d at 20 mm too:
  least material among the equal-life designs).
* `least_material`: both joints exactly at a target life T with the least
  bushing volume V = sum_j pi ((R_j + w_j)^2 - R_j^2) h_j (w_j the wall).  V
  grows with d and h while life falls with d, so d takes its lower bound and
  (h1, h2) solve cyc1 = cyc2 = T (2 equations, 2 unknowns).

The corner arguments are verified, not assumed: `kkt_check` evaluates the
Karush-Kuhn-Tucker sign conditions with the model's gradients at the answer.

`space_mapped` solves a problem on a fast model (quasi-static, exact
gradients) and corrects it on a reference model (dynamic): output space
mapping (Bandler et al., IEEE Trans. MTT 52, 2004), shifting the fast model's
lives by the reference-minus-fast difference at the current design and
solving again, until the reference model meets the problem's residual bar.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import partial

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jax import lax

from ..errors import InputError, SolverError
from .two_joint import LOWER, UPPER, VARIABLES, WALL_PER_RADIUS, TwoJointLife, check_design


def to_free(x, lo, hi):
    """u with lo + (hi - lo) sigmoid(u) = x (x strictly inside (lo, hi))."""
    s = (x - lo) / (hi - lo)
    return jnp.log(s) - jnp.log1p(-s)


def from_free(u, lo, hi):
    return lo + (hi - lo) * jax.nn.sigmoid(u)


def bushing_volume(x) -> jnp.ndarray:
    """PTFE volume of both bushings [m^3]: pi ((R + w)^2 - R^2) h, w = wall."""
    r = 0.5 * jnp.stack([x[0], x[1]])
    w = WALL_PER_RADIUS * r
    return jnp.sum(jnp.pi * w * (2 * r + w) * jnp.stack([x[2], x[3]]))


@dataclass
class DesignResult:
    """One solved design problem.  ``x`` [m] = (d1, d2, h1, h2); ``cycles`` =
    (cyc1, cyc2) from a fresh evaluation of the model at ``x``; ``history``:
    one entry per model evaluation inside the solver."""

    problem: str
    x: np.ndarray
    cycles: np.ndarray
    iterations: int
    model_evaluations: int
    wall_time_s: float
    history: list = field(default_factory=list)
    notes: dict = field(default_factory=dict)

    @property
    def rel_gap(self) -> float:
        c1, c2 = self.cycles
        return float(abs(c1 - c2) / (0.5 * (c1 + c2)))

    def summary(self) -> dict:
        d1, d2, h1, h2 = (float(v) * 1e3 for v in self.x)
        return {"problem": self.problem, "d1_mm": d1, "d2_mm": d2, "h1_mm": h1, "h2_mm": h2,
                "cyc1": float(self.cycles[0]), "cyc2": float(self.cycles[1]),
                "rel_gap": self.rel_gap, "iterations": self.iterations,
                "model_evaluations": self.model_evaluations,
                "wall_time_s": self.wall_time_s,
                "bushing_volume_mm3": float(bushing_volume(jnp.asarray(self.x))) * 1e9,
                **self.notes}


def levenberg_marquardt(rtol: float, atol: float) -> optx.LevenbergMarquardt:
    """optimistix's Levenberg-Marquardt with a textbook trust-region update.

    optimistix's `ClassicalTrustRegion` widens the region only when the actual
    reduction is within 1 % of the predicted one (``high_cutoff=0.99``).  A
    model seen through the sigmoid reparametrisation (and a simulator with
    adaptive steps) rarely predicts that well, so the damping never relaxed
    and the equal-life gap shrank slowly (docs/notes/design-solver.md).
    We widen at a ratio above 3/4
    as Nocedal & Wright's Algorithm 4.1 does; a step is still rejected (and
    the region shrunk) only below optimistix's 0.01, since optimistix ties
    rejection and shrinking to one cutoff and a noisy model should keep a
    step that gained a little."""
    solver: optx.LevenbergMarquardt = optx.LevenbergMarquardt(rtol=rtol, atol=atol)
    search: optx.ClassicalTrustRegion = optx.ClassicalTrustRegion(high_cutoff=0.75)
    return eqx.tree_at(lambda s: s.search, solver, search)


# A solve that hits its step limit is still an answer when every residual of
# a fresh rerun is within this: the design's bar (equal life within 0.5 %), and
# 0.5 % of a target life.
ACCEPT_RESIDUAL = 5e-3
START_MARGIN = 0.1  # free variables start at least 10 % of their range inside the box
FD_REL_STEP = 1e-3  # central-difference step, relative to each design variable


def finite_difference_jacobian(model, rel_step: float = FD_REL_STEP, on_jacobian=None):
    """``model`` with its derivative taken by central differences (a
    `jax.custom_jvp`: J v with J from 8 perturbed runs evaluated in one vmap).

    Why not automatic differentiation: the life model's forward-mode
    derivative matches central differences only where the wear stays shallow
    (design note "The dynamic life's derivative": at cycle_rtol 1e-8 the whole
    Jacobian within 0.12 % for a 0.2 mm limit, but the second joint's row
    ~30x off at the 2 mm limit, where the joint held at its end-of-life
    groove makes one cycle's wear rough in the design).  Central differences
    at 1e-3 relative step over that roughness; they are not converged at
    1e-4 at the default cycle tolerance 1e-6."""
    @jax.custom_jvp
    def f(x):
        return model(x)

    @f.defjvp
    def f_jvp(primals, tangents):
        (x,), (v,) = primals, tangents
        step = rel_step * jnp.abs(x)
        eye = jnp.eye(x.shape[0]) * step[:, None]
        points = jnp.concatenate([x + eye, x - eye])
        # lax.map, not vmap: each run skips the scan slots after its end
        # (under vmap lax.cond turns into select and every slot runs)
        values = lax.map(model, points)
        n = x.shape[0]
        jac = ((values[:n] - values[n:]) / (2 * step[:, None])).T
        if on_jacobian is not None:
            jax.debug.callback(on_jacobian, jac)
        return model(x), jac @ v

    return f


def jacobian_method(model) -> str:
    """"autodiff" when ``model.exact_gradients``, else "finite-difference"."""
    return "autodiff" if getattr(model, "exact_gradients", False) else "finite-difference"


class CompiledLife:
    """A life model with exact gradients, compiled once: each call gives the
    lives and their Jacobian (`jax.jacfwd`).  Inside a traced solver it enters
    as a host callback with a custom JVP, so the solver's own compiled loop
    stays small and every solve, space-mapping round and Jacobian of a study
    reuses one compiled model (the compile times: docs/notes/design-solver.md)."""

    def __init__(self, model):
        self.model = model
        self._compiled = None
        self._last: tuple | None = None

    def _executable(self):
        # compiled ahead of time: a jitted function called both from a solver's
        # host callback and from the main thread was traced and compiled twice
        # (jit's cache is keyed on the calling thread's trace context;
        # docs/notes/design-solver.md)
        if self._compiled is None:
            spec = jax.ShapeDtypeStruct((len(VARIABLES),), jnp.float64)
            self._compiled = jax.jit(lambda x: _value_and_jacobian(self.model, x)).lower(
                spec).compile()
        return self._compiled

    def value_and_jacobian(self, x) -> tuple[np.ndarray, np.ndarray]:
        x = np.asarray(x, dtype=np.float64)
        if self._last is None or not np.array_equal(self._last[0], x):
            value, jac = self._executable()(jnp.asarray(x))
            self._last = (x, np.asarray(value, np.float64), np.asarray(jac, np.float64))
        return self._last[1], self._last[2]

    def life(self, x) -> np.ndarray:
        return self.value_and_jacobian(x)[0]

    def __call__(self, x):
        return _host_life(self, x)


def _value_and_jacobian(model, x):
    """(model(x), jacfwd(model)(x)) from one forward-mode pass (one trace)."""
    basis = jnp.eye(x.shape[0], dtype=x.dtype)
    value, columns = jax.vmap(lambda v: jax.jvp(model, (x,), (v,)), out_axes=(None, -1))(basis)
    return value, columns


_VALUE = jax.ShapeDtypeStruct((2,), jnp.float64)
_JACOBIAN = jax.ShapeDtypeStruct((2, 4), jnp.float64)


@partial(jax.custom_jvp, nondiff_argnums=(0,))
def _host_life(life: CompiledLife, x):
    return jax.pure_callback(lambda x: life.value_and_jacobian(x)[0], _VALUE, x)


@_host_life.defjvp
def _host_life_jvp(life, primals, tangents):
    (x,), (v,) = primals, tangents
    value, jac = jax.pure_callback(life.value_and_jacobian, (_VALUE, _JACOBIAN), x)
    return value, jac @ v


_COMPILED: dict[int, tuple] = {}


def compiled(model) -> CompiledLife:
    """The `CompiledLife` of ``model`` (made once per model object)."""
    key = id(model)
    if key not in _COMPILED or _COMPILED[key][0] is not model:
        _COMPILED[key] = (model, CompiledLife(model))
    return _COMPILED[key][1]


def _differentiable(model, on_jacobian=None):
    """``model`` as a traceable function with the right derivative: its
    `CompiledLife` (autodiff) or its central-difference wrapper."""
    if jacobian_method(model) == "autodiff":
        return compiled(model)
    return finite_difference_jacobian(model, on_jacobian=on_jacobian)


def life_of(model, x) -> np.ndarray:
    """[cyc1, cyc2] of ``model`` at ``x`` (through its `CompiledLife` when it has one)."""
    if isinstance(model, ShiftedLife):
        return life_of(model.model, x) + np.asarray(model.shift)
    if jacobian_method(model) == "autodiff":
        return compiled(model).life(x)
    return model.life(x)


# Every model evaluation inside a solve, appended by `_record` (a host callback):
# one module-level recorder, so that the compiled solve is the same function
# from call to call and jit's cache serves repeated solves (space mapping).
_HISTORY: list[dict] = []


def _record(x, cycles, r):
    _HISTORY.append({"x_mm": (np.asarray(x) * 1e3).tolist(),
                     "cycles": np.asarray(cycles).tolist(),
                     "residual": np.asarray(r).tolist()})


def _design_residual(u, args):
    """Residual of a design problem at free coordinates ``u`` (all 4 variables;
    the fixed ones are masked to ``base``); ``shift``: space-mapping shift."""
    life, residual, base, free, shift = args
    x = jnp.where(free, from_free(u, jnp.asarray(LOWER), jnp.asarray(UPPER)), base)
    cycles = life(x) + shift
    r = residual(x, cycles)
    jax.debug.callback(_record, x, cycles, r)
    return r


def _solve(model: TwoJointLife | ShiftedLife, problem: str, residual, x_fixed, free, *, rtol, atol,
           max_steps) -> DesignResult:
    """Levenberg-Marquardt on residual(x, cycles) over the ``free`` variables."""
    x_fixed = np.asarray(x_fixed, dtype=float)
    check_design(x_fixed, what=f"{problem}: start")
    free = np.asarray(free, dtype=bool)
    # a start near a bound moves inside: the sigmoid is flat there (a Newton
    # step from u = logit(1 - 1e-6) overshoots to the far bound)
    margin = START_MARGIN * (UPPER - LOWER)
    x0 = np.where(free, np.clip(x_fixed, LOWER + margin, UPPER - margin), x_fixed)
    u0 = to_free(jnp.asarray(np.clip(x0, LOWER + margin, UPPER - margin)),
                 jnp.asarray(LOWER), jnp.asarray(UPPER))
    base = jnp.asarray(x_fixed)
    _HISTORY.clear()
    jacobians: list[int] = []
    shift = jnp.zeros(2)
    if isinstance(model, ShiftedLife):
        shift = jnp.asarray(model.shift, dtype=float)
        model = model.model
    life = _differentiable(model, on_jacobian=lambda _: jacobians.append(1))
    args = (life, residual, base, jnp.asarray(free), shift)

    # Levenberg-Marquardt, not plain Gauss-Newton: through the sigmoid an
    # undamped step can land where the sigmoid is flat and never come back
    # (seen on the closed-form test model: u -> -2886).
    solver = levenberg_marquardt(rtol, atol)
    t0 = time.perf_counter()
    sol: optx.Solution = optx.least_squares(_design_residual, solver, u0, args=args,
                                            max_steps=max_steps, throw=False)
    u = jax.block_until_ready(sol.value)
    history = list(_HISTORY)
    x = np.where(free, np.asarray(from_free(u, jnp.asarray(LOWER), jnp.asarray(UPPER))), x_fixed)
    wall = time.perf_counter() - t0
    cycles = life_of(model, x) + np.asarray(shift)  # a fresh run of the model at the answer
    notes = {}
    if sol.result != optx.RESULTS.successful:
        # The step test (rtol/atol on u and on the objective) can wait forever
        # on the model's own noise (~3e-4 relative in the life at cycle_rtol
        # 1e-6; docs/notes/design-solver.md).  What the user asked for is the residual, so
        # an answer whose fresh rerun meets ACCEPT_RESIDUAL is kept, flagged.
        r = float(np.max(np.abs(np.asarray(residual(jnp.asarray(x), jnp.asarray(cycles))))))
        if not (sol.result == optx.RESULTS.nonlinear_max_steps_reached
                and r <= ACCEPT_RESIDUAL):
            raise SolverError(f"{problem}: the optimiser stopped without converging "
                              f"({sol.result}) after {int(sol.stats['num_steps'])} steps at "
                              f"x = {np.round(x * 1e3, 4).tolist()} mm (residual {r:.2e})")
        notes["stopped"] = (f"step limit ({max_steps}) reached with the residual at {r:.2e} "
                            f"<= {ACCEPT_RESIDUAL:g} on a fresh rerun: accepted")
    # model runs: the primal ones, 2 x (number of variables) per central-difference
    # Jacobian, the final check
    runs = len(history) + 2 * int(free.sum()) * len(jacobians) + 1
    notes["jacobian_method"] = jacobian_method(model)
    return DesignResult(problem, x, cycles, int(sol.stats["num_steps"]), runs, wall, history,
                        notes)


class AtTarget(eqx.Module):
    """Residual cyc_j / T - 1 of the joints at the target life T [cycles];
    ``active`` (2,) masks joints whose life is not held at T (0: excluded)."""

    target: jnp.ndarray
    active: jnp.ndarray = eqx.field(default_factory=lambda: jnp.ones(2))

    def __call__(self, x, c):
        return self.active * (c / self.target - 1.0)


def life_gap(x, c):
    """The scale-free equal-life residual (cyc1 - cyc2) / mean(cyc1, cyc2)."""
    return jnp.atleast_1d((c[0] - c[1]) / (0.5 * (c[0] + c[1])))


def equal_life(model: TwoJointLife, x0, *, rtol=1e-4, atol=1e-4,
               max_steps=30) -> DesignResult:
    """min (cyc1 - cyc2)^2 over (d1, d2, h1, h2) in the Table 8-3 box from ``x0``
    (the thesis's problem), as the residual `life_gap`."""
    return _solve(model, "equal life", life_gap, x0, [True] * 4, rtol=rtol, atol=atol,
                  max_steps=max_steps)


def longest_common_life(model: TwoJointLife, *, rtol=1e-4, atol=1e-4,
                        max_steps=30) -> DesignResult:
    """Equal life with the longest common life (see the module notes)."""
    corner = LONGEST_LIFE_CORNER.copy()
    c = life_of(model, corner)
    weak = int(np.argmin(c))
    strong = 1 - weak
    x = corner.copy()
    free = [False] * 4
    free[strong + 2] = True  # the stronger joint's depth
    res = _solve(model, "longest common life", life_gap, x, free, rtol=rtol, atol=atol,
                 max_steps=max_steps)
    res.notes.update({"weaker_joint": weak + 1, "corner_cycles": c.tolist(),
                      "kkt": kkt_check(model, res.x, "longest common life", res.cycles)})
    return res


LONGEST_LIFE_CORNER = np.array([LOWER[0], LOWER[1], UPPER[2], UPPER[3]])  # d at 20, h at 50 mm


def least_material(model: TwoJointLife, target_cycles: float, *, rtol=1e-4, atol=1e-4,
                   max_steps=30, corner_cycles=None) -> DesignResult:
    """Both joints at ``target_cycles`` with the least bushing volume (module notes).

    The diameters sit at 20 mm, so the target must be reachable there with h
    <= 50 mm: checked first at `LONGEST_LIFE_CORNER` (``corner_cycles`` if
    the caller has them); `InputError` naming the joint if not.  (The
    thesis's 119,435 cycles is out of reach in our model: joint 1 lives
    106,358 cycles at that corner, steps = 10; the optimiser otherwise runs
    onto the h1 = 50 mm bound and stops after its 30 steps.)"""
    t = float(target_cycles)
    if not t > 0:
        raise InputError(f"least_material: target life must be > 0 cycles, got {t}")
    c = life_of(model, LONGEST_LIFE_CORNER) if corner_cycles is None else np.asarray(corner_cycles)
    short = [j for j in (0, 1) if c[j] < t]
    if short:
        j = short[0]
        raise InputError(f"least material: a life of {t:,.0f} cycles is out of reach with "
                         f"d = 20 mm: at h = 50 mm (the Table 8-3 bound) joint {j + 1} reaches "
                         f"the wear limit after {c[j]:,.0f} cycles")
    # a joint that outlives the target with the shallowest bushing stays there
    # (h at its lower bound: the constraint cyc_j >= T is not active)
    shallow = np.array([LOWER[0], LOWER[1], LOWER[2], LOWER[3]])
    c_low = life_of(model, shallow)
    active = c_low < t
    x = np.where(np.r_[False, False, active], 0.5 * (LOWER + UPPER), shallow)
    if not active.any():
        return DesignResult("least material", shallow, c_low, 0, 1, 0.0, [],
                            {"target_cycles": t, "jacobian_method": jacobian_method(model),
                             "note": "both joints outlive the target at h = 10 mm"})
    res = _solve(model, "least material", AtTarget(jnp.asarray(t), jnp.asarray(active, float)),
                 x, np.r_[False, False, active], rtol=rtol, atol=atol, max_steps=max_steps)
    res.notes["target_cycles"] = t
    if active.all():
        res.notes["kkt"] = kkt_check(model, res.x, "least material", res.cycles)
    else:
        res.notes["at_lower_bound"] = [f"h{j + 1}" for j in (0, 1) if not active[j]]
    return res


def kkt_check(model: TwoJointLife, x, problem: str, cycles) -> dict:
    """The first-order optimality conditions at ``x``, from the model's Jacobian.

    ``longest common life``: the weaker joint's life must not rise along any
    feasible direction of its own variables (d at its lower bound: dcyc/dd <= 0;
    h at its upper bound: dcyc/dh >= 0).  ``least material``: with the
    multipliers of cyc_j = T from the free depths, dL/dd_j >= 0 at d_j's lower
    bound (no descent by moving d up).  ``cycles``: the life at ``x``.
    Returns the numbers and a verdict.
    """
    if problem not in ("longest common life", "least material"):
        raise InputError(f"kkt_check: unknown problem {problem!r}")
    jac = np.asarray(jacobian(model, x))
    out = {"jacobian_cycles_per_mm": (jac * 1e-3).tolist()}
    if problem == "longest common life":
        weak = int(np.argmin(cycles))
        g = jac[weak]
        ok = bool(g[weak] <= 0 and g[weak + 2] >= 0)
        out.update({"weaker_joint": weak + 1, "dlife_dd_per_mm": g[weak] * 1e-3,
                    "dlife_dh_per_mm": g[weak + 2] * 1e-3, "optimal": ok})
    else:
        gv = np.asarray(jax.grad(bushing_volume)(jnp.asarray(x)))
        # stationarity in h: gv_h + sum_j lam_j jac[j, h] = 0 (2 x 2 system)
        lam = np.linalg.solve(jac[:, 2:].T, -gv[2:])
        dl_dd = gv[:2] + jac[:, :2].T @ lam
        out.update({"multipliers": lam.tolist(), "dL_dd_m2": dl_dd.tolist(),
                    "optimal": bool(np.all(dl_dd >= 0))})
    return out


def jacobian(model: TwoJointLife, x) -> np.ndarray:
    """d(cyc1, cyc2)/d(d1, d2, h1, h2) [cycles/m] at ``x`` (`jacobian_method`)."""
    return np.asarray(_jacobian(model, jnp.asarray(x, dtype=float)))


def _jacobian(model: TwoJointLife, x):
    if isinstance(model, ShiftedLife):
        model = model.model
    if jacobian_method(model) == "autodiff":
        return compiled(model).value_and_jacobian(x)[1]
    return _fd_jacobian(model, x)


@eqx.filter_jit
def _fd_jacobian(model, x):
    return jax.jacfwd(finite_difference_jacobian(model))(x)


class ShiftedLife(eqx.Module):
    """``model``'s lives plus a constant ``shift`` [cycles] (space mapping)."""

    model: TwoJointLife
    shift: jnp.ndarray

    @property
    def exact_gradients(self) -> bool:
        return getattr(self.model, "exact_gradients", False)

    def __call__(self, x):
        return self.model(x) + self.shift

    def life(self, x) -> np.ndarray:
        return life_of(self.model, x) + np.asarray(self.shift)


def space_mapped(solve, fast, reference, residual, *, tol: float = ACCEPT_RESIDUAL,
                 max_reference_runs: int = 6, log=None) -> DesignResult:
    """Solve a design problem on ``fast`` and correct it on ``reference``.

    ``solve(model) -> DesignResult`` solves the problem on a life model;
    ``residual(x, cycles)`` is the problem's residual (the answer is accepted
    when max |residual| <= ``tol`` with the reference model's lives).  Each
    round runs the reference model once at the current answer, shifts the fast
    model by the difference and solves again.  Returns the last answer with
    the reference lives in ``cycles`` and, in ``notes``: ``reference_runs``,
    ``fast_cycles``, ``shift``, ``rounds`` (per round x, reference and fast
    lives, residual); `SolverError` if the bar is not met within
    ``max_reference_runs``.
    """
    t0 = time.perf_counter()
    shift = np.zeros(2)
    rounds, evaluations, iterations = [], 0, 0
    for k in range(max_reference_runs):
        res = solve(fast if k == 0 else ShiftedLife(fast, jnp.asarray(shift)))
        evaluations += res.model_evaluations
        iterations += res.iterations
        ref = life_of(reference, res.x)
        own = life_of(fast, res.x)
        r = float(np.max(np.abs(np.asarray(residual(jnp.asarray(res.x), jnp.asarray(ref))))))
        rounds.append({"x_mm": (res.x * 1e3).tolist(), "reference_cycles": ref.tolist(),
                       "fast_cycles": own.tolist(), "residual": r})
        if log is not None:
            log(f"  round {k + 1}: x = {np.round(res.x * 1e3, 3).tolist()} mm, reference "
                f"lives {np.round(ref).tolist()}, residual {r:.2e}")
        if r <= tol:
            notes = {**res.notes, "reference_runs": k + 1, "fast_cycles": own.tolist(),
                     "shift": (ref - own).tolist(), "rounds": rounds}
            return DesignResult(res.problem, res.x, ref, iterations, evaluations,
                                time.perf_counter() - t0, res.history, notes)
        shift = ref - own  # the correction at the current design
    raise SolverError(f"{res.problem}: the reference model's residual is {r:.2e} > {tol:g} "
                      f"after {max_reference_runs} reference runs (space mapping did not "
                      f"converge); last design {np.round(res.x * 1e3, 4).tolist()} mm")
