"""Robust bushing design: least material for a life that 90 % of the joints reach.

Wear coefficients of nominally equal tests scatter by about +-50 % (Podra &
Andersson 1999; `diffwear.sweep.sensitivity` reads it as a log-normal k with
median k0 and 95 % of the tests within [k0 / 1.5, 1.5 k0]).  Each bushing
draws its own k.  The deterministic least-material design puts both joints
at the target life T at the median k: half of the mechanisms fail before T.
The robust design asks instead that the weaker joint's life reach T in 90 %
of the mechanisms,

    min V(x)   subject to   P10[ min_j cyc_j(x) k0 / k_j ] >= T,

with d at its lower bound (the least-material argument of
`diffwear.design.optimise`: life hardly depends on d, material grows with it)
and (h1, h2) free.  In the quasi-static model the life scales exactly as
1 / k (the wear rate is linear in k; the equilibrium does not depend on it),
so each step evaluates the lives once at k0 and scales them by a fresh batch
of sampled k: a stochastic gradient (optax Adam) with exact gradients of the
lives.  The constraint enters as a smooth penalty; the answer's percentile is
then re-estimated on a fresh, larger sample (`percentile_of`) with its
sampling error, and `monte_carlo_check` evaluates the model itself at
sampled k (vmap) to confirm it.
"""

from __future__ import annotations

import math
import time

import jax
import jax.numpy as jnp
import numpy as np
import optax

from ..errors import InputError
from ..sweep.sensitivity import Z95
from .optimise import (
    DesignResult,
    bushing_volume,
    compiled,
    from_free,
    jacobian_method,
    life_of,
    to_free,
)
from .two_joint import LOWER, UPPER, TwoJointLife

SCATTER = 0.5        # +-50 % (95 % interval of the log-normal k)
RELIABILITY = 0.9    # the 10th percentile of the weaker joint's life must reach the target
PENALTY = 20.0       # weight of the relative shortfall (an exact L1 penalty) against V / V_start
MARGIN = 1.005       # aim 0.5 % above the target: the sampled percentile is noisy
REACH = 0.95         # a target above this fraction of the best P10 in the box is lowered to it


def log_sigma(scatter: float = SCATTER) -> float:
    """sigma of ln k for a 95 % interval [k0 / (1 + s), k0 (1 + s)]."""
    return math.log1p(scatter) / Z95


def weakest_life(cycles, kappa):
    """min_j cyc_j / kappa_j for each sample row of ``kappa`` (k / k0) [cycles]."""
    return jnp.min(cycles[None, :] / kappa, axis=1)


def percentile_of(cycles, *, reliability: float = RELIABILITY, scatter: float = SCATTER,
                  n: int = 100_000, seed: int = 1) -> dict:
    """The (1 - reliability) quantile of the weaker joint's life over ``n``
    sampled k pairs, with its 95 % interval from the order statistics
    (binomial: ranks n q +- 1.96 sqrt(n q (1 - q)))."""
    rng = np.random.default_rng(seed)
    kappa = np.exp(rng.normal(0.0, log_sigma(scatter), (int(n), 2)))
    life = np.min(np.asarray(cycles)[None, :] / kappa, axis=1)
    return {**_quantile(life, 1.0 - reliability), "samples": int(n),
            "reliability": reliability, "scatter": scatter}


def _quantile(values, q: float) -> dict:
    """The q-quantile of ``values`` and its 95 % interval from the order
    statistics (binomial: ranks n q +- 1.96 sqrt(n q (1 - q)))."""
    v = np.sort(np.asarray(values))
    n = v.size
    half = Z95 * math.sqrt(n * q * (1 - q))
    lo, hi = int(max(0, math.floor(n * q - half))), int(min(n - 1, math.ceil(n * q + half)))
    return {"percentile": float(np.quantile(v, q)), "interval": [float(v[lo]), float(v[hi])]}


