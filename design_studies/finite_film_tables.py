#!/usr/bin/env python3
"""The shipped tables of the finite film for moving journals
(``src/diffwear/contact/finite_film_tables.npz``, read by
`diffwear.contact.finite_table.ShippedFiniteFilm`).

The dimensionless moving-journal table g(eps, phi) of `DynamicFiniteFilm`
depends only on L/D, the Reynolds grid, the supply groove and the table's top
eps (the scale K = 6 mu R^4 / c^2 aside).  This script builds it once per
L/D node on the default grid (`N_THETA` x `N_Z`, groove on), with
`ECCENTRICITY_NODES` x `DIRECTION_NODES` nodes up to `TOP_ECCENTRICITY_RATIO`,
and stores the stack (log envelope, scaled values, steady peak pressure).

Each L/D node is written to ``--work`` as it is done (a rerun skips the nodes
already there), then the stack to ``--out``:

    python design_studies/finite_film_tables.py [--work DIR] [--out FILE]
    python design_studies/finite_film_tables.py --check [--points 12]

``--check`` reads the shipped tables (`ShippedFiniteFilm`) at the geometric
midpoint between each pair of neighbouring L/D nodes (where the cubic in
log(L/D) is least accurate) and ``--points`` random (eps, phi) there, eps
uniform in [0, 0.998], phi uniform round the circle, against (a) a table
built at that L/D (`DynamicFiniteFilm`, the same eps and phi nodes: the error
of the interpolation in L/D alone) and (b) the direct solve
(`reynolds_forces`): |dF| over |F| and over the envelope E(eps) (the rms of
|F| over phi).

Cost: 425 Reynolds solves per L/D node, about 1-4 min of one CPU core each.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
import numpy as np  # noqa: E402

from diffwear.contact.finite_bearing import N_THETA, N_Z, FiniteBearingFilm  # noqa: E402
from diffwear.contact.finite_table import (  # noqa: E402
    SHIPPED_DIRECTION_NODES,
    SHIPPED_ECCENTRICITY_NODES,
    SHIPPED_RATIOS,
    SHIPPED_TOP,
    DynamicFiniteFilm,
)


def build(ratio: float):
    """The dimensionless table at L/D = ``ratio`` (R = 1, L = 2 ratio; mu = c
    = 1 do not enter g)."""
    film = FiniteBearingFilm(1.0, 2.0 * ratio, 1.0, max_eccentricity_ratio=0.5)
    table = DynamicFiniteFilm(film, 1.0, n_eccentricity=SHIPPED_ECCENTRICITY_NODES,
                              n_direction=SHIPPED_DIRECTION_NODES,
                              top_eccentricity_ratio=SHIPPED_TOP)
    return (np.asarray(table.log_envelope), np.asarray(table.scaled),
            np.asarray(table.log_peak))


def check(points: int, seed: int = 0):
    """The shipped tables against built tables and direct solves at the
    midpoints in L/D (module docstring); prints one row per midpoint and the
    worst and 90th percentile over all."""
    import jax.numpy as jnp

    from diffwear.contact.finite_bearing import reynolds_forces
    from diffwear.contact.finite_table import ShippedFiniteFilm

    rng = np.random.default_rng(seed)
    ratios = np.asarray(SHIPPED_RATIOS)
    rows = []
    for lo, hi in zip(ratios[:-1], ratios[1:], strict=True):
        ratio = float(np.sqrt(lo * hi))
        film = FiniteBearingFilm(1.0, 2.0 * ratio, 1.0, max_eccentricity_ratio=0.5)
        shipped = ShippedFiniteFilm(film, 1.0)
        built = DynamicFiniteFilm(film, 1.0, n_eccentricity=SHIPPED_ECCENTRICITY_NODES,
                                  n_direction=SHIPPED_DIRECTION_NODES,
                                  top_eccentricity_ratio=SHIPPED_TOP)
        eps = rng.uniform(0.0, SHIPPED_TOP, points)
        phi = rng.uniform(-np.pi, np.pi, points)
        for e, p in zip(eps, phi, strict=True):
            a, b = np.sin(p), np.cos(p)
            f_s = np.array(shipped.dimensionless_forces(jnp.asarray(e), a, b))
            f_b = np.array(built.dimensionless_forces(jnp.asarray(e), a, b))
            f_d = np.array(reynolds_forces(e, a, b, ratio))
            ring = [np.array(built.dimensionless_forces(jnp.asarray(e), np.sin(q), np.cos(q)))
                    for q in np.linspace(-np.pi, np.pi, 32, endpoint=False)]
            envelope = np.sqrt(np.mean([r @ r for r in ring]))
            rows.append((ratio, e, p, np.linalg.norm(f_s - f_b) / np.linalg.norm(f_d),
                         np.linalg.norm(f_s - f_d) / np.linalg.norm(f_d),
                         np.linalg.norm(f_s - f_d) / envelope))
        r = np.array([row[3:] for row in rows if row[0] == ratio])
        print(f"L/D {ratio:.4f}: vs built table max {100 * r[:, 0].max():.3f} %, vs direct "
              f"max {100 * r[:, 1].max():.3f} % of |F|, {100 * r[:, 2].max():.3f} % of E",
              flush=True)
    r = np.array([row[3:] for row in rows])
    for name, col in (("vs built table, of |F|", 0), ("vs direct, of |F|", 1),
                      ("vs direct, of E", 2)):
        print(f"{name}: max {100 * r[:, col].max():.3f} %, 90 % "
              f"{100 * np.percentile(r[:, col], 90):.3f} %")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--work", type=Path,
                    default=ROOT / "design_studies/results/finite_film_tables")
    ap.add_argument("--out", type=Path,
                    default=ROOT / "src/diffwear/contact/finite_film_tables.npz")
    ap.add_argument("--only", type=int, nargs="*", help="indices of the L/D nodes to build")
    ap.add_argument("--check", action="store_true", help="measure the shipped tables' accuracy")
    ap.add_argument("--points", type=int, default=12)
    args = ap.parse_args()
    if args.check:
        check(args.points)
        return
    args.work.mkdir(parents=True, exist_ok=True)
    ratios = np.asarray(SHIPPED_RATIOS)
    for i, ratio in enumerate(ratios):
        if args.only is not None and i not in args.only:
            continue
        path = args.work / f"node_{i:02d}.npz"
        if path.exists():
            continue
        t0 = time.process_time()
        w0 = time.perf_counter()
        env, scaled, peak = build(float(ratio))
        np.savez(path, ratio=ratio, log_envelope=env, scaled=scaled, log_peak=peak)
        print(f"L/D {ratio:.4f}: {time.process_time() - t0:.0f} s CPU, "
              f"{time.perf_counter() - w0:.0f} s wall", flush=True)
    if args.only is not None:
        return
    nodes = [np.load(args.work / f"node_{i:02d}.npz") for i in range(len(ratios))]
    np.savez_compressed(
        args.out, length_over_diameter=ratios,
        log_envelope=np.stack([n["log_envelope"] for n in nodes]),
        scaled=np.stack([n["scaled"] for n in nodes]),
        log_peak=np.stack([n["log_peak"] for n in nodes]),
        grid=np.array([N_THETA, N_Z]), top_eccentricity_ratio=np.array(SHIPPED_TOP))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
