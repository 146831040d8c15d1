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
from ..wear.status import not_an_answer
from .dataset import Dataset
from .effects import LIBRARY, EffectValues, Library, log_shape
from .model import BASE_NAMES, Observation, RigHistory, rig_defaults
from .quasi_static import DEFAULT_STEPS, QuasiStaticRigHistory

DEFAULT_LOG_SCALE = 0.1  # tau of a fitted parameter without a stated std
# Levenberg-Marquardt steps a fit may take per unknown where that exceeds the
# fitter's ``max_steps`` (a budget that grows with the unknowns, as MINPACK's
# lmder allows 100 (n + 1) evaluations): ten covers the slowest shipped fit,
# the coating campaign's depth discrepancy (66 steps for 7 unknowns)
STEPS_PER_UNKNOWN = 10
# A shape is kept within this many prior spreads of its default (a factor
# 1e4 either way for a decade prior): beyond, an effect has no shape left to
# give (a film formed at once is a change of k)
SHAPE_PRIOR_SIGMAS = 4.0
# The discrepancy's direction along k (`Fitter.k_direction`) is taken out of
# the fit where a Gauss-Newton 1-sigma step along it departs from the
# linearised residuals by more than this in chi2 (the quadratic's own value
# there is 1).  Measured at the shipped campaigns' base fits: 9-55 for the
# bushing angle, 0.2-0.3 for the pressure, under 0.01 for the sliding speed
# and under 1e-3 for the cycle count and the wear depth
VALLEY = 1.0
# Cycle counts at which the model's worn volume is reported beside the
# residuals (`Problem.probe_cycles`): fractions of the campaign, geometric
# from 1/50 (where a run-in shows) to the end
PROBE_FRACTIONS = tuple(float(f) for f in np.geomspace(0.02, 1.0, 12))


# The forward models a calibration fits, as classes (`ModelSettings.model`).
ForwardModel = type[QuasiStaticRigHistory] | type[RigHistory]


