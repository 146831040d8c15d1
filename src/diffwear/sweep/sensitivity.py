"""Sensitivity and uncertainty of a sweep model at a design point.

`sensitivity(model_fn, params)`: gradients of every output with respect to
every (or the chosen) parameter by AD (``mode="reverse"``, ``jax.jacrev``: one
backward pass per output, and what diffrax's default adjoint supports;
``mode="forward"``, ``jax.jacfwd``: one tangent per parameter, for models
solved with ``adjoint=diffrax.ForwardMode()``), and the
elasticities e = d ln y / d ln p = (p / y) dy/dp: the % change of an output per
% change of a parameter.  `finite_differences` gives the central-difference
gradient for checks; `diffwear.plots.sweep.tornado` draws the elasticities as a
tornado plot.

`propagate_scatter(model_fn, params, "k", scatter=0.5)`: samples one parameter
(by default the Archard wear coefficient) and runs the samples through `sweep`
(vmapped, the same path as any sweep), giving the distribution of the outputs
(and of the wear life, if asked) next to the linearised estimate from the
gradient.  `diffwear.plots.sweep.histogram` plots it.

Scatter of the wear coefficient: repeated pin-on-disc tests of one material
pair scatter by +-40-60 % (Podra & Andersson 1999, "Simulating sliding wear
with finite element method", Tribology International 32: 71-81).  We read that
as a log-normal k with median k0 and 95 % of the tests within
[k0 / (1 + s), k0 (1 + s)], s = 0.5 by default (sigma of ln k =
ln(1 + s) / 1.96): a positive, right-skewed coefficient, as wear coefficients
spanning decades are usually treated.  ``distribution="uniform"`` takes
k0 (1 + U(-s, s)) instead (the literal "+-s").

Caveat (docs, "Which derivatives to trust"): gradients through the adaptive rig evolution are
those of the frozen-step discretisation; at the rig's cycle tolerance 1e-6 they
differ from central differences by up to ~4 % (clearance).  The checks in the
tests use a tightly integrated model.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import InputError
from ..report import Table, markdown
from .result import SweepResult
from .runner import sweep

Z95 = 1.959963984540054  # two-sided 95 % quantile of the standard normal


@dataclass
class Sensitivity:
    """Outputs y and gradients dy/dp at the design point ``params``."""

    params: dict[str, float]
    outputs: dict[str, float]
    gradient: dict[str, dict[str, float]]  # output -> parameter -> dy/dp (SI)
    method: str = "reverse-mode AD"

    @property
    def wrt(self) -> list[str]:
        return list(next(iter(self.gradient.values())))

    def elasticity(self, output: str, param: str) -> float:
        """d ln y / d ln p = (p / y) dy/dp (NaN where y = 0)."""
        y = self.outputs[output]
        return self.params[param] * self.gradient[output][param] / y if y != 0 else math.nan

    def elasticities(self) -> dict[str, dict[str, float]]:
        return {o: {p: self.elasticity(o, p) for p in self.gradient[o]} for o in self.gradient}

    def table(self) -> list[dict]:
        """One row per (output, parameter): value, gradient, elasticity."""
        return [{"output": o, "parameter": p, "p": self.params[p], "y": self.outputs[o],
                 "dy_dp": self.gradient[o][p], "elasticity": self.elasticity(o, p)}
                for o in self.gradient for p in self.gradient[o]]

    def to_csv(self, path) -> Path:
        path = Path(path)
        rows = self.table()
        with path.open("w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            for r in rows:
                w.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in r.items()})
        return path

    def markdown(self, outputs: Sequence[str] | None = None) -> str:
        """Elasticity table: a row per parameter, a column per output."""
        outs = list(outputs or self.gradient)
        return markdown(Table(
            ("parameter", "value (SI)", *(f"d ln {o} / d ln p" for o in outs)),
            [(p, f"{self.params[p]:.4g}", *(f"{self.elasticity(o, p):+.3f}" for o in outs))
             for p in self.wrt], align="l" + "r" * (len(outs) + 1)))


def _split(model_fn, params: Mapping, wrt, outputs):
    known = getattr(model_fn, "param_names", None)
    params = {k: float(v) for k, v in params.items()}
    if known is not None:
        unknown = sorted(set(params) - set(known))
        missing = sorted(set(known) - set(params))
        if unknown or missing:
            raise InputError(f"sensitivity: parameters {unknown or missing} "
                             f"{'unknown' if unknown else 'missing'}; the model takes "
                             f"{list(known)}")
    wrt = list(known if (wrt is None and known is not None) else (wrt or params))
    bad = [w for w in wrt if w not in params]
    if bad:
        raise InputError(f"sensitivity: wrt {bad} not among the parameters {list(params)}")

    def f(x):
        out = model_fn({**params, **x})
        names = outputs or [k for k in out if k != "status"]
        return {k: out[k] for k in names}

    x0 = {k: jnp.asarray(params[k], dtype=jnp.float64) for k in wrt}
    return params, wrt, f, x0


def sensitivity(model_fn: Callable[[dict], dict], params: Mapping, *,
                wrt: Sequence[str] | None = None, outputs: Sequence[str] | None = None,
                mode: str = "reverse") -> Sensitivity:
    """Gradients (AD, ``mode`` "reverse" or "forward") of ``outputs`` (default:
    every output but ``status``) w.r.t. ``wrt`` (default: the model's
    ``param_names``, else every parameter) at ``params``."""
    if mode not in ("reverse", "forward"):
        raise InputError(f"sensitivity: mode {mode!r}; allowed: 'reverse', 'forward'")
    params, wrt, f, x0 = _split(model_fn, params, wrt, outputs)
    jac_fn = jax.jacrev if mode == "reverse" else jax.jacfwd
    y, jac = jax.jit(lambda x: (f(x), jac_fn(f)(x)))(x0)
    return Sensitivity(dict(params), {k: float(v) for k, v in y.items()},
                       {o: {p: float(jac[o][p]) for p in wrt} for o in y},
                       method=f"{mode}-mode AD")


def finite_differences(model_fn: Callable[[dict], dict], params: Mapping, *,
                       wrt: Sequence[str] | None = None, outputs: Sequence[str] | None = None,
                       rel_step: float = 1e-4) -> Sensitivity:
    """Central differences, step ``rel_step x |p|`` per parameter (one jitted
    function, 2 x len(wrt) + 1 evaluations)."""
    params, wrt, f, x0 = _split(model_fn, params, wrt, outputs)
    fj = jax.jit(f)
    y = {k: float(v) for k, v in fj(x0).items()}
    grad: dict[str, dict[str, float]] = {o: {} for o in y}
    for p in wrt:
        h = rel_step * (abs(params[p]) or 1.0)
        up = fj({**x0, p: x0[p] + h})
        dn = fj({**x0, p: x0[p] - h})
        for o in y:
            grad[o][p] = (float(up[o]) - float(dn[o])) / (2 * h)
    return Sensitivity(dict(params), y, grad,
                       method=f"central differences (step {rel_step:g} p)")


# ------------------------------------------------------------------ uncertainty
def sample(p0: float, scatter: float, n: int, *, distribution: str = "lognormal",
           seed: int = 0) -> np.ndarray:
    """``n`` samples around ``p0`` (see the module docstring for the meaning of
    ``scatter``); NumPy's PCG64 generator seeded with ``seed``."""
    if not (0 < scatter < 1 if distribution == "uniform" else scatter > 0):
        raise InputError(f"scatter = {scatter!r}; allowed: > 0 (lognormal), (0, 1) (uniform)")
    if int(n) != n or n < 2:
        raise InputError(f"n = {n!r} samples; allowed: an integer >= 2")
    rng = np.random.default_rng(seed)
    if distribution == "lognormal":
        return p0 * np.exp(rng.normal(0.0, math.log1p(scatter) / Z95, int(n)))
    if distribution == "uniform":
        return p0 * (1 + rng.uniform(-scatter, scatter, int(n)))
    raise InputError(f"distribution {distribution!r}; allowed: 'lognormal', 'uniform'")


