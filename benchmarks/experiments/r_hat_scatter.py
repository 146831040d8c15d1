"""Experiment: how far above 1 does R-hat scatter when the chains sample the
target exactly?

`diffwear.calibrate.posterior.nuts_chains` (the calibration's sampler: four
chains, 150 warm-up steps each, in whitened coordinates) is run on a
d-dimensional unit Gaussian, the posterior a calibration's sampler sees when
the Gauss-Newton covariance is exact, from many seeds.  Recorded for each
number of draws per chain: the median, the 90th percentile and the largest
of the largest rank-normalised split R-hat over the d numbers (Vehtari et al.
2021, blackjax's `rhat`), the share of seeds above 1.01, and the median of
the smallest bulk ESS.  Any share above 0 is the statistic's own scatter:
the chains are exact by construction.  With ``--until`` the chains run as
the calibration runs them, on from where they stopped by the given draws
at a time until every R-hat is at most 1.01 (`posterior.R_HAT_TARGET`, up
to `posterior.MAX_SAMPLES` a chain); recorded besides: the draws a chain
they took, and the spread of the pooled draws (1 if the stopping rule does
not bias them).

    python benchmarks/experiments/r_hat_scatter.py [--dims 2] [--samples 250 1000]
        [--until] [--seeds 40] [--json out.json]
"""

from __future__ import annotations

import argparse
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

from _record import write_record  # noqa: E402
from blackjax.diagnostics import ess_bulk, rhat  # noqa: E402

from diffwear.calibrate.posterior import (  # noqa: E402
    CHAINS,
    MAX_SAMPLES,
    R_HAT_TARGET,
    WARMUP,
    nuts_chains,
)

GOAL = 1.01


def scatter(dims: int, samples: int, seeds: int, until: bool = False) -> dict:
    """R-hat and ESS of ``seeds`` runs of the sampler on the unit Gaussian
    (``until``: the chains extended until R-hat meets its target)."""
    def log_density(z):
        return -0.5 * jnp.sum(z ** 2)

    r_hat, ess, per_chain, spread = [], [], [], []
    t0 = time.perf_counter()
    for seed in range(seeds):
        z, _ = nuts_chains(log_density, np.zeros(dims), np.eye(dims), CHAINS, WARMUP,
                           samples, seed, parallel=True,
                           r_hat_target=R_HAT_TARGET if until else None)
        per_chain.append(z.shape[1])
        spread.append(float(np.mean(z.reshape(-1, dims).std(axis=0))))
        r_hat.append(max(float(rhat(jnp.asarray(z[..., i]))) for i in range(dims)))
        ess.append(min(float(ess_bulk(jnp.asarray(z[..., i]))) for i in range(dims)))
    r = np.asarray(r_hat)
    n = np.asarray(per_chain)
    return {"dims": dims, "chains": CHAINS, "warmup": WARMUP, "samples": samples,
            "until_r_hat": R_HAT_TARGET if until else None,
            "max_samples": MAX_SAMPLES if until else samples,
            "draws_per_chain_median": float(np.median(n)), "draws_per_chain_largest": int(n.max()),
            "share_extended": float(np.mean(n > samples)),
            "pooled_spread_median": float(np.median(spread)),
            "seeds": seeds, "max_r_hat_median": float(np.median(r)),
            "max_r_hat_q90": float(np.quantile(r, 0.9)), "max_r_hat_largest": float(r.max()),
            "share_above_goal": float(np.mean(r > GOAL)),
            "min_ess_median": float(np.median(ess)), "seconds": time.perf_counter() - t0}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dims", type=int, nargs="+", default=[2])
    ap.add_argument("--samples", type=int, nargs="+", default=[250, 1000])
    ap.add_argument("--seeds", type=int, default=40)
    ap.add_argument("--until", action="store_true",
                    help="extend the chains until R-hat meets its target, as the calibration does")
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    rows = []
    for d in args.dims:
        for n in args.samples:
            row = scatter(d, n, args.seeds, args.until)
            rows.append(row)
            print(f"d {d}, {n} draws a chain, {args.seeds} seeds: max R-hat median "
                  f"{row['max_r_hat_median']:.4f}, 90 % {row['max_r_hat_q90']:.4f}, largest "
                  f"{row['max_r_hat_largest']:.4f}; above {GOAL}: {row['share_above_goal']:.0%}; "
                  f"min ESS median {row['min_ess_median']:.0f}; draws a chain median "
                  f"{row['draws_per_chain_median']:.0f}, largest {row['draws_per_chain_largest']}"
                  f" ({row['seconds']:.0f} s)",
                  flush=True)
    if args.json:
        write_record(args.json, experiment="r_hat_scatter", goal=GOAL, rows=rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