@dataclass(frozen=True)
class ModelSettings:
    """Which forward model, the class `quasi_static.QuasiStaticRigHistory` or
    `model.RigHistory` (each builds itself for a campaign: ``for_campaign``),
    and its resolution."""

    model: ForwardModel = QuasiStaticRigHistory
    dynamic_cycles: int | None = None   # default: the fewest with A <= MAX_EXTRAPOLATION
    n_theta: int = 90
    force_samples: int = 91
    cycle_rtol: float = 1e-6
    steps: int = DEFAULT_STEPS
    # the effects and discrepancy variables the calibration chooses among
    library: Library = LIBRARY

    def __post_init__(self):
        if not callable(getattr(self.model, "for_campaign", None)):
            raise InputError(f"calibration model {self.model!r}: allowed QuasiStaticRigHistory, "
                             "RigHistory")

    def build(self, cycles: float, checkpoints=(), window: float | None = None):
        return self.model.for_campaign(cycles, checkpoints, self, window)

    def with_model(self, model: ForwardModel) -> "ModelSettings":
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
    # worn volume (mass basis) reported at these cycle counts beside the
    # residuals (`outputs`): every inspection and `PROBE_FRACTIONS` of the run
    probe_cycles: tuple = ()
    cycles_of_point: np.ndarray | None = None   # the cycle count of each point
    kinds: tuple = ()                           # each series' kind
    library: Library = LIBRARY                  # the candidate effects and variables
    refused: tuple = ()                         # (effect, why) the model cannot take

    @property
    def kind_of_point(self) -> np.ndarray:
        return np.asarray(self.kinds, dtype=object)[self.series_of_point]

    @classmethod
    def from_dataset(cls, data: Dataset, settings: ModelSettings = ModelSettings()):
        if data.mechanism is not None:
            return cls._from_mechanism_file(data, settings)
        if data.preset != "rig":
            raise InputError(f"{data.path}: preset {data.preset!r}: only 'rig' is modelled")
        model = settings.build(data.max_cycles, _checkpoints(data), data.fit_cycles)
        return cls._assemble(data, model, rig_defaults(), BASE_NAMES, settings.library)

    @classmethod
    def _from_mechanism_file(cls, data: Dataset, settings: ModelSettings):
        from .mechanism_file import file_model

        if not settings.model.calibrates_files:
            raise InputError(f"{data.path}: a mechanism-file dataset is calibrated on the "
                             "quasi-static model; allowed: --model quasi-static")
        names = tuple(data.parameters)
        assert data.mechanism is not None  # this route is taken for a mechanism file only
        # an effect that adds forces to the rig (the slider guide's friction)
        # has no place in a user's mechanism: refused with the reason
        refused = tuple((e.name, "it adds forces to the rig's mechanism, which a mechanism "
                         "file replaces") for e in settings.library.effects if e.adds_forces)
        library = settings.library.without({n for n, _ in refused})
        model = file_model(data.mechanism, names, data.joint, cycles=float(data.max_cycles),
                           window=float(data.fit_cycles),
                           checkpoints=tuple(sorted(set(_checkpoints(data)))),
                           steps=settings.steps)
        problem = cls._assemble(data, model, dict(model.file_parameters.value0), names,
                                library)
        return dataclasses.replace(problem, refused=refused)

    @classmethod
    def _assemble(cls, data: Dataset, model, defaults: dict, names: tuple,
                  library: Library = LIBRARY):
        obs, ys, sig, hold, which, counts = [], [], [], [], [], []
        for k, s in enumerate(data.series):
            obs.append(Observation(s.kind, np.asarray(s.x), cycles=float(s.cycles or 0.0),
                                   basis=s.basis or "mass"))
            ys.append(s.y)
            sig.append(np.full(s.y.shape, s.sigma))
            hold.append(s.holdout)
            which.append(np.full(s.y.shape, k))
            counts.append(np.broadcast_to(np.asarray(s.cycle_counts, float), s.y.shape))
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
        end = float(data.fit_cycles)   # the fit window: nothing chosen looks beyond it
        probes = tuple(sorted({*(float(c) for c in _checkpoints(data) if c <= end),
                               *(f * end for f in PROBE_FRACTIONS)}))
        return cls(model, tuple(obs), np.concatenate(ys), np.concatenate(sig),
                   np.concatenate(hold), np.concatenate(which), tuple(data.fit_names),
                   {k: jnp.asarray(v, dtype=float) for k, v in base0.items()},
                   np.asarray(tau, dtype=float), suspects, names, probes,
                   np.concatenate(counts), tuple(s.kind for s in data.series), library)

    def with_model(self, model) -> "Problem":
        return dataclasses.replace(self, model=model)

    @property
    def n_base(self) -> int:
        return len(self.fit_names)

    @property
    def wear_coefficient_index(self) -> int | None:
        """Position of the fitted wear coefficient among the fitted unknowns (the
        rig's ``k``, a mechanism file's ``...wear.coefficient``), None when the
        dataset does not fit it."""
        for i, name in enumerate(self.fit_names):
            if name == "k" or name.endswith("wear.coefficient"):
                return i
        return None

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
        # a model failure poisons every prediction: reported, not fitted; NaN
        # with NaN derivatives (a 0 would read as a flat optimum)
        return not_an_answer(pred, ~h.ok, (x, effects, log_multipliers))

    def residual(self, x, effects: EffectValues, log_multipliers=None):
        return (self.predict(x, effects, log_multipliers) - self.y) / self.sigma

    def outputs(self, x, effects: EffectValues, log_multipliers=None):
        """(residuals, worn volume [m^3, mass basis] at `probe_cycles`) from one
        model run."""
        h = self.model(self.base(x, log_multipliers), effects)
        pred = jnp.concatenate([o(h) for o in self.observations])
        volume = (Observation("volume", np.asarray(self.probe_cycles, float))(h)
                  if self.probe_cycles else jnp.zeros(0))
        inputs = (x, effects, log_multipliers)
        pred = not_an_answer(pred, ~h.ok, inputs)
        return (pred - self.y) / self.sigma, not_an_answer(volume, ~h.ok, inputs)




@dataclass
class FitResult:
    """One fit: ``effect`` (None: the base model; several effects: their names
    joined by " + "), parameter values (SI) and 1-sigma uncertainties, the
    strength and its uncertainty, the effect's shape (SI; None without one)
    and its 1-sigma interval, chi-square of the fit points and of the
    held-out points, normalised residuals of all points.  The single-effect
    fields describe the first of ``effects``; every effect's numbers are in
    ``strengths``, ``strengths_std``, ``shapes`` and ``shape_intervals``, the
    learned discrepancy (if fitted) in ``discrepancy`` (variable) and
    ``discrepancy_coefficients`` / ``discrepancy_cov``."""

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
    effects: tuple = ()
    strengths: dict = field(default_factory=dict)
    strengths_std: dict = field(default_factory=dict)
    shapes: dict = field(default_factory=dict)
    shape_intervals: dict = field(default_factory=dict)
    discrepancy: str | None = None
    discrepancy_coefficients: np.ndarray | None = None
    discrepancy_cov: np.ndarray | None = None
    prior_chi2: float = 0.0

    def __post_init__(self):
        if self.effect is not None and not self.effects:
            self.effects = (self.effect,)
            self.strengths = self.strengths or {self.effect: self.strength}
            self.strengths_std = self.strengths_std or {self.effect: self.strength_std}
            if self.shape is not None:
                self.shapes = self.shapes or {self.effect: self.shape}
                self.shape_intervals = self.shape_intervals or {self.effect: self.shape_interval}

    def effect_values(self, library: Library | None = None) -> EffectValues:
        """The fitted effects (and discrepancy) as `EffectValues` of the fit's
        library (zeros for the base model)."""
        if library is None:
            lay = self.notes.get("layout")
            library = LIBRARY if lay is None else lay.library
        values: dict = {}
        for name in self.effects:
            values[name] = self.strengths[name]
            shape = library.effect(name).shape
            if self.shapes.get(name) is not None and shape is not None:
                values[shape.name] = self.shapes[name]
        out = EffectValues.of(library, **values)
        if self.discrepancy is not None:
            out = out.with_discrepancy(self.discrepancy, self.discrepancy_coefficients)
        return out

    @property
    def n_effect(self) -> int:
        """Fitted numbers of the effects: 1 per strength, 1 per shape."""
        return len(self.effects) + len(self.shapes)

    @property
    def n_discrepancy(self) -> int:
        return 0 if self.discrepancy_coefficients is None else len(self.discrepancy_coefficients)

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


