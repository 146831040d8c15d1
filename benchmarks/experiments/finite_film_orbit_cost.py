"""Experiment: the cost of one quasi-static lubricated wear evaluation
(`LubricatedQuasiStaticJoint.cycle_wear`: the journal's periodic orbit with
the squeeze film, 180 load samples) on the shipped four-bar's coupler-rocker
joint (four_bar_lubricated.toml), on the short film (the file's ``bearing =
"short"``) and on the finite film from the shipped tables (the file without
``bearing``: `film_law_for` gives the finite film there).  jit-compiled;
the median wall and process CPU time of ``--repeat`` calls after the
compiling one.

    python benchmarks/experiments/finite_film_orbit_cost.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))

import equinox as eqx  # noqa: E402
import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402

from diffwear.choices import SHIPPED_MECHANISMS  # noqa: E402
from diffwear.config.loader import loads as load_text  # noqa: E402
from diffwear.mechanism_file.motion import initial_state  # noqa: E402
from diffwear.mechanism_file.wear import drive_period  # noqa: E402
from diffwear.models import QuasiStatic  # noqa: E402
from diffwear.quasistatic import LubricatedQuasiStaticJoint  # noqa: E402

FILE = SHIPPED_MECHANISMS / "four_bar_lubricated.toml"
JOINT = "coupler_rocker"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    text = FILE.read_text()
    files = {"short": load_text(text, file=FILE.name),
             "finite": load_text(text.replace(', bearing = "short" }', " }"), file=FILE.name)}
    mfile = files["short"]
    loads = QuasiStatic().loads(mfile.mechanism, (JOINT,), initial_state(mfile),
                                drive_period(mfile)).joints[0]

    @eqx.filter_jit
    def wear(joint, depth):
        return joint.cycle_wear(depth, loads)

    for name, f in files.items():
        joint = LubricatedQuasiStaticJoint.from_joint(f.mechanism.element(JOINT))
        depth = jnp.zeros(joint.n)
        t0 = time.perf_counter()
        first = wear(joint, depth)
        jax.block_until_ready(first)
        compile_s = time.perf_counter() - t0
        walls, cpus = [], []
        for _ in range(args.repeat):
            w0, c0 = time.perf_counter(), time.process_time()
            jax.block_until_ready(wear(joint, depth))
            walls.append(time.perf_counter() - w0)
            cpus.append(time.process_time() - c0)
        print(f"{name} ({type(joint.law.film).__name__}): first call {compile_s:.1f} s, then "
              f"median {statistics.median(walls):.3f} s wall, {statistics.median(cpus):.3f} s "
              f"CPU; max depth rate {float(jnp.max(first[0])):.4g}", flush=True)


if __name__ == "__main__":
    main()
