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
    python design_studies/finite_film_tables.py --check [--points 8] [--build-every 4]

``--check`` reads the shipped tables (`ShippedFiniteFilm`) at the geometric
midpoint between each pair of neighbouring L/D nodes (where the cubic in
log(L/D) is least accurate) and ``--points`` random (eps, phi) there, eps
uniform in [0, 0.998], phi uniform round the circle, against (a) the direct
solve (`reynolds_forces`): |dF| over |F| and over the envelope E(eps) (the
rms of |F| over phi), and (b) at every ``--build-every``-th midpoint a table
built at that L/D (`DynamicFiniteFilm`, the same eps and phi nodes: the error
of the interpolation in L/D alone).

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


def _midpoint_cases(points: int, seed: int = 0):
    """(L/D, eps, phi) of the check: ``points`` random (eps, phi) at each
    geometric midpoint between neighbouring L/D nodes."""
    rng = np.random.default_rng(seed)
    ratios = np.asarray(SHIPPED_RATIOS)
    mids = np.sqrt(ratios[:-1] * ratios[1:])
    return [(float(m), float(e), float(p)) for m in mids
            for e, p in zip(rng.uniform(0.0, SHIPPED_TOP, points),
                            rng.uniform(-np.pi, np.pi, points), strict=True)]


def direct_solves(points: int, work: Path):
    """The direct solves (`reynolds_forces`) at `_midpoint_cases`, stored in
    ``work`` (they need no table)."""
    import jax.numpy as jnp

    from diffwear.contact.finite_bearing import reynolds_forces

    path = work / f"direct_{points}.npy"
    if path.exists():
        return np.load(path)
    solve = jax.jit(lambda e, a, b, r: jnp.stack(reynolds_forces(e, a, b, r)))
    forces = np.array([solve(e, np.sin(p), np.cos(p), r)
                       for r, e, p in _midpoint_cases(points)])
    np.save(path, forces)
    return forces


def check(points: int, work: Path, build_every: int):
    """The shipped tables against direct solves at the midpoints in L/D and,
    at every ``build_every``-th midpoint, against a table built there
    (module docstring); prints one row per midpoint and the worst and 90th
    percentile over all."""
    import equinox as eqx
    import jax.numpy as jnp

    from diffwear.contact.finite_table import ShippedFiniteFilm

    cases = _midpoint_cases(points)
    direct = direct_solves(points, work)
    read = eqx.filter_jit(lambda t, e, a, b: jnp.stack(t.dimensionless_forces(e, a, b)))
    ring_phi = jnp.linspace(-jnp.pi, jnp.pi, 32, endpoint=False)
    ring = eqx.filter_jit(lambda t, e: jax.vmap(
        lambda q: jnp.stack(t.dimensionless_forces(e, jnp.sin(q), jnp.cos(q))))(ring_phi))
    rows = []
    for k in range(len(SHIPPED_RATIOS) - 1):
        ratio = cases[k * points][0]
        film = FiniteBearingFilm(1.0, 2.0 * ratio, 1.0, max_eccentricity_ratio=0.5)
        shipped = ShippedFiniteFilm(film, 1.0)
        built = None
        if k % build_every == 0:
            built = DynamicFiniteFilm(film, 1.0, n_eccentricity=SHIPPED_ECCENTRICITY_NODES,
                                      n_direction=SHIPPED_DIRECTION_NODES,
                                      top_eccentricity_ratio=SHIPPED_TOP)
        for j in range(points):
            _, e, p = cases[k * points + j]
            a, b = np.sin(p), np.cos(p)
            f_s = np.asarray(read(shipped, e, a, b))
            f_d = direct[k * points + j]
            envelope = float(np.sqrt(np.mean(np.sum(np.asarray(ring(shipped, e)) ** 2, axis=1))))
            vs_built = np.nan
            if built is not None:
                f_b = np.asarray(read(built, e, a, b))
                vs_built = np.linalg.norm(f_s - f_b) / np.linalg.norm(f_d)
            rows.append((ratio, vs_built, np.linalg.norm(f_s - f_d) / np.linalg.norm(f_d),
                         np.linalg.norm(f_s - f_d) / envelope))
        r = np.array([row[1:] for row in rows if row[0] == ratio])
        vs = 100 * np.max(r[:, 0]) if built is not None else np.nan
        print(f"L/D {ratio:.4f}: vs built table max {vs:.3f} %, vs direct max "
              f"{100 * r[:, 1].max():.3f} % of |F|, {100 * r[:, 2].max():.3f} % of E",
              flush=True)
    r = np.array([row[1:] for row in rows])
    for name, col in (("vs built table, of |F|", 0), ("vs direct, of |F|", 1),
                      ("vs direct, of E", 2)):
        print(f"{name}: max {100 * np.nanmax(r[:, col]):.3f} %, 90 % "
              f"{100 * np.nanpercentile(r[:, col], 90):.3f} %")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--work", type=Path,
                    default=ROOT / "design_studies/results/finite_film_tables")
    ap.add_argument("--out", type=Path,
                    default=ROOT / "src/diffwear/contact/finite_film_tables.npz")
    ap.add_argument("--only", type=int, nargs="*", help="indices of the L/D nodes to build")
    ap.add_argument("--check", action="store_true", help="measure the shipped tables' accuracy")
    ap.add_argument("--points", type=int, default=8)
    ap.add_argument("--build-every", type=int, default=4,
                    help="--check: build a table at every n-th midpoint")
    ap.add_argument("--direct-only", action="store_true",
                    help="--check: only the direct solves (stored in --work)")
    args = ap.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    if args.direct_only:
        direct_solves(args.points, args.work)
        return
    if args.check:
        check(args.points, args.work, args.build_every)
        return
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