def moments(p0: float, scatter: float, distribution: str = "lognormal") -> tuple[float, float]:
    """Exact mean and standard deviation of the sampled parameter."""
    if distribution == "lognormal":
        s2 = (math.log1p(scatter) / Z95) ** 2
        mean = p0 * math.exp(s2 / 2)
        return mean, mean * math.sqrt(math.expm1(s2))
    return p0, p0 * scatter / math.sqrt(3)


@dataclass
class Propagation:
    """Sampled outputs of a scattered parameter, with the linearised estimate."""

    name: str
    p0: float
    scatter: float
    distribution: str
    result: SweepResult                      # the samples' sweep (grid = the samples)
    y0: dict[str, float]
    gradient: dict[str, float]               # dy/dp at p0
    life: dict | None = None                 # wear life, if asked
    stats: dict[str, dict] = field(default_factory=dict)

    def summary(self) -> dict:
        return {"parameter": self.name, "p0": self.p0, "scatter": self.scatter,
                "distribution": self.distribution, "samples": len(self.result),
                "outputs": self.stats}


def _stats(x, mean_lin, std_lin, lin_samples):
    """Sample statistics of ``x``; the linearised estimate with the exact
    moments of the distribution (``*_linear``) and applied to the same samples
    (``*_linear_samples``: free of sampling noise, so the difference to
    mean/std is the model's non-linearity alone)."""
    x = np.asarray(x, dtype=float)
    return {"mean": float(np.mean(x)), "std": float(np.std(x, ddof=1)),
            "p5": float(np.percentile(x, 5)), "p50": float(np.median(x)),
            "p95": float(np.percentile(x, 95)), "mean_linear": float(mean_lin),
            "std_linear": float(std_lin),
            "mean_linear_samples": float(np.mean(lin_samples)),
            "std_linear_samples": float(np.std(lin_samples, ddof=1))}


