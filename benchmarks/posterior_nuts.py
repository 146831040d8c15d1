"""Does NUTS converge on the shipped campaigns?  The whole calibration loop
of each campaign (`diffwear.calibrate.identify.calibrate`, the quasi-static
model, no dynamic check, no look ahead) chooses its model; NUTS
(`diffwear.calibrate.posterior.nuts`: four chains, the Gauss-Newton
covariance as the mass matrix) then samples that model's numbers.  Recorded
per campaign: the largest rank-normalised split R-hat over the numbers (goal
<= 1.01), the smallest bulk ESS, the divergences and the times.

    python benchmarks/posterior_nuts.py [CAMPAIGN ...] [--json PATH]

Each campaign takes the loop's minutes plus the sampler's; a campaign
already in the record is kept unless named again.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)

from diffwear.calibrate import load_dataset  # noqa: E402
from diffwear.calibrate.fit import Fitter  # noqa: E402
from diffwear.calibrate.identify import calibrate  # noqa: E402
from diffwear.calibrate.posterior import CHAINS, SAMPLES, WARMUP, nuts  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RECORD = HERE / "records" / "posterior_nuts.json"
CAMPAIGNS = ROOT / "design_studies" / "calibration"
DEFAULT = ("campaign_two_lobe_k", "campaign_pressure_exponent", "campaign_run_in_and_creep")
GOAL_R_HAT = 1.01


def one(name: str) -> dict:
    data = load_dataset(CAMPAIGNS / name)
    t0 = time.perf_counter()
    c = calibrate(data, check=False, outlook=None, log=lambda *_: None)
    loop_s = time.perf_counter() - t0
    final = c.final or c.base
    t1 = time.perf_counter()
    post = nuts(Fitter(c.problem), final)
    d = post.diagnostics
    names = list(post.layout.natural(post.z[:1]))
    return {"campaign": name, "model": [*final.effects,
                                        *([f"discrepancy:{final.discrepancy}"]
                                          if final.discrepancy else [])],
            "numbers": len(names), "max_r_hat": d["max_r_hat"], "min_ess": d["min_ess"],
            "r_hat": dict(zip(names, map(float, d["r_hat"]))),
            "divergences": d["divergences"], "draws": d["draws_sampled"],
            "meets_goal": d["max_r_hat"] <= GOAL_R_HAT,
            "loop_s": loop_s, "nuts_s": time.perf_counter() - t1}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaigns", nargs="*", default=list(DEFAULT))
    ap.add_argument("--json", type=Path, default=RECORD)
    args = ap.parse_args(argv)
    record = json.loads(args.json.read_text()) if args.json.is_file() else {}
    rows = {r["campaign"]: r for r in record.get("rows", [])}
    for name in args.campaigns:
        row = one(name)
        rows[name] = row
        print(f"{name}: max R-hat {row['max_r_hat']:.4f} (goal <= {GOAL_R_HAT}), "
              f"min ESS {row['min_ess']:.0f}, {row['divergences']} divergences; "
              f"loop {row['loop_s']:.0f} s, NUTS {row['nuts_s']:.0f} s", flush=True)
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({
            "chains": CHAINS, "warmup": WARMUP, "samples": SAMPLES, "goal_r_hat": GOAL_R_HAT,
            "rows": sorted(rows.values(), key=lambda r: r["campaign"])}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