@dataclass
class Linearisation:
    """The model at one packed point: residuals ``r`` (all points), their
    directional derivatives ``jac`` (points x tangents), the worn volume at
    `Problem.probe_cycles` and its derivatives."""

    r: np.ndarray
    jac: np.ndarray
    volume: np.ndarray
    volume_jac: np.ndarray


class Fitter:
    """Compiled pieces shared by all fits of one problem, and the
    Levenberg-Marquardt iteration (Marquardt's diagonal scaling).

    Why not optimistix here: on the dynamic model its trust-region LM needs
    many more steps (the model's adaptive steps make chi2 slightly rough at
    the 1e-3 scale, and its ratio test keeps shrinking the region); the plain
    Marquardt loop below accepts a Gauss-Newton-like step in a few iterations
    on either model (docs/notes/calibration-selection.md).  Each iteration is
    one forward-mode pass giving r and J together (`jax.jvp` over a batch of
    tangents), compiled once for the base fit and every refit: which effects
    (and which discrepancy variable) a fit frees is data (the tangents), not
    structure.  Unknowns z are in units of each parameter's stated spread
    (tau), of an effect's scale, of a shape's prior spread and of a
    discrepancy coefficient's prior spread, so the step tolerance ``xtol``
    reads "1 % of a spread".  A fit may take ``max_steps`` Levenberg-
    Marquardt steps, or `STEPS_PER_UNKNOWN` per unknown where that is more
    (a discrepancy of many coefficients can descend a long valley: on the
    coating campaign the depth's, 7 unknowns, took 66 steps and was dropped
    as failed at 30).
    """

    def __init__(self, problem: Problem, *, xtol=1e-2, ftol=1e-4, max_steps=30):
        self.problem = problem
        self.xtol, self.ftol, self.max_steps = xtol, ftol, max_steps
        self.library = library = problem.library
        nb, ne = problem.n_base, len(library.effects)
        # every unknown the loop differentiates by, packed: v = (fitted x,
        # strengths, ln shapes, ln multipliers of every rig parameter,
        # discrepancy coefficients)
        nu = len(problem.names)
        self._slices = (slice(0, nb), slice(nb, nb + ne), slice(nb + ne, nb + 2 * ne),
                        slice(nb + 2 * ne, nb + 2 * ne + nu))
        self._disc = slice(nb + 2 * ne + nu, nb + 2 * ne + nu + library.size)
        self.n_packed = self._disc.stop
        # directional derivatives per call: the one-effect fit's unknowns (x,
        # strength, shape); more come in batches of this size, so one compiled
        # program serves every fit, the score tests and the suspects
        # (not one per use: docs/notes/calibration-selection.md)
        self.width = nb + 2
        sx, ss, sg, su = self._slices
        sd = self._disc

        def outputs(v):
            effects = EffectValues(v[ss], v[sg], v[sd], library=library)
            return problem.outputs(v[sx], effects, v[su])

        def columns(v, tangents):
            """(outputs, d outputs / dv . t for each row t of ``tangents``)."""
            return jax.vmap(lambda t: jax.jvp(outputs, (v,), (t,)),
                            out_axes=((None, None), (1, 1)))(tangents)

        self._columns = jax.jit(columns)
        self._outputs = jax.jit(outputs)
        self._raw_outputs = outputs
        self.evaluations = 0
        self.k_index = problem.wear_coefficient_index
        # fits kept by the caller, by (effects, discrepancy): a model reached
        # on two selection paths is fitted once
        self.fits: dict = {}
        self._k_free: dict = {}   # discrepancy variable -> unit vector (`k_direction`)

    def _pack(self, x, strength=None, log_shape=None, u=None, discrepancy=None) -> np.ndarray:
        v = np.zeros(self.n_packed)
        sx, ss, sg, su = self._slices
        v[sx] = x
        for sl, part in ((ss, strength), (sg, log_shape), (su, u), (self._disc, discrepancy)):
            if part is not None:
                v[sl] = part
        return v

    def residuals(self, v) -> np.ndarray:
        """The residuals of every point at the packed point ``v`` (no derivative)."""
        self.evaluations += 1
        return np.asarray(self._outputs(jnp.asarray(v))[0])

    def log_posterior(self, fit: "FitResult"):
        """z -> log p(z | data) up to a constant, a JAX function of ``fit``'s
        unknowns (`posterior` module notes; -inf outside the layout's bounds
        and where the model fails).  Its gradient is one reverse pass of the
        model (a sampler asks for a scalar's gradient: one pass, where the
        fit's forward-mode program would push one tangent per unknown),
        zeroed where the model fails.  Outside the bounds (a strength past
        its physical limit, where the model need not be defined) the model
        is evaluated at the fit instead: a sampler's trajectory can go there."""
        lay: Layout = fit.notes["layout"]
        rows = jnp.asarray(np.asarray(fit.notes["rows"], bool))
        tangents = jnp.asarray(lay.tangents)
        prior = jnp.asarray(lay.prior_index)
        lower, upper = jnp.asarray(lay.lower), jnp.asarray(lay.upper)
        z_fit = jnp.asarray(fit.notes["z"], dtype=float)
        outputs = self._raw_outputs

        def misfit(z):
            inside = jnp.all((z >= lower) & (z <= upper))
            # double where: outside the bounds the model runs at the fit
            r = jnp.where(rows, outputs(tangents.T @ jnp.where(inside, z, z_fit))[0], 0.0)
            # a point the model cannot reach adds nothing, and no NaN flows
            # back through it; the value says the model failed
            finite = jnp.isfinite(r)
            safe = jnp.where(finite, r, 0.0)
            value = -0.5 * (safe @ safe + z[prior] @ z[prior])
            return value, inside & jnp.all(finite)

        @jax.custom_vjp
        def log_p(z):
            value, ok = misfit(z)
            return jnp.where(ok, value, -jnp.inf)

        def forward(z):
            (value, ok), grad = jax.value_and_grad(misfit, has_aux=True)(z)
            return (jnp.where(ok, value, -jnp.inf),
                    jnp.where(ok & jnp.all(jnp.isfinite(grad)), grad, 0.0))

        def backward(grad, g):
            return (g * grad,)

        log_p.defvjp(forward, backward)
        return log_p

    def linearise(self, v, tangents) -> Linearisation:
        """The model and its derivatives along any number of tangent rows, in
        batches of ``width``."""
        tangents = np.atleast_2d(tangents)
        cols, vcols = [], []
        r = vol = None
        for i in range(0, max(tangents.shape[0], 1), self.width):
            batch = tangents[i:i + self.width]
            pad = np.zeros((self.width - batch.shape[0], self.n_packed))
            (r, vol), (jac, vjac) = self._columns(jnp.asarray(v),
                                                  jnp.asarray(np.vstack([batch, pad])))
            self.evaluations += 1
            cols.append(np.asarray(jac)[:, :batch.shape[0]])
            vcols.append(np.asarray(vjac)[:, :batch.shape[0]])
        return Linearisation(np.asarray(r), np.concatenate(cols, axis=1), np.asarray(vol),
                             np.concatenate(vcols, axis=1))

    def _directional(self, v, tangents) -> tuple[np.ndarray, np.ndarray]:
        """(r, J T^T) for any number of tangent rows."""
        lin = self.linearise(v, tangents)
        return lin.r, lin.jac

    def _unit(self, part: int, index) -> np.ndarray:
        """Tangent rows: unit vectors of ``index`` within packed part ``part``
        (0 x, 1 strengths, 2 ln shapes, 3 ln multipliers, 4 discrepancy)."""
        start = (*self._slices, self._disc)[part].start
        t = np.zeros((len(index), self.n_packed))
        t[np.arange(len(index)), start + np.asarray(index, dtype=int)] = 1.0
        return t

    def _levenberg_marquardt(self, z, evaluate, rows, free, what, bounds=None,
                             max_steps: int | None = None):
        """(z, steps, fit-row Jacobian, all residuals) at the accepted minimum.
        ``evaluate(z) -> (all residuals, fit-row Jacobian)``; ``rows(r_all, z)``:
        the objective's rows; ``bounds``: (lower, upper) arrays of z (a step
        is cut back to the box); ``max_steps``: default the fitter's."""
        max_steps = self.max_steps if max_steps is None else max_steps
        lower, upper = ((np.full(z.shape, -np.inf), np.full(z.shape, np.inf))
                        if bounds is None else bounds)
        r_all, jac = evaluate(z)
        r = rows(r_all, z)
        if not np.all(np.isfinite(r)):
            raise SolverError(f"calibration of the {what}: the model failed at the start "
                              "(non-finite predictions)")
        chi2, lam, steps = float(r @ r), 1e-3, 0
        for steps in range(1, max_steps + 1):
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
                          f"{max_steps} steps (chi2 {chi2:.6g})")

    def effect_jacobian(self, x, log_shape, v=None) -> np.ndarray:
        """dr/ds of every effect (columns, the library's order) at the log-shapes
        ``log_shape`` (ln of shape / default) and zero strength, or at the
        packed point ``v`` (a fitted model) with its ln shapes replaced by
        ``log_shape`` for the effects it has at zero strength."""
        if v is None:
            v = self._pack(x, log_shape=log_shape)
        else:
            v = np.array(v, dtype=float)
            _, ss, sg, _ = self._slices
            off = v[ss] == 0.0
            v[sg] = np.where(off, log_shape, v[sg])
        return self._directional(v, self._unit(1, range(len(self.library.effects))))[1]

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

    def layout(self, effects=(), discrepancy: str | None = None) -> "Layout":
        return Layout.of(self, tuple(effects), discrepancy)

    def base_fit(self) -> "FitResult":
        """The base model's fit (every effect at zero), fitted once."""
        key: tuple = (frozenset(), None)
        if key not in self.fits:
            self.fits[key] = self.fit(None)
        return self.fits[key]

    def k_direction(self, variable: str) -> np.ndarray | None:
        """The direction u, in the discrepancy's coefficients (prior units),
        along which k (1 + delta) changes like k itself over the data (g = J_d^T
        J_k over the fit points at the base fit, normalised), when it must be
        taken out of the fit; None when it need not, or when k is not fitted.

        Along u, delta and k trade against each other: moving delta by u and
        ln k by the matching amount (`identified_k`) leaves the predictions
        unchanged to first order.  Where u's effect is k's almost exactly (a
        Fourier series over a worn arc: a near-constant over the data), the
        trade is a valley that is straight only to first order: a step of the
        Gauss-Newton 1-sigma along it departs from the linearised residuals by
        tens to thousands in chi2, and the Laplace posterior has no meaning
        there.  Then the discrepancy is held orthogonal to u (`Layout.of`),
        which costs it nothing the data show apart from k.  Where the step
        departs by less than `VALLEY` (a trend in the cycle count or the wear
        depth, whose effect differs from k's: the data see that direction
        apart from k, 1e4-1e5 times better than the prior), u stays free, as
        taking it out would cost a three-term basis a third of its freedom (on
        a wear coefficient swinging with the cycle count, chi2 5,795 instead
        of 1,172).  Computed once per variable, at the base fit, from the fit
        points alone."""
        if self.k_index is None:
            return None
        if variable not in self._k_free:
            self._k_free[variable] = self._valley(variable)
        return self._k_free[variable]

    def _valley(self, variable: str) -> np.ndarray | None:
        """u of `k_direction` where a Gauss-Newton 1-sigma step along it (delta
        by u, ln k by the matching amount) departs from the linearised fit
        residuals by more than `VALLEY` in chi2; None otherwise."""
        k = self.k_index
        assert k is not None  # `k_direction` asks only where k is fitted
        base = self.base_fit()
        lay = Layout.of(self, (), variable, constrained=False)
        rows = ~self.problem.holdout
        nb = self.problem.n_base
        z0 = lay.start(None, 0.0, 0.0, base)
        lin = self.linearise(lay.pack(z0), lay.tangents)
        jac = lin.jac[rows]
        g = jac[:, nb:].T @ jac[:, k]
        norm = float(np.linalg.norm(g))
        if norm == 0.0:
            return None
        u = g / norm
        a = identified_k(jac, k, slice(nb, lay.size))
        moved = (jac[:, nb:] + np.outer(jac[:, k], a)) @ u   # the step's linear effect
        dz = np.zeros(lay.size)
        dz[nb:], dz[k] = u, a @ u
        dz /= math.sqrt(1.0 + float(moved @ moved))         # 1 sigma (data and prior)
        exact = self.residuals(lay.pack(z0 + dz))[rows]
        departure = float(np.sum((exact - lin.r[rows] - jac @ dz) ** 2))
        return u if departure > VALLEY else None

    def refine(self, fit: "FitResult", z) -> "FitResult":
        """``fit``'s model fitted again from the unknowns ``z`` (a point of its
        layout where the posterior's draws found it higher than at the fit)."""
        lay = fit.notes["layout"]
        return self.fit(lay.effects, discrepancy=lay.discrepancy, rows=fit.notes["rows"],
                        z0=np.asarray(z, float))

    def fit(self, effect: str | tuple | None = None, x0=None, s0=0.0, log_shape0=0.0, *,
            discrepancy: str | None = None, start: "FitResult | None" = None,
            rows: np.ndarray | None = None, z0: np.ndarray | None = None) -> FitResult:
        """Fit the base parameters with ``effect`` (a name, a tuple of names or
        None) and the learned discrepancy over ``discrepancy`` (a variable of
        `discrepancy.VARIABLES`, or None).  Starting point: ``x0`` (the model's
        fitted unknowns), ``s0`` / ``log_shape0`` (a number for a single effect,
        a dict by name for several), or ``start``, an earlier fit whose numbers
        are reused where it shares the effects, or ``z0``, the unknowns
        themselves.  ``rows``: the points fitted (default: every point not held
        out); the others are predicted."""
        p = self.problem
        effects = () if effect is None else (effect,) if isinstance(effect, str) else tuple(effect)
        lay = self.layout(effects, discrepancy)
        z0 = lay.start(x0, s0, log_shape0, start) if z0 is None else z0
        what = ("base model" + "".join(f" + {e}" for e in effects)
                + (f" + discrepancy in {discrepancy}" if discrepancy else ""))
        fit_rows = ~p.holdout if rows is None else np.asarray(rows, bool)

        def objective_rows(r_all, z):
            return np.concatenate([r_all[fit_rows], lay.prior_rows(z)])

        def evaluate(z):
            lin = self.linearise(lay.pack(z), lay.tangents)
            return lin.r, np.vstack([lin.jac[fit_rows], lay.prior_jacobian])

        t0 = time.perf_counter()
        z0 = np.clip(z0, lay.lower, lay.upper)
        z, steps, jz, r = self._levenberg_marquardt(
            z0, evaluate, objective_rows, np.ones(lay.size, bool), what, (lay.lower, lay.upper),
            max(self.max_steps, STEPS_PER_UNKNOWN * lay.size))
        wall = time.perf_counter() - t0
        if not np.all(np.isfinite(r)):  # a held-out point the model could not reach
            raise SolverError(f"calibration of the {what}: the model failed at the solution "
                              "(non-finite predictions)")
        # Gauss-Newton covariance of z from the last Jacobian (fit and prior rows)
        cov = np.linalg.pinv(jz.T @ jz)
        return lay.result(z, cov, jz[:int(fit_rows.sum())], r, steps, wall,
                          float(np.sum(lay.prior_rows(z) ** 2)), fit_rows)