def propagate_scatter(model_fn: Callable[[dict], dict], params: Mapping, name: str = "k", *,
                      scatter: float = 0.5, distribution: str = "lognormal", n: int = 64,
                      seed: int = 0, chunk_size: int | None = None,
                      outputs: Sequence[str] | None = None,
                      life: tuple[str, float, float] | None = None,
                      mode: str = "reverse") -> Propagation:
    """Sample ``name`` around its value in ``params``, run the samples with
    `sweep`, and compare the output statistics with the linearised estimate
    mean = y0 + g (E[p] - p0), std = |g| std(p) (g = dy/dp at p0 by AD).

    ``life = (output, limit, cycles)``: also the wear life in cycles to reach
    ``output = limit``, assuming the output grows linearly with cycles
    (life = cycles x limit / y; e.g. ("max_depth_mm", 0.5, 21_400)), and its
    linearisation.
    """
    if name not in params:
        raise InputError(f"propagate_scatter: {name!r} is not among the parameters "
                         f"{list(params)}")
    p0 = float(params[name])
    ks = sample(p0, scatter, n, distribution=distribution, seed=seed)
    res = sweep(model_fn, params, {name: ks}, chunk_size=chunk_size)
    sens = sensitivity(model_fn, params, wrt=[name], outputs=outputs, mode=mode)
    outs = outputs or list(sens.outputs)
    mean_p, std_p = moments(p0, scatter, distribution)
    g = {o: sens.gradient[o][name] for o in outs}
    stats = {o: _stats(res[o], sens.outputs[o] + g[o] * (mean_p - p0), abs(g[o]) * std_p,
                       sens.outputs[o] + g[o] * (ks - p0)) for o in outs}
    life_info = None
    if life is not None:
        out, limit, cycles = life
        if out not in outs:
            raise InputError(f"propagate_scatter: life output {out!r} not among {outs}")
        y0 = sens.outputs[out]
        lives = cycles * limit / res[out]
        dl = -cycles * limit / y0 ** 2 * g[out]  # d life / dp at p0
        stats["life_cycles"] = _stats(lives, cycles * limit / y0 + dl * (mean_p - p0),
                                      abs(dl) * std_p, cycles * limit / y0 + dl * (ks - p0))
        life_info = {"output": out, "limit": limit, "cycles": cycles, "samples": lives}
    return Propagation(name, p0, scatter, distribution, res, sens.outputs, g, life_info, stats)


__all__ = ["Sensitivity", "sensitivity", "finite_differences", "sample", "moments",
           "Propagation", "propagate_scatter"]
