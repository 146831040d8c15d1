"""Weighted least squares through the full simulator.

`Problem` turns a `Dataset` into a residual vector r = (model - data) / sigma
(each point weighted by its series' stated 1-sigma noise) as a pure JAX
function of the unknowns z:

* fitted rig parameters (``Dataset.fit_names``), each as v = v0 exp(tau x)
  (positive by construction; tau = std / v0 from the dataset, else 0.1);
* one effect strength s = scale x (linear: zero strength is the base model
  and the score test of `identify` is taken there).  Which effect is selected
  by a one-hot vector passed as data, so the base fit and every effect's
  refit share one compiled solver.

`fit` solves min ||r_fit(z)||^2 by Levenberg-Marquardt (`Fitter`; Jacobian by
forward-mode autodiff), then reports the parameters with their
1-sigma uncertainties from the Gauss-Newton covariance (J^T J)^-1 of the fit
points, and the residuals of the held-out points.  A solver failure raises
`SolverError`; a model failure (integrator) inside the fit is reported as
such, never as NaN parameters.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import InputError, SolverError
from .dataset import Dataset
from .effects import EFFECTS, NAMES
from .model import MAX_EXTRAPOLATION, Observation, RigHistory, rig_defaults

DEFAULT_LOG_SCALE = 0.1  # tau of a fitted parameter without a stated std


@dataclass(frozen=True)
class ModelSettings:
    """Resolution of the forward model (see `model.RigHistory`)."""

    dynamic_cycles: int | None = None   # default: the fewest with A <= MAX_EXTRAPOLATION
    n_theta: int = 90
    force_samples: int = 91
    cycle_rtol: float = 1e-6

    def model(self, cycles: float) -> RigHistory:
        d = self.dynamic_cycles or max(1, math.ceil(cycles / MAX_EXTRAPOLATION))
        return RigHistory(cycles=float(cycles), dynamic_cycles=d, n_theta=self.n_theta,
                          force_samples=self.force_samples, cycle_rtol=self.cycle_rtol,
                          cycle_atol=self.cycle_rtol)


@dataclass(frozen=True, eq=False)
class Problem:
    """The dataset as residuals of the model (see module notes).  Plain data
    closed over by the jitted functions (hashable by identity)."""

    model: RigHistory
    observations: tuple
    y: np.ndarray
    sigma: np.ndarray
    holdout: np.ndarray
    series_of_point: np.ndarray
    fit_names: tuple
    base0: dict
    tau: np.ndarray

    @classmethod
    def from_dataset(cls, data: Dataset, settings: ModelSettings = ModelSettings()):
        if data.preset != "rig":
            raise InputError(f"{data.path}: preset {data.preset!r}: only 'rig' is modelled")
        model = settings.model(data.max_cycles)
        obs, ys, sig, hold, which = [], [], [], [], []
        for k, s in enumerate(data.series):
            obs.append(Observation(s.kind, np.asarray(s.x), model.extrapolation,
                                   model.dynamic_cycles, cycles=float(s.cycles or 0.0),
                                   basis=s.basis or "mass"))
            ys.append(s.y)
            sig.append(np.full(s.y.shape, s.sigma))
            hold.append(s.holdout)
            which.append(np.full(s.y.shape, k))
        base0 = rig_defaults()
        tau = []
        for name, p in data.parameters.items():
            base0[name] = p.value
        for name in data.fit_names:
            p = data.parameters[name]
            tau.append(p.std / p.value if p.std else DEFAULT_LOG_SCALE)
        return cls(model, tuple(obs), np.concatenate(ys), np.concatenate(sig),
                   np.concatenate(hold), np.concatenate(which), tuple(data.fit_names),
                   {k: jnp.asarray(v, dtype=float) for k, v in base0.items()},
                   np.asarray(tau, dtype=float))

    @property
    def n_base(self) -> int:
        return len(self.fit_names)

    def base(self, x) -> dict:
        out = dict(self.base0)
        for i, name in enumerate(self.fit_names):
            out[name] = self.base0[name] * jnp.exp(self.tau[i] * x[i])
        return out

    def predict(self, x, strengths):
        h = self.model(self.base(x), strengths)
        pred = jnp.concatenate([o(h) for o in self.observations])
        # an integrator failure poisons every prediction: reported, not fitted
        return jnp.where(h.ok, pred, jnp.nan)

    def residual(self, x, strengths):
        return (self.predict(x, strengths) - self.y) / self.sigma


SCALES = np.array([e.scale for e in EFFECTS])


@dataclass
class FitResult:
    """One fit: ``effect`` (None: the base model), parameter values (SI) and
    1-sigma uncertainties, the strength and its uncertainty, chi-square of the
    fit points and of the held-out points, normalised residuals of all points."""

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
    notes: dict = field(default_factory=dict)

    @property
    def dof(self) -> int:
        return self.n_fit - len(self.params) - (self.effect is not None)

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

    Why not optimistix here: its trust-region LM took 39+ steps on this
    problem (the model's adaptive steps make chi2 slightly rough at the 1e-3
    scale, and its ratio test keeps shrinking the region), about 4 minutes per
    fit; the plain Marquardt loop below accepts a Gauss-Newton-like step in 3-6
    iterations.  Each iteration is one forward-mode pass giving r and J
    together (`jax.jacfwd` with ``has_aux``), compiled once for the base fit and
    every refit (the effect is selected by a one-hot vector passed as data).
    Unknowns z are in units of each parameter's stated spread (tau) or of an
    effect's scale, so the step tolerance ``xtol`` reads "1 % of a spread".
    """

    def __init__(self, problem: Problem, *, xtol=1e-2, ftol=1e-4, max_steps=20):
        self.problem = problem
        self.xtol, self.ftol, self.max_steps = xtol, ftol, max_steps
        self._jacobian = jax.jit(jax.jacfwd(lambda x, s: problem.residual(x, s), argnums=(0, 1)))

        def both(z, onehot):
            """(fit-point residuals: differentiated, all residuals: carried)."""
            p = self.problem
            r = p.residual(z[:-1], onehot * SCALES * z[-1])
            return r[~p.holdout], r

        self._value_and_jac = jax.jit(jax.jacfwd(both, has_aux=True))
        self.evaluations = 0

    def _evaluate(self, z, onehot):
        """At z = (x_base, s / scale), ``onehot`` selecting the effect (zeros:
        the base model): residuals of all points and the fit points' Jacobian."""
        jac, r_all = self._value_and_jac(jnp.asarray(z), onehot)
        self.evaluations += 1
        return np.asarray(r_all), np.asarray(jac)

    def _levenberg_marquardt(self, z, onehot, free, what):
        """(z, steps, fit-point Jacobian, all residuals) at the accepted minimum."""
        fit_rows = ~self.problem.holdout
        r_all, jac = self._evaluate(z, onehot)
        r = r_all[fit_rows]
        if not np.all(np.isfinite(r)):
            raise SolverError(f"calibration of the {what}: the model failed at the start "
                              "(integrator failure: non-finite predictions)")
        chi2, lam, steps = float(r @ r), 1e-3, 0
        for steps in range(1, self.max_steps + 1):
            j = jac[:, free]
            a, g = j.T @ j, j.T @ r
            d = np.maximum(np.diag(a), 1e-12 * max(np.max(np.diag(a)), 1e-300))
            while True:
                dz = np.zeros_like(z)
                dz[free] = np.linalg.solve(a + lam * np.diag(d), -g)
                r_all_new, jac_new = self._evaluate(z + dz, onehot)
                r_new = r_all_new[fit_rows]
                chi2_new = float(r_new @ r_new) if np.all(np.isfinite(r_new)) else math.inf
                if chi2_new <= chi2:
                    break
                lam *= 4.0
                if np.max(np.abs(dz)) < self.xtol:
                    # even a step of < xtol raises chi2: a minimum, down to the
                    # model's adaptive-step noise
                    return z, steps, jac, r_all
            drop = chi2 - chi2_new
            z, r, r_all, jac, chi2 = z + dz, r_new, r_all_new, jac_new, chi2_new
            lam = max(lam / 3.0, 1e-7)
            if np.max(np.abs(dz)) < self.xtol or drop < self.ftol * chi2:
                return z, steps, jac, r_all
        raise SolverError(f"calibration of the {what}: Levenberg-Marquardt did not converge in "
                          f"{self.max_steps} steps (chi2 {chi2:.6g})")

    def jacobian(self, x, strengths) -> tuple[np.ndarray, np.ndarray]:
        """(dr/dx_base, dr/dstrengths) of all points, forward mode."""
        jx, js = self._jacobian(jnp.asarray(x), jnp.asarray(strengths))
        return np.asarray(jx), np.asarray(js)

    def fit(self, effect: str | None = None, x0=None, s0: float = 0.0) -> FitResult:
        p = self.problem
        nb = p.n_base
        onehot = np.zeros(len(NAMES))
        if effect is not None:
            onehot[NAMES.index(effect)] = 1.0
        x0 = np.zeros(nb) if x0 is None else np.asarray(x0, dtype=float)
        scale = SCALES[NAMES.index(effect)] if effect is not None else 1.0
        z0 = np.concatenate([x0, [s0 / scale]])
        free = np.ones(nb + 1, bool)
        free[nb] = effect is not None
        what = "base model" if effect is None else f"base model + {effect}"
        t0 = time.perf_counter()
        z, steps, jz, r = self._levenberg_marquardt(z0, jnp.asarray(onehot), free, what)
        wall = time.perf_counter() - t0
        x, s = z[:nb], z[nb] * scale if effect is not None else 0.0
        strengths = onehot * s
        if not np.all(np.isfinite(r)):  # a held-out point the model could not reach
            raise SolverError(f"calibration of the {what}: the model failed at the solution "
                              "(integrator failure: non-finite predictions)")
        fit_rows = ~p.holdout
        # Gauss-Newton covariance of z from the last Jacobian (fit points)
        cov = np.linalg.pinv(jz[:, free].T @ jz[:, free])
        std_z = np.zeros(nb + 1)
        std_z[free] = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        # the base fit also keeps the Jacobian w.r.t. every strength: the score tests
        jx, js = self.jacobian(x, strengths) if effect is None else (None, None)
        base = p.base(jnp.asarray(x))
        params = {n: float(base[n]) for n in p.fit_names}
        params_std = {n: float(params[n] * p.tau[i] * std_z[i])
                      for i, n in enumerate(p.fit_names)}
        pred = r * p.sigma + p.y
        return FitResult(
            effect=effect, params=params, params_std=params_std, strength=float(s),
            strength_std=float(std_z[nb] * scale) if effect is not None else 0.0,
            chi2_fit=float(np.sum(r[fit_rows] ** 2)), n_fit=int(fit_rows.sum()),
            chi2_holdout=float(np.sum(r[p.holdout] ** 2)), n_holdout=int(p.holdout.sum()),
            residual=r, prediction=pred, iterations=steps, wall_time_s=wall,
            notes={"x": x.tolist(), "jacobian_base": jx, "jacobian_effects": js})