def identified_k(jac, k: int, d: slice) -> np.ndarray:
    """How the wear coefficient is identified beside a learned discrepancy.

    Over the worn arc the discrepancy's Fourier terms (or its trends in
    depth, cycles, ...) are not orthogonal to a constant, so a constant part
    of delta and k trade against each other: k alone is not identified.  The
    identified wear coefficient k_id is k with delta's component along k's
    direction taken out, x_id = x_k - a.z_d, where a_j = -<J_k, J_j> / <J_k,
    J_k> over the fit points (``jac``: their Jacobian by the unknowns, k at
    column ``k``, the discrepancy's at ``d``): in the coordinates (x_id, z_d)
    every discrepancy direction J_j + a_j J_k is orthogonal to k's, so k_id
    keeps the uncertainty k has without the discrepancy, and delta is
    reported relative to it, k (1 + delta) = k_id (1 + delta) exp(tau a.z_d).
    Returns a."""
    jk = jac[:, k]
    norm = float(jk @ jk)
    return -(jk @ jac[:, d]) / norm if norm > 0 else np.zeros(d.stop - d.start)


@dataclass
class Layout:
    """Where each fitted number sits in the fit's unknowns z and in the packed
    point v of the model: the base parameters, then each effect's strength,
    then each shaped effect's ln shape, then the discrepancy's coefficients
    (each in units of its spread), with their bounds and prior rows."""

    fitter: Fitter
    effects: tuple
    shaped: tuple
    discrepancy: str | None
    size: int
    tangents: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    prior_index: np.ndarray      # z entries with a unit Gaussian prior row
    prior_jacobian: np.ndarray
    # the discrepancy's coefficients act through P z_d (P = I - u u^T, u the
    # direction `Fitter.k_direction`); identity when unconstrained
    projection: np.ndarray | None = None
    # beside a discrepancy: a of `identified_k` at the fit (x_id = x_k - a.z_d),
    # so that every report of k, the posterior's included, is the identified one
    k_identification: np.ndarray | None = None

    @classmethod
    def of(cls, fitter: Fitter, effects: tuple, discrepancy: str | None,
           constrained: bool = True) -> "Layout":
        lib = fitter.library
        for e in effects:
            if e not in lib.names:
                raise InputError(f"unknown effect {e!r}; allowed: {', '.join(lib.names)}")
        if discrepancy is not None and discrepancy not in lib.variable_names:
            raise InputError(f"unknown discrepancy variable {discrepancy!r}; allowed: "
                             f"{', '.join(lib.variable_names)}")
        nb = fitter.problem.n_base
        shaped = tuple(e for e in effects if lib.effect(e).shape is not None)
        nd = lib.variable(discrepancy).size if discrepancy else 0
        size = nb + len(effects) + len(shaped) + nd
        t = np.zeros((size, fitter.n_packed))
        t[:nb] = fitter._unit(0, range(nb))
        lower, upper = np.full(size, -np.inf), np.full(size, np.inf)
        scales, log_std = lib.scales, lib.log_std
        for i, e in enumerate(effects):
            k = lib.index(e)
            t[nb + i] = fitter._unit(1, [k])[0] * scales[k]
            lower[nb + i] = lib.effects[k].lower / scales[k]
        o = nb + len(effects)
        for i, e in enumerate(shaped):
            k = lib.index(e)
            t[o + i] = fitter._unit(2, [k])[0] * log_std[k]
            lower[o + i], upper[o + i] = -SHAPE_PRIOR_SIGMAS, SHAPE_PRIOR_SIGMAS
        o += len(shaped)
        projection = None
        if discrepancy:
            sl = lib.slices[discrepancy]
            t[o:] = (fitter._unit(4, range(sl.start, sl.stop))
                     * lib.variable(discrepancy).prior_std()[:, None])
            u = fitter.k_direction(discrepancy) if constrained else None
            if u is not None:
                projection = np.eye(nd) - np.outer(u, u)
                t[o:] = projection @ t[o:]
        prior = np.arange(nb + len(effects), size)
        pj = np.zeros((prior.size, size))
        pj[np.arange(prior.size), prior] = 1.0
        return cls(fitter, effects, shaped, discrepancy, size, t, lower, upper, prior, pj,
                   projection)

    @property
    def library(self) -> Library:
        return self.fitter.library

    def _prior_std(self) -> np.ndarray:
        """The discrepancy's prior spread per coefficient."""
        assert self.discrepancy is not None, "a layout without a discrepancy"
        return self.library.variable(self.discrepancy).prior_std()

    def discrepancy_coefficients(self, z) -> np.ndarray:
        """The coefficients delta acts with at unknowns ``z`` (..., size), in
        the discrepancy's own units (P z_d times the prior scale)."""
        assert self.discrepancy is not None, "a layout without a discrepancy"
        scale = self._prior_std()
        zd = np.asarray(z)[..., self.size - scale.size:]
        if self.projection is not None:
            zd = zd @ self.projection
        return zd * scale

    @property
    def n_base(self) -> int:
        return self.fitter.problem.n_base

    def pack(self, z) -> np.ndarray:
        """The packed model point v at unknowns z (v = T^T z: every tangent
        row is the unit step of its unknown)."""
        return self.tangents.T @ z

    def prior_rows(self, z) -> np.ndarray:
        return z[self.prior_index]

    def natural(self, z) -> dict:
        """{name: values} of the numbers at unknowns ``z`` (S, size) in SI: the
        fitted rig parameters (the identified wear coefficient), each effect's
        strength (``<effect>``) and shape (``<shape name>``), the discrepancy's
        coefficients (``delta_<variable>_<j>``)."""
        z = np.atleast_2d(z)
        p = self.fitter.problem
        nb = self.n_base
        out = {}
        for i, name in enumerate(p.fit_names):
            x = z[:, i]
            if i == self.fitter.k_index and self.k_identification is not None:
                x = x - z[:, self.size - self.k_identification.size:] @ self.k_identification
            out[name] = float(p.base0[name]) * np.exp(p.tau[i] * x)
        for i, e in enumerate(self.effects):
            out[e] = z[:, nb + i] * self.library.effect(e).scale
        o = nb + len(self.effects)
        for i, e in enumerate(self.shaped):
            shape = self.library.effect(e).shape
            assert shape is not None  # a shaped effect
            out[shape.name] = shape.default * np.exp(z[:, o + i] * shape.log_std)
        o += len(self.shaped)
        if self.discrepancy:
            coef = self.discrepancy_coefficients(z)
            for j in range(coef.shape[1]):
                out[f"delta_{self.discrepancy}_{j + 1}"] = coef[:, j]
        return out

    def start(self, x0, s0, log_shape0, start: FitResult | None) -> np.ndarray:
        nb = self.n_base
        z = np.zeros(self.size)
        if start is not None:
            x0 = start.notes["x"] if x0 is None else x0
            s0 = {**start.strengths, **(s0 if isinstance(s0, dict) else {})}
            log_shape0 = {**{e: log_shape(e, v, self.library) for e, v in start.shapes.items()
                             if v is not None},
                          **(log_shape0 if isinstance(log_shape0, dict) else {})}
            variable = self.discrepancy
            if variable is not None and start.discrepancy == variable:
                scale = self._prior_std()
                z[-scale.size:] = np.asarray(start.discrepancy_coefficients) / scale
        if x0 is not None:
            z[:nb] = np.asarray(x0, dtype=float)
        one = len(self.effects) == 1
        for i, e in enumerate(self.effects):
            k = self.library.index(e)
            s = s0 if one and not isinstance(s0, dict) else (
                s0.get(e, 0.0) if isinstance(s0, dict) else 0.0)
            z[nb + i] = float(s) / self.library.scales[k]
        o = nb + len(self.effects)
        for i, e in enumerate(self.shaped):
            k = self.library.index(e)
            g = log_shape0 if one and not isinstance(log_shape0, dict) else (
                log_shape0.get(e, 0.0) if isinstance(log_shape0, dict) else 0.0)
            z[o + i] = float(g) / self.library.log_std[k]
        return z

    def result(self, z, cov, jac_fit, r, steps, wall, prior_chi2, fit_rows) -> FitResult:
        p = self.fitter.problem
        nb = self.n_base
        std_z = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        x = z[:nb]
        base = p.base(jnp.asarray(x))
        params = {n: float(base[n]) for n in p.fit_names}
        params_std = {n: float(params[n] * p.tau[i] * std_z[i])
                      for i, n in enumerate(p.fit_names)}
        strengths, strengths_std, shapes, intervals = {}, {}, {}, {}
        for i, e in enumerate(self.effects):
            scale = self.library.effect(e).scale
            strengths[e] = float(z[nb + i] * scale)
            strengths_std[e] = float(std_z[nb + i] * scale)
        o = nb + len(self.effects)
        for i, e in enumerate(self.shaped):
            shape = self.library.effect(e).shape
            assert shape is not None  # a shaped effect
            default = shape.default
            ln, half = z[o + i] * shape.log_std, std_z[o + i] * shape.log_std
            shapes[e] = float(default * math.exp(ln))
            intervals[e] = (float(default * math.exp(ln - half)),
                            float(default * math.exp(ln + half)))
        o += len(self.shaped)
        coef = cov_d = None
        b = None
        if self.discrepancy:
            prior = self._prior_std()
            coef = self.discrepancy_coefficients(z)
            proj = np.eye(len(prior)) if self.projection is None else self.projection
            cov_d = (proj @ cov[o:, o:] @ proj) * np.outer(prior, prior)
            ki = self.fitter.k_index
            if ki is not None:
                # the wear coefficient identified beside the discrepancy
                # (`identified_k`): its value and 1-sigma replace the model's
                k = ki
                a = identified_k(jac_fit, k, slice(o, self.size))
                self.k_identification = a
                e = np.zeros(self.size)
                e[k], e[o:] = 1.0, -a
                x_id = x[k] - a @ z[o:]
                b = p.tau[k] * a / prior               # ln(k_model / k_id) per coefficient
                name = p.fit_names[k]
                params[name] = float(p.base0[name] * math.exp(p.tau[k] * x_id))
                params_std[name] = float(params[name] * p.tau[k]
                                         * math.sqrt(max(float(e @ cov @ e), 0.0)))
        first = self.effects[0] if self.effects else None
        v = self.pack(z)
        held = ~fit_rows
        return FitResult(
            effect=" + ".join(self.effects) if self.effects else None,
            params=params, params_std=params_std,
            strength=strengths.get(first, 0.0) if first else 0.0,
            strength_std=strengths_std.get(first, 0.0) if first else 0.0,
            chi2_fit=float(np.sum(r[fit_rows] ** 2)), n_fit=int(fit_rows.sum()),
            chi2_holdout=float(np.sum(r[held] ** 2)), n_holdout=int(held.sum()),
            residual=r, prediction=r * p.sigma + p.y, iterations=steps, wall_time_s=wall,
            shape=shapes.get(first) if first else None,
            shape_interval=intervals.get(first) if first else None,
            # "x": the model's fitted unknowns (``params`` hold the identified k
            # beside a discrepancy: `identified_k`)
            notes={"x": v[:nb].tolist(), "z": z, "cov": cov, "jacobian": jac_fit,
                   "v": v, "layout": self, "rows": fit_rows,
                   "log_k_per_coefficient": b},
            effects=self.effects, strengths=strengths, strengths_std=strengths_std,
            shapes=shapes, shape_intervals=intervals, discrepancy=self.discrepancy,
            discrepancy_coefficients=coef, discrepancy_cov=cov_d, prior_chi2=prior_chi2)
