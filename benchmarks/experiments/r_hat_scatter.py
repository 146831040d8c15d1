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
the chains are exact by construction.

    python benchmarks/experiments/r_hat_scatter.py [--dims 2] [--samples 250 1000]
        [--seeds 40] [--json out.json]
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

from diffwear.calibrate.posterior import CHAINS, WARMUP, nuts_chains  # noqa: E402

GOAL = 1.01


def scatter(dims: int, samples: int, seeds: int) -> dict:
    """R-hat and ESS of ``seeds`` runs of the sampler on the unit Gaussian."""
    def log_density(z):
        return -0.5 * jnp.sum(z ** 2)

    r_hat, ess = [], []
    t0 = time.perf_counter()
    for seed in range(seeds):
        z, _ = nuts_chains(log_density, np.zeros(dims), np.eye(dims), CHAINS, WARMUP,
                           samples, seed, parallel=True)
        r_hat.append(max(float(rhat(jnp.asarray(z[..., i]))) for i in range(dims)))
        ess.append(min(float(ess_bulk(jnp.asarray(z[..., i]))) for i in range(dims)))
    r = np.asarray(r_hat)
    return {"dims": dims, "chains": CHAINS, "warmup": WARMUP, "samples": samples,
            "seeds": seeds, "max_r_hat_median": float(np.median(r)),
            "max_r_hat_q90": float(np.quantile(r, 0.9)), "max_r_hat_largest": float(r.max()),
            "share_above_goal": float(np.mean(r > GOAL)),
            "min_ess_median": float(np.median(ess)), "seconds": time.perf_counter() - t0}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dims", type=int, nargs="+", default=[2])
    ap.add_argument("--samples", type=int, nargs="+", default=[250, 1000])
    ap.add_argument("--seeds", type=int, default=40)
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    rows = []
    for d in args.dims:
        for n in args.samples:
            row = scatter(d, n, args.seeds)
            rows.append(row)
            print(f"d {d}, {n} draws a chain, {args.seeds} seeds: max R-hat median "
                  f"{row['max_r_hat_median']:.4f}, 90 % {row['max_r_hat_q90']:.4f}, largest "
                  f"{row['max_r_hat_largest']:.4f}; above {GOAL}: {row['share_above_goal']:.0%}; "
                  f"min ESS median {row['min_ess_median']:.0f} ({row['seconds']:.0f} s)",
                  flush=True)
    if args.json:
        write_record(args.json, experiment="r_hat_scatter", goal=GOAL, rows=rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
