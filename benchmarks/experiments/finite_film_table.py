"""Experiment: size, cost and accuracy of the tabulated finite film
(`DynamicFiniteFilm`) against direct Reynolds solves.

For each L/D, one table of (2 k - 1) eps nodes by 2 m directions is built
(timed: lax.map, one eps node after the other, and batched), and its node
subsets (every second eps node, every second direction) give the smaller
tables k x m, k x 2m, (2k - 1) x m with no further solves.  Each table is
read at random off-node points (eps uniform in [0, 0.95], phi uniform round
the circle) and compared with `reynolds_forces` there: the error |dF| over
|F| and over the envelope E(eps) (the rms of |F| over phi at that eps; the
two differ where the film separates and |F| << E).

    python benchmarks/experiments/finite_film_table.py [--ld 0.25 0.7 1 2]
        [--eps-nodes 21] [--directions 32] [--points 24] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))

import equinox as eqx  # noqa: E402
import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from jax import lax  # noqa: E402

from diffwear.contact.finite_bearing import FiniteBearingFilm, reynolds_forces  # noqa: E402
from diffwear.contact.finite_table import DynamicFiniteFilm  # noqa: E402

MU, R, C = 0.02, 0.010, 20e-6


def subset(table, every_eps, every_dir):
    """The table on every ``every_eps``-th eps node and every ``every_dir``-th
    direction (the envelope recomputed over the kept directions)."""
    raw = table.scaled * jnp.exp(table.log_envelope)[:, None, None]
    raw = raw[::every_eps, ::every_dir]
    env = jnp.sqrt(jnp.mean(jnp.sum(raw**2, axis=-1), axis=1))
    return eqx.tree_at(lambda t: (t.scaled, t.log_envelope, t.log_peak), table,
                       (raw / env[:, None, None], jnp.log(env), table.log_peak[::every_eps]))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ld", type=float, nargs="+", default=[0.25, 0.7, 1.0, 2.0])
    ap.add_argument("--eps-nodes", type=int, default=21)
    ap.add_argument("--directions", type=int, default=32)
    ap.add_argument("--points", type=int, default=24)
    ap.add_argument("--grid", type=int, nargs=2, default=[96, 12], metavar=("N_THETA", "N_Z"),
                    help="the Reynolds grid of film and solves (default 96 12)")
    ap.add_argument("--repeat", action="store_true",
                    help="build the table twice: the second time without compiling")
    ap.add_argument("--batch", type=int, default=0, help="also time lax.map batch_size")
    ap.add_argument("--json")
    args = ap.parse_args()
    rng = np.random.default_rng(1)
    rows = []
    for ld in args.ld:
        n_theta, n_z = args.grid
        film = FiniteBearingFilm(MU, 2 * R * ld, C, n_theta=n_theta, n_z=n_z)
        build = eqx.filter_jit(lambda f, b=None: DynamicFiniteFilm(
            f, R, args.eps_nodes, args.directions, batch_size=b))
        t0, c0 = time.perf_counter(), time.process_time()
        table = jax.block_until_ready(build(film))
        first, first_cpu = time.perf_counter() - t0, time.process_time() - c0
        timing = {"grid": [n_theta, n_z], "first_call_s": first, "first_call_cpu_s": first_cpu,
                  "load": os.getloadavg()[0]}
        if args.repeat:
            t0 = time.perf_counter()
            table = jax.block_until_ready(build(film))
            timing["run_s"] = time.perf_counter() - t0
        if args.batch:
            bb = eqx.filter_jit(lambda f: DynamicFiniteFilm(
                f, R, args.eps_nodes, args.directions, batch_size=args.batch))
            jax.block_until_ready(bb(film))
            t0 = time.perf_counter()
            jax.block_until_ready(bb(film))
            timing["batched_run_s"] = time.perf_counter() - t0
        eps = rng.uniform(0.0, 0.95, args.points)
        phi = rng.uniform(-np.pi, np.pi, args.points)
        xs = jnp.stack([jnp.asarray(eps), jnp.sin(phi), jnp.cos(phi)], axis=1)
        direct = jax.jit(lambda xs: lax.map(
            lambda x: jnp.stack(reynolds_forces(x[0], x[1], x[2], ld, n_theta, n_z)), xs))
        t0, c0 = time.perf_counter(), time.process_time()
        ref = np.asarray(direct(xs))
        timing["direct_solve_s_each"] = (time.perf_counter() - t0) / args.points
        timing["direct_solve_cpu_s_each"] = (time.process_time() - c0) / args.points
        print(f"L/D {ld}: {timing}", flush=True)
        for ke, kd in [(1, 1), (2, 1), (1, 2), (2, 2)]:
            sub = subset(table, ke, kd)
            read = jax.jit(jax.vmap(lambda x, t=sub: jnp.stack(
                t.dimensionless_forces(x[0], x[1], x[2]))))
            got = np.asarray(read(xs))
            env = np.exp(np.asarray(jax.vmap(
                lambda e, t=sub: t.log_envelope[0] * 0 + jnp.log(jnp.sqrt(jnp.mean(jnp.sum(
                    jax.vmap(lambda p: jnp.stack(t.dimensionless_forces(
                        e, jnp.sin(p), jnp.cos(p))))(jnp.linspace(0, 2 * jnp.pi, 64,
                                                                  endpoint=False))**2,
                    axis=-1)))))(jnp.asarray(eps))))
            err = np.linalg.norm(got - ref, axis=1)
            rel_f = err / np.linalg.norm(ref, axis=1)
            rel_e = err / env
            row = {"ld": ld, "n_eccentricity": int(sub.log_envelope.shape[0]),
                   "n_direction": int(sub.scaled.shape[1]),
                   "max_err_over_F": float(rel_f.max()),
                   "p90_err_over_F": float(np.quantile(rel_f, 0.9)),
                   "max_err_over_E": float(rel_e.max()),
                   "worst": [float(eps[rel_f.argmax()]), float(phi[rel_f.argmax()])],
                   **timing}
            rows.append(row)
            print(json.dumps(row), flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
