"""Weighted least squares through the forward model.

`Problem` turns a `Dataset` into a residual vector r = (model - data) / sigma
(each point weighted by its series' stated 1-sigma noise) as a pure JAX
function of the unknowns z:

* fitted rig parameters (``Dataset.fit_names``), each as v = v0 exp(tau x)
  (positive by construction; tau = std / v0 from the dataset, else 0.1);
* one effect's strength s = scale x (linear: zero strength is the base model
  and the score test of `identify` is taken there) and, for an effect with a
  shape, its log-shape in units of the prior spread, ln(shape / default) =
  log_std x, with the prior as one more residual row (x ~ N(0, 1)).  Which
  effect is selected by a one-hot vector passed as data, so the base fit and
  every effect's refit share one compiled solver.

The forward model is a strategy (`ModelSettings.model`): the quasi-static
model (`quasi_static.QuasiStaticRigHistory`, default: milliseconds per step,
exact derivatives) or the dynamic model (`model.RigHistory`).

`fit` solves min ||r_fit(z)||^2 by Levenberg-Marquardt (`Fitter`; Jacobian by
forward-mode autodiff), then reports the parameters with their 1-sigma
uncertainties from the Gauss-Newton covariance (J^T J)^-1 of the fit points,
and the residuals of the held-out points.  A solver failure raises
`SolverError`; a model failure (integrator) inside the fit is reported as
such, never as NaN parameters.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import InputError, SolverError
from .dataset import Dataset
from .effects import EFFECTS, NAMES, SHAPED, EffectValues
from .model import BASE_NAMES, MAX_EXTRAPOLATION, Observation, RigHistory, rig_defaults
from .quasi_static import DEFAULT_STEPS, QuasiStaticRigHistory

DEFAULT_LOG_SCALE = 0.1  # tau of a fitted parameter without a stated std
# A shape is kept within this many prior spreads of its default (a factor
# 1e4 either way for a decade prior): beyond, an effect has no shape left to
# give (a film formed at once is a change of k)
SHAPE_PRIOR_SIGMAS = 4.0
MODELS = ("quasi-static", "dynamic")


@dataclass(frozen=True)
class ModelSettings:
    """Which forward model, and its resolution (`quasi_static.QuasiStaticRigHistory`,
    `model.RigHistory`)."""

    model: str = "quasi-static"
    dynamic_cycles: int | None = None   # default: the fewest with A <= MAX_EXTRAPOLATION
    n_theta: int = 90
    force_samples: int = 91
    cycle_rtol: float = 1e-6
    steps: int = DEFAULT_STEPS

    def __post_init__(self):
        if self.model not in MODELS:
            raise InputError(f"calibration model {self.model!r}: allowed {', '.join(MODELS)}")

    def build(self, cycles: float, checkpoints=()):
        if self.model == "dynamic":
            d = self.dynamic_cycles or max(1, math.ceil(cycles / MAX_EXTRAPOLATION))
            return RigHistory(cycles=float(cycles), dynamic_cycles=d, n_theta=self.n_theta,
                              force_samples=self.force_samples, cycle_rtol=self.cycle_rtol,
                              cycle_atol=self.cycle_rtol)
        return QuasiStaticRigHistory(cycles=float(cycles),
                                     checkpoints=tuple(sorted({float(c) for c in checkpoints})),
                                     steps=self.steps, n_theta=self.n_theta)

    def with_model(self, model: str) -> "ModelSettings":
        return dataclasses.replace(self, model=model)


def _checkpoints(data: Dataset) -> list[float]:
    """Cycle counts at which a profile, volume or depth is measured."""
    out: list[float] = []
    for s in data.series:
        if s.kind != "force":
            out.extend(float(c) for c in np.unique(s.cycle_counts))
    return out


@dataclass(frozen=True, eq=False)
class Problem:
    """The dataset as residuals of the model (see module notes).  Plain data
    closed over by the jitted functions (hashable by identity).  ``suspects``:
    parameters not fitted that `identify` may score (log-scale columns)."""

    model: RigHistory | QuasiStaticRigHistory
    observations: tuple
    y: np.ndarray
    sigma: np.ndarray
    holdout: np.ndarray
    series_of_point: np.ndarray
    fit_names: tuple
    base0: dict
    tau: np.ndarray
    suspects: tuple = ()

    names: tuple = BASE_NAMES

    @classmethod
    def from_dataset(cls, data: Dataset, settings: ModelSettings = ModelSettings()):
        if data.mechanism is not None:
            return cls._from_mechanism_file(data, settings)
        if data.preset != "rig":
            raise InputError(f"{data.path}: preset {data.preset!r}: only 'rig' is modelled")
        model = settings.build(data.max_cycles, _checkpoints(data))
        return cls._assemble(data, model, rig_defaults(), BASE_NAMES)

    @classmethod
    def _from_mechanism_file(cls, data: Dataset, settings: ModelSettings):
        from .mechanism_file import file_model

        if settings.model != "quasi-static":
            raise InputError(f"{data.path}: a mechanism-file dataset is calibrated on the "
                             "quasi-static model; allowed: --model quasi-static")
        names = tuple(data.parameters)
        assert data.mechanism is not None  # this route is taken for a mechanism file only
        model = file_model(data.mechanism, names, data.joint, cycles=float(data.max_cycles),
                           checkpoints=tuple(sorted(set(_checkpoints(data)))),
                           steps=settings.steps)
        return cls._assemble(data, model, dict(model.file_parameters.value0), names)

    @classmethod
    def _assemble(cls, data: Dataset, model, defaults: dict, names: tuple):
        obs, ys, sig, hold, which = [], [], [], [], []
        for k, s in enumerate(data.series):
            obs.append(Observation(s.kind, np.asarray(s.x), cycles=float(s.cycles or 0.0),
                                   basis=s.basis or "mass"))
            ys.append(s.y)
            sig.append(np.full(s.y.shape, s.sigma))
            hold.append(s.holdout)
            which.append(np.full(s.y.shape, k))
        base0 = dict(defaults)
        tau = []
        for name, p in data.parameters.items():
            if p.value is not None:
                base0[name] = p.value
        for name in data.fit_names:
            p = data.parameters[name]
            tau.append(abs(p.std / base0[name]) if p.std else DEFAULT_LOG_SCALE)
        suspects = tuple(n for n in names if n not in data.fit_names
                         and (n not in data.parameters or data.parameters[n].suspect))
        return cls(model, tuple(obs), np.concatenate(ys), np.concatenate(sig),
                   np.concatenate(hold), np.concatenate(which), tuple(data.fit_names),
                   {k: jnp.asarray(v, dtype=float) for k, v in base0.items()},
                   np.asarray(tau, dtype=float), suspects, names)

    def with_model(self, model) -> "Problem":
        return dataclasses.replace(self, model=model)

    @property
    def n_base(self) -> int:
        return len(self.fit_names)

    def base(self, x, log_multipliers=None) -> dict:
        """Rig parameters at fitted unknowns ``x``; ``log_multipliers``: ln of a
        factor on each of `BASE_NAMES` (the suspects' score columns)."""
        out = dict(self.base0)
        for i, name in enumerate(self.fit_names):
            out[name] = self.base0[name] * jnp.exp(self.tau[i] * x[i])
        if log_multipliers is not None:
            out = {n: out[n] * jnp.exp(log_multipliers[i]) for i, n in enumerate(self.names)}
        return out

    def predict(self, x, effects: EffectValues, log_multipliers=None):
        h = self.model(self.base(x, log_multipliers), effects)
        pred = jnp.concatenate([o(h) for o in self.observations])
        # a model failure poisons every prediction: reported, not fitted
        return jnp.where(h.ok, pred, jnp.nan)

    def residual(self, x, effects: EffectValues, log_multipliers=None):
        return (self.predict(x, effects, log_multipliers) - self.y) / self.sigma


SCALES = np.array([e.scale for e in EFFECTS])
LOG_STD = np.array([e.shape.log_std if e.shape else 0.0 for e in EFFECTS])
HAS_SHAPE = np.array(SHAPED, dtype=float)


@dataclass
class FitResult:
    """One fit: ``effect`` (None: the base model), parameter values (SI) and
    1-sigma uncertainties, the strength and its uncertainty, the effect's shape
    (SI; None without one) and its 1-sigma interval, chi-square of the fit
    points and of the held-out points, normalised residuals of all points."""

    effect: str | None
    params: dict
    params_std: dict
    strength: float
    strength_std: float
    chi2_fit: float
    n_fit: int
    chi2_holdout: float
    n_holdout: int
    residual: np.ndarray
    prediction: np.ndarray
    iterations: int
    wall_time_s: float
    shape: float | None = None
    shape_interval: tuple | None = None
    notes: dict = field(default_factory=dict)

    def effect_values(self) -> EffectValues:
        """The fitted effect as `EffectValues` (zeros for the base model)."""
        if self.effect is None:
            return EffectValues.zero()
        values = {self.effect: self.strength}
        shape = EFFECTS[NAMES.index(self.effect)].shape
        if self.shape is not None and shape is not None:
            values[shape.name] = self.shape
        return EffectValues.of(**values)

    @property
    def n_effect(self) -> int:
        """Fitted numbers of the effect: 0 (base), 1 (strength), 2 (+ shape)."""
        return 0 if self.effect is None else 1 + (self.shape is not None)

    @property
    def dof(self) -> int:
        return self.n_fit - len(self.params) - self.n_effect

    @property
    def rmse_holdout(self) -> float:
        """RMS of the held-out residuals, in units of the stated noise."""
        return math.sqrt(self.chi2_holdout / self.n_holdout) if self.n_holdout else math.nan

    @property
    def rmse_fit(self) -> float:
        return math.sqrt(self.chi2_fit / self.n_fit)


class Fitter:
    """Compiled pieces shared by all fits of one problem, and the
    Levenberg-Marquardt iteration (Marquardt's diagonal scaling).

    Why not optimistix here: on the dynamic model its trust-region LM took 39+
    steps (the model's adaptive steps make chi2 slightly rough at the 1e-3
    scale, and its ratio test keeps shrinking the region); the plain Marquardt
    loop below accepts a Gauss-Newton-like step in 3-6 iterations on either
    model.  Each iteration is one forward-mode pass giving r and J together
    (`jax.jacfwd` with ``has_aux``), compiled once for the base fit and every
    refit (the effect is selected by a one-hot vector passed as data).
    Unknowns z are in units of each parameter's stated spread (tau), of an
    effect's scale and of a shape's prior spread, so the step tolerance
    ``xtol`` reads "1 % of a spread".
    """

    def __init__(self, problem: Problem, *, xtol=1e-2, ftol=1e-4, max_steps=30):
        self.problem = problem
        self.xtol, self.ftol, self.max_steps = xtol, ftol, max_steps
        nb, ne = problem.n_base, len(NAMES)
        # every unknown the loop differentiates by, packed: v = (fitted x,
        # strengths, ln shapes, ln multipliers of every rig parameter)
        nu = len(problem.names)
        self._slices = (slice(0, nb), slice(nb, nb + ne), slice(nb + ne, nb + 2 * ne),
                        slice(nb + 2 * ne, nb + 2 * ne + nu))
        self.n_packed = nb + 2 * ne + nu
        # directional derivatives per call: the fit's own unknowns (x, strength,
        # shape); the score tests' columns come in batches of this size, so
        # one compiled program serves the fits, the score tests and the
        # suspects (compiling one per use cost ~4x the whole loop's run time)
        self.width = nb + 2
        sx, ss, sg, su = self._slices

        def residual(v):
            return problem.residual(v[sx], EffectValues(v[ss], v[sg]), v[su])

        def columns(v, tangents):
            """(r, dr/dv . t for each row t of ``tangents``) at packed ``v``."""
            r, jac = jax.vmap(lambda t: jax.jvp(residual, (v,), (t,)), out_axes=(None, 1))(
                tangents)
            return r, jac

        self._columns = jax.jit(columns)
        self.evaluations = 0

    def _pack(self, x, strength=None, log_shape=None, u=None) -> np.ndarray:
        v = np.zeros(self.n_packed)
        sx, ss, sg, su = self._slices
        v[sx] = x
        for sl, part in ((ss, strength), (sg, log_shape), (su, u)):
            if part is not None:
                v[sl] = part
        return v

    def _directional(self, v, tangents) -> tuple[np.ndarray, np.ndarray]:
        """(r, J T^T) for any number of tangent rows, in batches of ``width``."""
        tangents = np.atleast_2d(tangents)
        r, cols = None, []
        for i in range(0, tangents.shape[0], self.width):
            batch = tangents[i:i + self.width]
            pad = np.zeros((self.width - batch.shape[0], self.n_packed))
            r, jac = self._columns(jnp.asarray(v), jnp.asarray(np.vstack([batch, pad])))
            self.evaluations += 1
            cols.append(np.asarray(jac)[:, :batch.shape[0]])
        return np.asarray(r), np.concatenate(cols, axis=1)

    def _unit(self, part: int, index) -> np.ndarray:
        """Tangent rows: unit vectors of ``index`` within packed part ``part``."""
        start = self._slices[part].start
        t = np.zeros((len(index), self.n_packed))
        t[np.arange(len(index)), start + np.asarray(index, dtype=int)] = 1.0
        return t

    def _evaluate(self, z, onehot):
        """At z = (x_base, s / scale, ln-shape / log_std), ``onehot`` selecting
        the effect (zeros: the base model): residuals of all points and the
        Jacobian of the fit rows (fit points and the prior row)."""
        nb = self.problem.n_base
        onehot = np.asarray(onehot)
        v = self._pack(z[:nb], onehot * SCALES * z[nb], onehot * LOG_STD * z[nb + 1])
        t = np.zeros((nb + 2, self.n_packed))
        t[:nb] = self._unit(0, range(nb))
        t[nb, self._slices[1]] = onehot * SCALES
        t[nb + 1, self._slices[2]] = onehot * LOG_STD
        r_all, jac = self._directional(v, t)
        prior = np.zeros((1, nb + 2))
        prior[0, nb + 1] = float(onehot @ HAS_SHAPE)
        return r_all, np.vstack([jac[~self.problem.holdout], prior])

    def _levenberg_marquardt(self, z, evaluate, rows, free, what, bounds=None):
        """(z, steps, fit-row Jacobian, all residuals) at the accepted minimum.
        ``evaluate(z) -> (all residuals, fit-row Jacobian)``; ``rows(r_all, z)``:
        the objective's rows; ``bounds``: (lower, upper) arrays of z (a step
        is cut back to the box)."""
        lower, upper = (np.full(z.shape, -np.inf), np.full(z.shape, np.inf)) \
            if bounds is None else bounds
        r_all, jac = evaluate(z)
        r = rows(r_all, z)
        if not np.all(np.isfinite(r)):
            raise SolverError(f"calibration of the {what}: the model failed at the start "
                              "(non-finite predictions)")
        chi2, lam, steps = float(r @ r), 1e-3, 0
        for steps in range(1, self.max_steps + 1):
            j = jac[:, free]
            a, g = j.T @ j, j.T @ r
            d = np.maximum(np.diag(a), 1e-12 * max(np.max(np.diag(a)), 1e-300))
            while True:
                dz = np.zeros_like(z)
                dz[free] = np.linalg.solve(a + lam * np.diag(d), -g)
                dz = np.clip(z + dz, lower, upper) - z
                r_all_new, jac_new = evaluate(z + dz)
                r_new = rows(r_all_new, z + dz)
                chi2_new = float(r_new @ r_new) if np.all(np.isfinite(r_new)) else math.inf
                if chi2_new <= chi2:
                    break
                lam *= 4.0
                if np.max(np.abs(dz)) < self.xtol:
                    # even a step of < xtol raises chi2: a minimum, down to the
                    # model's rounding (or the dynamic model's adaptive-step noise)
                    return z, steps, jac, r_all
            drop = chi2 - chi2_new
            z, r, r_all, jac, chi2 = z + dz, r_new, r_all_new, jac_new, chi2_new
            lam = max(lam / 3.0, 1e-7)
            if np.max(np.abs(dz)) < self.xtol or drop < self.ftol * chi2:
                return z, steps, jac, r_all
        raise SolverError(f"calibration of the {what}: Levenberg-Marquardt did not converge in "
                          f"{self.max_steps} steps (chi2 {chi2:.6g})")

    def effect_jacobian(self, x, log_shape) -> np.ndarray:
        """dr/ds of every effect (columns, `NAMES` order) at zero strength and
        the log-shapes ``log_shape`` (ln of shape / default)."""
        v = self._pack(x, log_shape=log_shape)
        return self._directional(v, self._unit(1, range(len(NAMES))))[1]

    def parameter_jacobian(self, x, u=None, names=None):
        """(dr/dx of the fitted unknowns, dr/d ln p of the rig parameters
        ``names``, r) at ln multipliers ``u`` (default none) of every rig
        parameter."""
        nb = self.problem.n_base
        names = self.problem.names if names is None else names
        v = self._pack(x, u=u)
        t = np.vstack([self._unit(0, range(nb)),
                       self._unit(3, [self.problem.names.index(n) for n in names])])
        r, jac = self._directional(v, t)
        return jac[:, :nb], jac[:, nb:], r

    def fit_suspect(self, name: str, x0, u0: float = 0.0) -> FitResult:
        """The base model refitted with rig parameter ``name`` (not one the
        dataset fits) free as well, on a log scale: its value in ``params``."""
        p = self.problem
        nb, i = p.n_base, p.names.index(name)
        fit_rows = ~p.holdout

        def evaluate(z):
            u = np.zeros(len(p.names))
            u[i] = z[nb]
            jx, ju, r = self.parameter_jacobian(z[:nb], u, names=(name,))
            return r, np.column_stack([jx, ju])[fit_rows]

        z0 = np.concatenate([np.asarray(x0, dtype=float), [u0]])
        t0 = time.perf_counter()
        z, steps, jz, r = self._levenberg_marquardt(
            z0, evaluate, lambda r_all, z: r_all[fit_rows], np.ones(nb + 1, bool),
            f"base model with {name} free")
        cov = np.linalg.pinv(jz.T @ jz)
        std_z = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        base = p.base(jnp.asarray(z[:nb]))
        params = {n: float(base[n]) for n in p.fit_names}
        params_std = {n: float(params[n] * p.tau[k] * std_z[k])
                      for k, n in enumerate(p.fit_names)}
        value = float(p.base0[name]) * math.exp(z[nb])
        params[name], params_std[name] = value, value * float(std_z[nb])
        return FitResult(
            effect=None, params=params, params_std=params_std, strength=0.0, strength_std=0.0,
            chi2_fit=float(np.sum(r[fit_rows] ** 2)), n_fit=int(fit_rows.sum()),
            chi2_holdout=float(np.sum(r[p.holdout] ** 2)), n_holdout=int(p.holdout.sum()),
            residual=r, prediction=r * p.sigma + p.y, iterations=steps,
            wall_time_s=time.perf_counter() - t0, notes={"x": z[:nb].tolist()})

    def fit(self, effect: str | None = None, x0=None, s0: float = 0.0,
            log_shape0: float = 0.0) -> FitResult:
        p = self.problem
        nb = p.n_base
        onehot = np.zeros(len(NAMES))
        k = None if effect is None else NAMES.index(effect)
        if k is not None:
            onehot[k] = 1.0
        shaped = k is not None and SHAPED[k]
        x0 = np.zeros(nb) if x0 is None else np.asarray(x0, dtype=float)
        scale = SCALES[k] if k is not None else 1.0
        log_std = LOG_STD[k] if shaped else 1.0
        z0 = np.concatenate([x0, [s0 / scale, log_shape0 / log_std if shaped else 0.0]])
        free = np.ones(nb + 2, bool)
        free[nb] = k is not None
        free[nb + 1] = shaped
        what = "base model" if effect is None else f"base model + {effect}"
        fit_rows = ~p.holdout

        def rows(r_all, z):
            return np.concatenate([r_all[fit_rows], [z[-1] if shaped else 0.0]])

        t0 = time.perf_counter()
        lower = np.full(nb + 2, -np.inf)
        upper = np.full(nb + 2, np.inf)
        if k is not None:
            lower[nb] = EFFECTS[k].lower / scale
            lower[nb + 1], upper[nb + 1] = -SHAPE_PRIOR_SIGMAS, SHAPE_PRIOR_SIGMAS
        z0 = np.clip(z0, lower, upper)
        z, steps, jz, r = self._levenberg_marquardt(
            z0, lambda z: self._evaluate(z, onehot), rows, free, what, (lower, upper))
        wall = time.perf_counter() - t0
        x = z[:nb]
        if not np.all(np.isfinite(r)):  # a held-out point the model could not reach
            raise SolverError(f"calibration of the {what}: the model failed at the solution "
                              "(non-finite predictions)")
        # Gauss-Newton covariance of z from the last Jacobian (fit rows)
        cov = np.linalg.pinv(jz[:, free].T @ jz[:, free])
        std_z = np.zeros(nb + 2)
        std_z[free] = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        # the strength's spread at the fitted shape (the shape held): a shape
        # trades off against the strength, so this, not the marginal spread,
        # says whether the effect is there at all
        given = free.copy()
        given[nb + 1] = False
        std_given = (math.sqrt(max(np.linalg.pinv(jz[:, given].T @ jz[:, given])[-1, -1], 0.0))
                     * scale if k is not None else 0.0)
        base = p.base(jnp.asarray(x))
        params = {n: float(base[n]) for n in p.fit_names}
        params_std = {n: float(params[n] * p.tau[i] * std_z[i])
                      for i, n in enumerate(p.fit_names)}
        pred = r * p.sigma + p.y
        shape = interval = None
        effect_shape = EFFECTS[k].shape if k is not None else None
        if shaped and effect_shape is not None:
            default = effect_shape.default
            ln = z[nb + 1] * log_std
            shape = float(default * math.exp(ln))
            half = std_z[nb + 1] * log_std
            interval = (float(default * math.exp(ln - half)), float(default * math.exp(ln + half)))
        return FitResult(
            effect=effect, params=params, params_std=params_std,
            strength=float(z[nb] * scale) if k is not None else 0.0,
            strength_std=float(std_z[nb] * scale) if k is not None else 0.0,
            chi2_fit=float(np.sum(r[fit_rows] ** 2)), n_fit=int(fit_rows.sum()),
            chi2_holdout=float(np.sum(r[p.holdout] ** 2)), n_holdout=int(p.holdout.sum()),
            residual=r, prediction=pred, iterations=steps, wall_time_s=wall,
            shape=shape, shape_interval=interval,
            notes={"x": x.tolist(), "jacobian": jz[:-1], "strength_std_given_shape": std_given})
