"""Does NUTS converge on the shipped campaigns?  Each campaign's model is
the one its calibration loop chose (`diffwear.calibrate.identify.calibrate`,
the quasi-static model, no dynamic check, no look ahead), or, with
``--choose`` / ``--chosen``, the one its shipped calibration chose (dynamic
check included); NUTS (`diffwear.calibrate.posterior.nuts`: four chains, in the
coordinates that whiten the Gauss-Newton covariance) then samples that model's
numbers, its chains running on until every R-hat is at most 1.01 (up to
1,000 draws a chain).  Recorded per campaign: the largest rank-normalised
split R-hat over the numbers (goal <= 1.01), the draws a chain it took, the
smallest bulk ESS, the divergences, the
time of one gradient of the log posterior, each chain's mean and spread
of each number, the times and the device.

    python benchmarks/posterior_nuts.py [CAMPAIGN ...] [--json PATH]
    python benchmarks/posterior_nuts.py [CAMPAIGN ...] --choose MODELS.json
    python benchmarks/posterior_nuts.py [CAMPAIGN ...] --chosen MODELS.json [--json PATH]

The loop takes minutes of each campaign and the sampler an hour of one CPU
core, so the two can run on different machines: ``--choose`` fits the model
each stored calibration (``design_studies/calibration/results``) chose and
writes its effects, discrepancy variable and fitted unknowns; ``--chosen``
refits each from its unknowns (a few steps) and samples it on whatever
device JAX finds (the chains vectorised on an accelerator;
`benchmarks/gpu_nuts.sh`).  A campaign already in the record is kept unless
named again.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

from diffwear.calibrate import load_dataset  # noqa: E402
from diffwear.calibrate.effects import log_shape  # noqa: E402
from diffwear.calibrate.fit import Fitter, Problem  # noqa: E402
from diffwear.calibrate.identify import calibrate  # noqa: E402
from diffwear.calibrate.posterior import (  # noqa: E402
    CHAINS,
    MAX_SAMPLES,
    R_HAT_TARGET,
    SAMPLES,
    WARMUP,
    nuts,
)

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RECORD = HERE / "records" / "posterior_nuts.json"
CAMPAIGNS = ROOT / "design_studies" / "calibration"
RESULTS = CAMPAIGNS / "results"   # the shipped calibrations (`run_all.py`)
DEFAULT = ("campaign_two_lobe_k", "campaign_pressure_exponent", "campaign_run_in_and_creep")
GOAL_R_HAT = R_HAT_TARGET


def model_of(fit) -> dict:
    """The chosen model of a fit, enough to refit it (`refit`)."""
    lay = fit.notes["layout"]
    return {"effects": list(lay.effects), "discrepancy": lay.discrepancy,
            "z": np.asarray(fit.notes["z"], float).tolist(),
            "rows": np.asarray(fit.notes["rows"], bool).tolist(),
            "chi2_fit": fit.chi2_fit, "prior_chi2": fit.prior_chi2}


def choose(name: str) -> dict:
    """The model the shipped calibration of ``name`` chose (the numbers of
    its stored posterior name its effects and discrepancy variable), fitted
    again from the base fit with the stored strengths, shapes and
    discrepancy coefficients (the posterior's means): the model the shipped
    loop chose with its dynamic check, which the loop alone (on the
    quasi-static model) need not choose."""
    stored = json.loads((RESULTS / name / "summary.json").read_text())
    numbers = {k: v["mean"] for k, v in stored["posterior"]["numbers"].items()}
    t0 = time.perf_counter()
    fitter = Fitter(Problem.from_dataset(load_dataset(CAMPAIGNS / name)))
    lib = fitter.library
    effects = tuple(e for e in lib.names if e in numbers)
    discrepancy = next((v for v in lib.variable_names if f"delta_{v}_1" in numbers), None)
    lay = fitter.layout(effects, discrepancy)
    coefficients = None
    if discrepancy is not None:
        size = lib.variable(discrepancy).size
        coefficients = np.array([numbers[f"delta_{discrepancy}_{j + 1}"] for j in range(size)])
    start = dataclasses.replace(fitter.base_fit(), discrepancy=discrepancy,
                                discrepancy_coefficients=coefficients)
    z0 = lay.start(None, {e: numbers[e] for e in effects},
                   {e: log_shape(e, numbers[lib.effect(e).shape.name], lib) for e in lay.shaped},
                   start)
    fit = fitter.fit(effects, discrepancy=discrepancy, z0=z0)
    model = model_of(fit)
    if model["rows"] == (~fitter.problem.holdout).tolist():
        del model["rows"]   # the dataset's own fit points
    return {**model, "chi2_fit_stored": stored["chi2_fit"], "fit_s": time.perf_counter() - t0}


def refit(name: str, model: dict):
    """(fitter, fit) of ``model`` (`model_of`) on campaign ``name``, refitted
    from its unknowns: the same fit, on this machine's arithmetic."""
    fitter = Fitter(Problem.from_dataset(load_dataset(CAMPAIGNS / name)))
    rows = model.get("rows")
    fit = fitter.fit(tuple(model["effects"]), discrepancy=model["discrepancy"],
                     rows=None if rows is None else np.asarray(rows, bool),
                     z0=np.asarray(model["z"], float))
    return fitter, fit


def gradient_seconds(fitter, fit, repeats: int = 5) -> float:
    """Median time of one gradient of the log posterior at the fit (compiled)."""
    grad = jax.jit(jax.grad(fitter.log_posterior(fit)))
    z = jnp.asarray(fit.notes["z"], float)
    grad(z).block_until_ready()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        grad(z).block_until_ready()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def one(name: str, model: dict | None = None, sample: bool = True,
        timed: bool = True) -> dict:
    """``timed``: time one gradient (a compilation of its own)."""
    if model is None:
        data = load_dataset(CAMPAIGNS / name)
        t0 = time.perf_counter()
        c = calibrate(data, check=False, outlook=None, log=lambda *_: None)
        loop_s = time.perf_counter() - t0
        fitter, final = Fitter(c.problem), c.final or c.base
    else:
        loop_s = None   # chosen by the shipped loop (`choose`)
        fitter, final = refit(name, model)
    grad_s = gradient_seconds(fitter, final) if timed else None
    device = {"device": jax.devices()[0].device_kind, "backend": jax.default_backend()}
    chosen = f" (chosen {model['chi2_fit']:.2f})" if model else ""
    timing = f"one gradient {grad_s:.4f} s" if grad_s is not None else "sampling"
    print(f"{name}: fit chi2 {final.chi2_fit:.2f}{chosen}; {timing} on {device['device']}",
          flush=True)
    if not sample:
        return {"campaign": name, "numbers": final.notes["layout"].size,
                "gradient_s": grad_s, **device}
    t1 = time.perf_counter()
    post = nuts(fitter, final, log=lambda line: print(f"{name}: {line}", flush=True))
    d = post.diagnostics
    names = list(post.layout.natural(post.z[:1]))
    return {"campaign": name, "model": [*final.effects,
                                        *([f"discrepancy:{final.discrepancy}"]
                                          if final.discrepancy else [])],
            "chi2_fit": final.chi2_fit,
            **({"chi2_fit_chosen": model["chi2_fit"]} if model else {}),
            "numbers": len(names), "max_r_hat": d["max_r_hat"], "min_ess": d["min_ess"],
            "r_hat": dict(zip(names, map(float, d["r_hat"]))),
            "chain_mean": dict(zip(names, np.asarray(d["chain_mean"]).T.tolist())),
            "chain_std": dict(zip(names, np.asarray(d["chain_std"]).T.tolist())),
            "divergences": d["divergences"], "draws": d["draws_sampled"],
            "draws_per_chain": d["draws_per_chain"],
            "meets_goal": d["max_r_hat"] <= GOAL_R_HAT,
            "loop_s": loop_s, "gradient_s": grad_s, "nuts_s": time.perf_counter() - t1,
            **device}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaigns", nargs="*", default=list(DEFAULT))
    ap.add_argument("--json", type=Path, default=RECORD)
    ap.add_argument("--choose", type=Path, help="write the chosen models here; no sampling")
    ap.add_argument("--chosen", type=Path, help="sample the models written by --choose")
    ap.add_argument("--gradient-only", action="store_true",
                    help="time one gradient of the log posterior; no sampling")
    args = ap.parse_args(argv)
    if args.choose:
        chosen = json.loads(args.choose.read_text()) if args.choose.is_file() else {}
        for name in args.campaigns:
            chosen[name] = choose(name)
            m = chosen[name]
            print(f"{name}: {m['effects']} + {m['discrepancy']}, chi2 {m['chi2_fit']:.2f} "
                  f"(stored {m['chi2_fit_stored']:.2f}), {m['fit_s']:.0f} s", flush=True)
            args.choose.write_text(json.dumps(chosen, indent=1) + "\n")
        return 0
    models = json.loads(args.chosen.read_text()) if args.chosen else {}
    record = json.loads(args.json.read_text()) if args.json.is_file() else {}
    rows = {r["campaign"]: r for r in record.get("rows", [])}
    for i, name in enumerate(args.campaigns):
        row = one(name, models[name] if args.chosen else None, not args.gradient_only,
                  timed=i == 0 or not args.chosen)
        rows[name] = row
        if args.gradient_only:
            args.json.write_text(json.dumps({"rows": list(rows.values())}, indent=2) + "\n")
            continue
        print(f"{name}: max R-hat {row['max_r_hat']:.4f} (goal <= {GOAL_R_HAT}) after "
              f"{row['draws_per_chain']} draws a chain, "
              f"min ESS {row['min_ess']:.0f}, {row['divergences']} divergences; "
              f"NUTS {row['nuts_s']:.0f} s "
              f"on {row['device']}", flush=True)
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({
            **{k: v for k, v in record.items() if k not in ("rows", "max_samples")},
            "chains": CHAINS, "warmup": WARMUP, "samples": SAMPLES,
            "max_samples": MAX_SAMPLES, "goal_r_hat": GOAL_R_HAT,
            "rows": sorted(rows.values(), key=lambda r: r["campaign"])}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
