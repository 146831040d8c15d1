"""Experiment: what one gradient of a calibration's log posterior costs, with
each wear cycle's intermediate arrays stored for the reverse pass or
recomputed in it.

A sampler asks for the gradient of a scalar, one reverse pass of the
quasi-static model.  Left to itself, JAX's reverse pass through the wear
integration's scan stores, per step, every intermediate the backward pass
reads: about thirty arrays over the cycle's load samples and the bushing's
nodes (the pressures, contact indicators, their derivatives), 180 x 90 each
on a shipped campaign.  Writing and reading them made the gradient 5-6x the
model's value.  `diffwear.models.quasi_static._JointWear.cycle` is a
`jax.checkpoint` that keeps only the pin offsets of each cycle's equilibrium
(named inside the solves' derivative rules, so their iterations are not run
again) and recomputes the rest.  This times, on stored calibration models
(`benchmarks/records/posterior_nuts_models.json`):

* the model's value (the residuals) and one forward-mode derivative;
* the log posterior's gradient as shipped (recomputed), and with the
  cycle's arrays stored (the checkpoint removed), compiled separately;
* the largest difference of the two gradients (they are the same
  derivative; only the work differs).

    python benchmarks/experiments/reverse_pass.py [CAMPAIGN ...] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "benchmarks"))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

jax.config.update("jax_enable_x64", True)

from _record import write_record  # noqa: E402
from posterior_nuts import refit  # noqa: E402

from diffwear.models import quasi_static  # noqa: E402

MODELS = ROOT / "benchmarks" / "records" / "posterior_nuts_models.json"
DEFAULT = ("campaign_pressure_exponent", "campaign_two_lobe_k")


def median_seconds(f, *args, repeats: int) -> float:
    jax.block_until_ready(f(*args))
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(f(*args))
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def gradient(fitter, fit, stored: bool):
    """The compiled gradient of the log posterior; ``stored``: without the
    cycle's checkpoint (every intermediate kept for the reverse pass)."""
    term = quasi_static._JointWear
    kept = term.cycle
    if stored:
        term.cycle = term._cycle
    try:
        g = jax.jit(jax.grad(fitter.log_posterior(fit)))
        z = jnp.asarray(fit.notes["z"], float)
        g(z).block_until_ready()   # traced and compiled with the variant in place
    finally:
        term.cycle = kept
    return g


def one(name: str, model: dict, repeats: int) -> dict:
    fitter, fit = refit(name, model)
    z = jnp.asarray(fit.notes["z"], float)
    lay = fit.notes["layout"]
    tangents = jnp.asarray(lay.tangents)
    outputs = fitter._raw_outputs

    def residuals(z):
        return outputs(tangents.T @ z)[0]

    value = jax.jit(residuals)
    jvp = jax.jit(lambda z: jax.jvp(residuals, (z,), (jnp.ones_like(z),)))
    recomputed, stored = gradient(fitter, fit, False), gradient(fitter, fit, True)
    row = {"campaign": name, "numbers": int(z.shape[0]),
           "value_s": median_seconds(value, z, repeats=repeats),
           "jvp_s": median_seconds(jvp, z, repeats=repeats),
           "gradient_recomputed_s": median_seconds(recomputed, z, repeats=repeats),
           "gradient_stored_s": median_seconds(stored, z, repeats=repeats)}
    g1, g2 = np.asarray(recomputed(z)), np.asarray(stored(z))
    row["gradient_max_relative_difference"] = float(
        np.max(np.abs(g1 - g2)) / max(np.max(np.abs(g2)), 1e-300))
    row["stored_over_recomputed"] = row["gradient_stored_s"] / row["gradient_recomputed_s"]
    row["recomputed_over_value"] = row["gradient_recomputed_s"] / row["value_s"]
    print(f"{name} ({row['numbers']} numbers): value {row['value_s']:.4f} s, "
          f"gradient {row['gradient_recomputed_s']:.4f} s recomputed / "
          f"{row['gradient_stored_s']:.4f} s stored "
          f"({row['stored_over_recomputed']:.2f}x), gradients differ by "
          f"{row['gradient_max_relative_difference']:.1e}", flush=True)
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaigns", nargs="*", default=list(DEFAULT))
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    models = json.loads(MODELS.read_text())
    rows = [one(name, models[name], args.repeats) for name in args.campaigns]
    if args.json:
        write_record(args.json, experiment="reverse_pass", repeats=args.repeats, rows=rows)


if __name__ == "__main__":
    main()
