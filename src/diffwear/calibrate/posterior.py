"""The posterior of a chosen model's numbers, and the bands it gives.

The fit's unknowns z (the fitted rig parameters, the effects' strengths and
shapes, the discrepancy's coefficients, each in units of its spread:
`fit.Layout`) have the posterior

    p(z | data) ~ exp(-(|r_fit(z)|^2 + |z_prior|^2) / 2)

within the layout's bounds: the fit points' residuals in units of their
stated noise, the unit Gaussian priors of shapes and discrepancy
coefficients, and flat priors on the rest.  Two ways to it:

* **Laplace, checked** (`method="laplace"`, the fast path): draws around the
  fit along the Gauss-Newton covariance's principal directions, each scaled
  to the exact posterior's fall-off along it (`_matched_root`), from a
  Student-t of 5 degrees of freedom, each evaluated on the exact model;
  the importance ratios p / q, Pareto
  smoothed (Vehtari, Simpson, Gelman, Yao and Gabry, J. Mach. Learn. Res. 25
  (2024) 72), weight the draws, and their Pareto k says whether the
  Gaussian is near enough: below `PARETO_K_OK` the weighted draws stand for
  the posterior; above it the draws stand for the matched Gaussian,
  unweighted (importance weights resting on a few draws would give bands
  far too narrow), and the report says the Gaussian is unchecked and names
  the sampler.
* **NUTS** (`method="nuts"`): the No-U-Turn sampler (Hoffman and Gelman, J.
  Mach. Learn. Res. 15 (2014) 1593; blackjax) on the same compiled model,
  its gradient one reverse pass of the model (`Fitter.log_posterior`),
  `CHAINS` chains, the rank-normalised split R-hat and the bulk effective
  sample size of each number reported (Vehtari, Gelman, Simpson, Carpenter
  and Buerkner, Bayesian Anal. 16 (2021) 667); the chains run on until
  every R-hat is at most `R_HAT_TARGET` or `MAX_SAMPLES` draws a chain.  It samples u, the numbers
  in the coordinates that whiten the Gauss-Newton covariance C (z = z_fit +
  R u, R R^T = C), where the posterior is near a unit Gaussian: the
  warm-up adapts the step size and a mass matrix from the identity, and
  its estimate is shrunk towards 1e-3 I (Stan's regularisation), which
  presumes numbers of unit scale (in z a number whose spread is 1e-3 is
  given a 100 times too wide mass-matrix entry, and every trajectory
  diverges).

Either way the posterior is a set of weighted draws with the model's
predictions at every measured point, so the predictive band of a
measurement (model and noise) and any derived number (the life,
`forecast`) come from the same draws.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import InputError, SolverError
from .fit import FitResult, Fitter

METHODS = ("laplace", "nuts")
# "linear": the Laplace draws' predictions by the fit's linearisation, for a
# model too costly to evaluate at every draw (the dynamic model)
DRAWS = 160          # Laplace draws evaluated on the exact model
# Pareto k of the importance ratios below which the weighted Gaussian draws
# stand for the posterior (0.7: Vehtari et al. 2024, Sec. 3.2, for a few
# hundred draws)
PARETO_K_OK = 0.7
# degrees of freedom of the Student-t proposal of the Laplace draws
PROPOSAL_DOF = 5.0
CHAINS = 4
WARMUP = 150
SAMPLES = 250
# The chains go on, `SAMPLES` more draws each, until every number's R-hat is
# at most R_HAT_TARGET (Vehtari et al. 2021, Sec. 4: 1.01), up to
# MAX_SAMPLES draws a chain.  On an exact unit Gaussian the sampler's largest
# R-hat over two numbers exceeds 1.01 in 7 of 40 seeds at 250 draws a chain
# and in 0 of 40 at 1,000 (benchmarks/records/r_hat_scatter.json): below
# 1,000 a chain, R-hat's own scatter reaches the target
R_HAT_TARGET = 1.01
MAX_SAMPLES = 1000
BAND = 0.90           # the predictive band's probability
SEED = 20091         # draws are repeatable


@dataclass
class Posterior:
    """Weighted draws of a fit's unknowns and the model's residuals at them."""

    method: str
    fit: FitResult
    z: np.ndarray                # (S, d) unknowns
    weights: np.ndarray          # (S,) normalised
    residuals: np.ndarray        # (S, points) residual r = (model - data) / sigma
    diagnostics: dict = field(default_factory=dict)
    chains: int = 1

    @property
    def layout(self):
        return self.fit.notes["layout"]

    def numbers(self) -> dict:
        """{name: {mean, std, q05, q95, (r_hat, ess)}} of each number in SI (a
        wear coefficient in 1/Pa = m^3/(N m))."""
        values = self.layout.natural(self.z)
        out = {}
        for k, (name, col) in enumerate(values.items()):
            entry = _weighted_summary(col, self.weights)
            if "r_hat" in self.diagnostics:
                entry["r_hat"] = float(self.diagnostics["r_hat"][k])
                entry["ess"] = float(self.diagnostics["ess"][k])
            else:  # the effective number of the draws as weighted
                entry["ess"] = float(1.0 / np.sum(self.weights ** 2))
            out[name] = entry
        return out

    def predictive_band(self, sigma: np.ndarray, y: np.ndarray, level: float = BAND):
        """(lower, upper) of the ``level`` predictive band of every point in
        data units (`predictive_band` of this posterior alone)."""
        return predictive_band(((self, 1.0),), sigma, y, level)

    def entry(self) -> dict:
        return {"method": self.method, "draws": int(self.z.shape[0]), "chains": self.chains,
                "diagnostics": {k: (np.asarray(v).tolist() if isinstance(v, np.ndarray) else v)
                                for k, v in self.diagnostics.items()},
                "numbers": self.numbers()}


def predictive_band(pool: Sequence[tuple[Posterior, float]], sigma: np.ndarray,
                    y: np.ndarray, level: float = BAND):
    """(lower, upper) of the ``level`` predictive band of every point in data
    units: the mixture over the draws of the model's prediction plus the
    point's Gaussian noise.  ``pool``: (posterior, weight) of each model the
    answer holds open, their draws pooled by those weights (one model: weight 1)."""
    pred = np.concatenate([p.residuals * sigma + y for p, _ in pool])   # (S, n)
    w = np.concatenate([p.weights * weight for p, weight in pool])
    w = w / np.sum(w)
    lo = _mixture_quantile(pred, sigma, w, 0.5 * (1.0 - level))
    hi = _mixture_quantile(pred, sigma, w, 0.5 * (1.0 + level))
    return lo, hi


def coverage(pool: Sequence[tuple[Posterior, float]], sigma: np.ndarray, y: np.ndarray,
             rows: np.ndarray, level: float = BAND) -> float:
    """Share of the points ``rows`` inside their ``level`` predictive band
    over ``pool`` (`predictive_band`); NaN when ``rows`` holds none."""
    if not np.any(rows):
        return math.nan
    lo, hi = predictive_band(pool, sigma, y, level)
    inside = (y >= lo) & (y <= hi)
    return float(np.mean(inside[rows]))


def _weighted_summary(x: np.ndarray, w: np.ndarray) -> dict:
    mean = float(np.sum(w * x))
    std = math.sqrt(max(float(np.sum(w * (x - mean) ** 2)), 0.0))
    return {"mean": mean, "std": std, "q05": _weighted_quantile(x, w, 0.05),
            "q95": _weighted_quantile(x, w, 0.95)}


def _weighted_quantile(x: np.ndarray, w: np.ndarray, q: float) -> float:
    order = np.argsort(x)
    cw = np.cumsum(w[order])
    cw = (cw - 0.5 * w[order]) / cw[-1]
    return float(np.interp(q, cw, x[order]))


def _normal_cdf(x):
    return 0.5 * (1.0 + _erf(x / math.sqrt(2.0)))


_erf = np.vectorize(math.erf, otypes=[float])


def _mixture_quantile(means: np.ndarray, sigma: np.ndarray, w: np.ndarray, q: float,
                      iterations: int = 60) -> np.ndarray:
    """Per point (column), the ``q`` quantile of sum_s w_s N(means[s], sigma^2)
    (bisection on the mixture's CDF)."""
    lo = means.min(axis=0) - 8.0 * sigma
    hi = means.max(axis=0) + 8.0 * sigma
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        cdf = np.einsum("s,sn->n", w, _normal_cdf((mid[None] - means) / sigma[None]))
        below = cdf < q
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return 0.5 * (lo + hi)


def _log_target(fitter: Fitter, fit: FitResult, r_all: np.ndarray, z: np.ndarray) -> float:
    """log p(z | data) up to a constant (module notes), -inf outside the bounds."""
    lay = fit.notes["layout"]
    rows = fit.notes["rows"]
    if np.any(z < lay.lower) or np.any(z > lay.upper) or not np.all(np.isfinite(r_all[rows])):
        return -math.inf
    r = r_all[rows]
    prior = lay.prior_rows(z)
    return -0.5 * float(r @ r + prior @ prior)


# The proposal's scale along each principal direction of the Gauss-Newton
# covariance is matched to the exact posterior there (`_matched_root`), from
# probes at these multiples of the Gaussian's 1-sigma, kept within this range
PROBES = (0.5, 1.0)
MATCHED_RANGE = (0.05, 2.0)


def _matched_root(fitter: Fitter, fit: FitResult, cov: np.ndarray):
    """A square root of the proposal's covariance: the Gauss-Newton
    covariance's principal directions, each scaled to where the exact log
    posterior has fallen by 1/2 (its 1-sigma if it were Gaussian there).

    Where the data inform a direction only at second order (a discrepancy's
    coefficients where the pin barely wears: zero first-order effect, a large
    one a step away) the exact posterior falls off like a s^2 + b s^4, not
    s^2 / 2, and draws at the Gaussian's scale all land far out in its tail
    (the importance weights then rest on one draw).  The fall-off measured at
    `PROBES` (both signs averaged) gives a and b; the scale is the root of
    a s^2 + b s^4 = 1/2.  Returns (root, the scale factors)."""
    lay = fit.notes["layout"]
    z_hat = np.asarray(fit.notes["z"], float)
    at_fit = -0.5 * (fit.chi2_fit + fit.prior_chi2)
    lam, vec = np.linalg.eigh(cov)
    sd = np.sqrt(np.clip(lam, 0.0, None))
    factors = np.ones(lam.size)
    for i in np.flatnonzero(sd > 0):
        fall = []
        for step in PROBES:
            drops = []
            for sign in (-1.0, 1.0):
                z = z_hat + sign * step * sd[i] * vec[:, i]
                drops.append(at_fit - _log_target(fitter, fit, fitter.residuals(lay.pack(z)), z))
            fall.append(float(np.mean(drops)))
        (s1, d1), (s2, d2) = zip(PROBES, fall)
        if not (np.isfinite(d1) and np.isfinite(d2)):
            factors[i] = MATCHED_RANGE[0] if not np.isfinite(d1) else s1
            continue
        # d(s) = a s^2 + b s^4 through the two probes
        m = np.array([[s1 ** 2, s1 ** 4], [s2 ** 2, s2 ** 4]])
        a, b = np.clip(np.linalg.solve(m, [d1, d2]), 0.0, None)
        if b > 0:
            root_s2 = (-a + math.sqrt(a * a + 2.0 * b)) / (2.0 * b)
        else:
            root_s2 = 0.5 / a if a > 0 else MATCHED_RANGE[1] ** 2
        factors[i] = float(np.clip(math.sqrt(root_s2), *MATCHED_RANGE))
    return vec * (sd * factors), factors


def laplace(fitter: Fitter, fit: FitResult, draws: int = DRAWS, seed: int = SEED) -> Posterior:
    """Gaussian draws at the fit, evaluated on the exact model and weighted by
    Pareto-smoothed importance ratios (module notes)."""
    from blackjax.diagnostics import psis_weights

    lay = fit.notes["layout"]
    z_hat = np.asarray(fit.notes["z"], float)
    cov = _symmetric(np.asarray(fit.notes["cov"], float))
    root, factors = _matched_root(fitter, fit, cov)
    rng = np.random.default_rng(seed)
    # a Student-t proposal with the Gaussian's scale: its heavier tails keep
    # the importance ratios bounded where the posterior's tails are heavier
    # than the Gaussian's (a skewed shape, a strength near its bound)
    d = z_hat.size
    eps = rng.standard_normal((draws, d)) / np.sqrt(
        rng.chisquare(PROPOSAL_DOF, (draws, 1)) / PROPOSAL_DOF)
    z = z_hat + eps @ root.T
    residuals = np.stack([fitter.residuals(lay.pack(zi)) for zi in z])
    log_p = np.array([_log_target(fitter, fit, r, zi) for r, zi in zip(residuals, z)])
    log_q = -0.5 * (PROPOSAL_DOF + d) * np.log1p(np.sum(eps ** 2, axis=1) / PROPOSAL_DOF)
    finite = np.isfinite(log_p)
    log_ratio = np.where(finite, log_p - log_q, -np.inf)
    if finite.sum() < 10:
        raise SolverError("posterior: the model fails at most draws near the fit "
                          f"({int(finite.sum())} of {draws} finite); the Gaussian "
                          "approximation cannot be checked")
    ref = np.max(log_ratio[finite])
    lw, k = psis_weights(jnp.asarray(np.where(finite, log_ratio - ref, -1e300)))
    w = np.exp(np.asarray(lw, float))
    w = np.where(finite, w, 0.0)
    w /= w.sum()
    k = float(k)
    adequate = bool(k < PARETO_K_OK)
    ess = float(1.0 / np.sum(w ** 2))
    if not adequate:
        # the exact model does not confirm the Gaussian: weights that rest on
        # a few draws would give bands far too narrow, so the draws stand for
        # the (matched) Gaussian itself, unchecked: weights N / t
        log_n = -0.5 * np.sum(eps ** 2, axis=1)
        w = np.where(finite, np.exp(log_n - log_q - np.max((log_n - log_q)[finite])), 0.0)
        w /= w.sum()
    at_fit = -0.5 * (fit.chi2_fit + fit.prior_chi2)
    best = int(np.argmax(np.where(finite, log_p, -np.inf)))
    diagnostics = {"pareto_k": k, "ess": ess, "gaussian_adequate": adequate,
                   "weights": "importance" if adequate else "gaussian, unchecked",
                   "failed_draws": int((~finite).sum()),
                   # a draw the posterior puts higher than the fit: the fit stopped
                   # short of its minimum (`refined`)
                   "best_draw_gain": float(log_p[best] - at_fit), "best_draw": best,
                   "matched_scales": factors.tolist()}
    # the failed draws keep their rows (their weight is zero)
    residuals = np.where(np.isfinite(residuals), residuals, 0.0)
    return Posterior("laplace", fit, z, w, residuals, diagnostics)


def nuts_chains(logdensity, mean, cov, chains: int = CHAINS, warmup: int = WARMUP,
                samples: int = SAMPLES, seed: int = SEED, parallel: bool | None = None,
                log=None, *, numbers=None, r_hat_target: float | None = R_HAT_TARGET,
                max_samples: int = MAX_SAMPLES):
    """NUTS chains on ``logdensity`` (z -> log p, a JAX function) sampled in
    the coordinates u that whiten ``cov`` about ``mean`` (z = mean + R u;
    module notes): the draws of z (chains, draws, d) and whether each
    transition diverged (chains, draws).

    Each chain warms up and takes ``samples`` draws; while the largest
    R-hat (rank-normalised, split) of ``numbers(z)`` exceeds ``r_hat_target``,
    every chain goes on from where it stopped, with its adapted step size and
    mass matrix, by ``samples`` more draws, up to ``max_samples`` a chain
    (``r_hat_target`` None: no more than ``samples``).  ``numbers``: (S, d)
    draws -> (S, m) the numbers R-hat is judged on (default: z itself).
    ``parallel``: see `nuts`; ``log``: a line as each chain ends, one after
    another, and as the chains are extended."""
    import time

    import blackjax

    z_hat = jnp.asarray(mean, dtype=float)
    root = jnp.asarray(_whitening(np.asarray(cov, float)))
    key = jax.random.PRNGKey(seed)

    def whitened(u):   # the log density at z = z_hat + R u
        return logdensity(z_hat + root @ u)

    def draws(state, params, key):
        kernel = blackjax.nuts(whitened, **params).step

        def step(state, k):
            state, info = kernel(k, state)
            return state, (state.position, info.is_divergent)

        state, (positions, divergent) = jax.lax.scan(step, state, jax.random.split(key, samples))
        return (state, params), z_hat + positions @ root.T, divergent

    @jax.jit
    def one_chain(key):
        k_init, k_warm, k_run = jax.random.split(key, 3)
        start = 0.5 * jax.random.normal(k_init, z_hat.shape)
        adapt = blackjax.window_adaptation(
            blackjax.nuts, whitened, is_mass_matrix_diagonal=False,
            initial_inverse_mass_matrix=jnp.eye(z_hat.shape[0]), initial_step_size=0.5,
            imm_shrinkage_to_previous=0.9)
        (state, params), _ = adapt.run(k_warm, start, num_steps=warmup)
        return draws(state, params, k_run)

    more = jax.jit(draws)
    keys = jax.random.split(key, chains)
    if jax.default_backend() != "cpu" if parallel is None else parallel:
        def run_all(block, carry):
            if block == 0:
                return jax.vmap(one_chain)(keys)
            return jax.vmap(more)(*carry, jax.vmap(lambda k: jax.random.fold_in(k, block))(keys))
    else:
        def run_all(block, carry):
            runs = []
            for i, k in enumerate(keys):
                t0 = time.perf_counter()
                if block == 0:
                    runs.append(jax.block_until_ready(one_chain(k)))
                else:
                    chain_carry = jax.tree_util.tree_map(lambda x: x[i], carry)
                    runs.append(jax.block_until_ready(
                        more(*chain_carry, jax.random.fold_in(k, block))))
                if log is not None:
                    what = f"{warmup} warm-up steps, {samples} draws" if block == 0 else \
                        f"{samples} more draws"
                    log(f"posterior: NUTS chain {i + 1} of {chains} ({what}) in "
                        f"{time.perf_counter() - t0:.0f} s")
            return jax.tree_util.tree_map(lambda *x: jnp.stack(x), *runs)

    positions, divergent = [], []
    block, carry = 0, None
    while True:
        carry, p, d = run_all(block, carry)
        positions.append(np.asarray(p))        # (chains, samples, d)
        divergent.append(np.asarray(d))
        z = np.concatenate(positions, axis=1)
        block += 1
        if r_hat_target is None or z.shape[1] + samples > max_samples:
            break
        r_hat = max_r_hat(z, numbers)
        if not r_hat > r_hat_target:
            break
        if log is not None:
            log(f"posterior: largest R-hat {r_hat:.4f} above {r_hat_target} after "
                f"{z.shape[1]} draws a chain; each chain goes on for {samples} more")
    return z, np.concatenate(divergent, axis=1)


def r_hats(z: np.ndarray, numbers=None) -> np.ndarray:
    """The rank-normalised split R-hat (Vehtari et al. 2021) of each number
    of chains ``z`` (chains, draws, d); ``numbers``: see `nuts_chains`."""
    from blackjax.diagnostics import rhat

    chains, n, d = z.shape
    values = z if numbers is None else np.asarray(numbers(z.reshape(-1, d))).reshape(chains, n, -1)
    return np.array([float(rhat(jnp.asarray(values[..., i]))) for i in range(values.shape[-1])])


def max_r_hat(z: np.ndarray, numbers=None) -> float:
    return float(np.max(r_hats(z, numbers)))


def nuts(fitter: Fitter, fit: FitResult, chains: int = CHAINS, warmup: int = WARMUP,
         samples: int = SAMPLES, seed: int = SEED, parallel: bool | None = None,
         log=None, r_hat_target: float | None = R_HAT_TARGET,
         max_samples: int = MAX_SAMPLES) -> Posterior:
    """NUTS on the exact model (module notes), the chains extended until every
    reported number's R-hat is at most ``r_hat_target`` (`nuts_chains`;
    ``diagnostics["converged"]`` says whether it was met within
    ``max_samples`` draws a chain).  ``parallel``: the chains as
    one vectorised program (default: on an accelerator, where the chains'
    arithmetic runs side by side; on a CPU it runs no faster than the chains
    one after another, and each chain's tree depth then sets its own cost);
    ``log``: a line as each chain ends (chains one after another)."""
    from blackjax.diagnostics import ess_bulk

    lay = fit.notes["layout"]
    if fit.dof < 1:
        raise InputError(f"posterior sampling: {fit.n_fit} fit points for {lay.size} numbers "
                         "leave no degree of freedom; allowed: more fit points than numbers "
                         "(or --posterior laplace)")

    def numbers(z):   # the reported numbers (S, m) of draws z (S, d)
        return np.stack(list(lay.natural(z).values()), axis=-1)

    chain_z, divergent = nuts_chains(fitter.log_posterior(fit), np.asarray(fit.notes["z"], float),
                                     _symmetric(np.asarray(fit.notes["cov"], float)),
                                     chains, warmup, samples, seed, parallel, log,
                                     numbers=numbers, r_hat_target=r_hat_target,
                                     max_samples=max_samples)
    per_chain = chain_z.shape[1]
    stacked = numbers(chain_z.reshape(-1, lay.size)).reshape(chains, per_chain, -1)
    r_hat = r_hats(stacked)
    ess = np.array([float(ess_bulk(jnp.asarray(stacked[..., i])))
                    for i in range(stacked.shape[-1])])
    z = chain_z.reshape(-1, lay.size)
    thin = max(1, z.shape[0] // DRAWS)   # the predictions at a spread of the draws
    z_kept = z[::thin]
    residuals = np.stack([fitter.residuals(lay.pack(zi)) for zi in z_kept])
    w = np.full(z_kept.shape[0], 1.0 / z_kept.shape[0])
    diagnostics = {"r_hat": r_hat, "ess": ess, "max_r_hat": float(np.max(r_hat)),
                   "min_ess": float(np.min(ess)),
                   "divergences": int(np.sum(divergent)), "draws_sampled": int(z.shape[0]),
                   "draws_per_chain": per_chain,
                   # the chains ran on until R-hat met this (or MAX_SAMPLES)
                   "r_hat_target": r_hat_target,
                   "converged": bool(r_hat_target is None or np.max(r_hat) <= r_hat_target),
                   # each chain's mean and spread of each number (chains, d): where
                   # an R-hat above 1 comes from
                   "chain_mean": stacked.mean(axis=1), "chain_std": stacked.std(axis=1)}
    return Posterior("nuts", fit, z_kept, w, residuals, diagnostics, chains)


def linear(fitter: Fitter, fit: FitResult, draws: int = DRAWS, seed: int = SEED) -> Posterior:
    """Gaussian draws at the fit with the predictions linearised, unchecked:
    for a model whose every evaluation costs a minute (module notes)."""
    lay = fit.notes["layout"]
    z_hat = np.asarray(fit.notes["z"], float)
    root = _root(_symmetric(np.asarray(fit.notes["cov"], float)))
    eps = np.random.default_rng(seed).standard_normal((draws, z_hat.size))
    z = z_hat + eps @ root.T
    jac = fitter.linearise(np.asarray(fit.notes["v"]), lay.tangents).jac
    residuals = fit.residual[None] + (z - z_hat) @ jac.T
    w = np.full(draws, 1.0 / draws)
    return Posterior("laplace, linearised", fit, z, w, residuals,
                     {"ess": float(draws), "checked": False})


# A draw this much higher in log posterior than the fit (a chi-square lower
# by twice it) means the fit stopped short of its minimum: it is refined
# from that draw and the posterior drawn again
REFINE_GAIN = 2.0


def refined(fitter: Fitter, post: Posterior, log=print) -> Posterior:
    """``post`` again at a refined fit when one of its draws lies higher than
    the fit (`REFINE_GAIN`); else ``post``."""
    gain = post.diagnostics.get("best_draw_gain", 0.0)
    if not gain > REFINE_GAIN:
        return post
    try:
        fit = fitter.refine(post.fit, post.z[post.diagnostics["best_draw"]])
    except SolverError:
        return post
    if not fit.chi2_fit + fit.prior_chi2 < post.fit.chi2_fit + post.fit.prior_chi2:
        return post
    log(f"posterior: a draw lay {gain:.1f} above the fit in log posterior; the fit refined "
        f"from it (chi2 {post.fit.chi2_fit:.1f} -> {fit.chi2_fit:.1f})")
    again = posterior(fitter, fit, post.method, log)
    again.diagnostics["refined_from_chi2"] = post.fit.chi2_fit
    return again


def posterior(fitter: Fitter, fit: FitResult, method: str = "laplace", log=None) -> Posterior:
    if method not in (*METHODS, "linear"):
        raise InputError(f"--posterior {method!r}: allowed {', '.join(METHODS)}")
    if method == "nuts":
        return nuts(fitter, fit, log=log)
    return laplace(fitter, fit) if method == "laplace" else linear(fitter, fit)


# NUTS needs this many fit points beyond the base parameters (a posterior
# from fewer is the prior's shape: the sampler has nothing to explore)
MIN_SAMPLING_DOF = 10


def require_sampling(data, problem) -> None:
    """Refuse (InputError) a sampler asked for on a dataset with too few fit
    points to give a posterior."""
    n = int(np.sum(~problem.holdout))
    if n - problem.n_base < MIN_SAMPLING_DOF:
        raise InputError(f"{data.path}: --posterior nuts on {n} fit point(s) for "
                         f"{problem.n_base} fitted parameter(s): too few data to sample a "
                         f"posterior; allowed: at least {problem.n_base + MIN_SAMPLING_DOF} fit "
                         "points, or --posterior laplace")


def _symmetric(a: np.ndarray) -> np.ndarray:
    return 0.5 * (a + a.T)


def _whitening(cov: np.ndarray) -> np.ndarray:
    """R with R R^T = ``cov``, invertible: the eigenvalues floored at 1e-12 of
    the largest (u then moves z along every direction)."""
    lam, vec = np.linalg.eigh(cov)
    return vec * np.sqrt(np.maximum(lam, 1e-12 * max(float(np.max(lam)), 1e-300)))


def _root(cov: np.ndarray) -> np.ndarray:
    """A matrix square root R (R R^T = cov) of a positive semi-definite ``cov``."""
    lam, vec = np.linalg.eigh(cov)
    return vec * np.sqrt(np.clip(lam, 0.0, None))