def robust_least_material(model: TwoJointLife, target_cycles: float, *,
                          reliability: float = RELIABILITY, scatter: float = SCATTER,
                          batch: int = 1024, steps: int = 80, learning_rate: float = 0.1,
                          seed: int = 0, log=None) -> DesignResult:
    """Least bushing material with the weaker joint's life >= ``target_cycles``
    in ``reliability`` of the mechanisms (module notes), by optax Adam over
    (h1, h2) with d1 = d2 = 20 mm; ``batch`` k pairs sampled per step.  A
    target beyond reach (above `REACH` of the percentile at d = 20 mm,
    h = 50 mm, the longest lives in the box) is lowered to it and both are
    reported (``asked_cycles``, ``target_cycles``)."""
    if jacobian_method(model) != "autodiff":
        raise InputError("robust design needs a model with exact gradients (the quasi-static "
                         "model): its stochastic gradients are autodiff gradients of the lives")
    t = float(target_cycles)
    if not t > 0:
        raise InputError(f"robust design: target life must be > 0 cycles, got {t}")
    life = compiled(model)
    best = percentile_of(life.life(np.concatenate([LOWER[:2], UPPER[2:]])),
                         reliability=reliability, scatter=scatter)["percentile"]
    asked = t
    if t > REACH * best:
        t = float(np.floor(REACH * best / 1000.0) * 1000.0)
    lo, hi = jnp.asarray(LOWER[2:]), jnp.asarray(UPPER[2:])
    d = LOWER[:2]
    h0 = 0.5 * (LOWER[2:] + UPPER[2:])
    v_start = float(bushing_volume(jnp.asarray(np.concatenate([d, h0]))))
    sigma = log_sigma(scatter)
    q = 1.0 - reliability

    def objective(u, cycles, jac, kappa):
        """V / V_start + penalty; cycles and their Jacobian w.r.t. (h1, h2)
        enter linearised at the current point (exact gradient)."""
        h = from_free(u, lo, hi)
        x = jnp.concatenate([jnp.asarray(d), h])
        c = cycles + jac @ (h - jax.lax.stop_gradient(h))
        p = jnp.quantile(weakest_life(c, kappa), q)
        short = jnp.maximum((MARGIN * t - p) / t, 0.0)
        return bushing_volume(x) / v_start + PENALTY * short, p

    grad = jax.jit(jax.value_and_grad(objective, has_aux=True))
    optimiser = optax.adam(optax.cosine_decay_schedule(learning_rate, steps, alpha=0.05))
    u = to_free(jnp.asarray(h0), lo, hi)
    state = optimiser.init(u)
    key = jax.random.PRNGKey(seed)
    history = []
    t0 = time.perf_counter()
    for i in range(steps):
        h = np.asarray(from_free(u, lo, hi))
        x = np.concatenate([d, h])
        cycles, jac = life.value_and_jacobian(x)
        key, sub = jax.random.split(key)
        kappa = jnp.exp(sigma * jax.random.normal(sub, (batch, 2)))
        (value, p), g = grad(u, jnp.asarray(cycles), jnp.asarray(jac[:, 2:]), kappa)
        updates, state = optimiser.update(g, state, u)
        u = optax.apply_updates(u, updates)
        history.append({"x_mm": (x * 1e3).tolist(), "cycles": cycles.tolist(),
                        "percentile": float(p), "objective": float(value)})
        if log is not None and (i % 10 == 0 or i == steps - 1):
            log(f"  step {i + 1}: h = {np.round(h * 1e3, 3).tolist()} mm, P{100 * q:.0f} "
                f"life {float(p):,.0f} (target {t:,.0f})")
    x = np.concatenate([d, np.asarray(from_free(u, lo, hi))])
    cycles = life_of(model, x)
    check = percentile_of(cycles, reliability=reliability, scatter=scatter)
    notes = {"target_cycles": t, "asked_cycles": asked, "best_percentile_in_box": best,
             "reliability": reliability, "k_scatter": scatter,
             "batch": batch, "percentile_check": check, "jacobian_method": "autodiff",
             "optimiser": f"optax adam, {steps} steps, cosine-decayed rate {learning_rate}"}
    return DesignResult("robust least material", x, cycles, steps, steps + 1,
                        time.perf_counter() - t0, history, notes)


def monte_carlo_check(model: TwoJointLife, x, *, n: int = 1000, reliability: float = RELIABILITY,
                      scatter: float = SCATTER, seed: int = 2, chunk: int = 250) -> dict:
    """The weaker joint's life percentile from the model evaluated at ``n``
    sampled (k1, k2) pairs (vmap, in chunks), not from the 1 / k scaling."""
    rng = np.random.default_rng(seed)
    kappa = np.exp(rng.normal(0.0, log_sigma(scatter), (int(n), 2)))
    xj = jnp.asarray(x, dtype=float)
    f = jax.jit(jax.vmap(lambda s: model.evaluate(xj, s).cycles))
    lives = np.concatenate([np.asarray(f(jnp.asarray(kappa[i:i + chunk])))
                            for i in range(0, int(n), chunk)])
    return {**_quantile(lives.min(axis=1), 1.0 - reliability), "samples": int(n),
            "lives_times_k": (lives * kappa).tolist()[:4]}
