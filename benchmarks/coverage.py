"""Do the calibration's 90 % predictive bands cover 90 % of what they claim?
The study is `diffwear.calibrate.coverage` (its notes say how); this prints
and records it.

    python benchmarks/coverage.py [--campaigns 20] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)

from diffwear.calibrate.coverage import GOAL, run  # noqa: E402

HERE = Path(__file__).resolve().parent
RECORD = HERE / "records" / "calibration_coverage.json"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--campaigns", type=int, default=20)
    ap.add_argument("--json", type=Path, default=RECORD)
    args = ap.parse_args(argv)
    result = run(args.campaigns, log=lambda m: print(m, file=sys.stderr, flush=True))
    print(f"pooled held-out coverage of the 90 % bands: "
          f"{result['pooled_heldout_coverage']:.3f} over {args.campaigns} campaigns "
          f"(goal {GOAL[0]}-{GOAL[1]}); "
          f"median per campaign {result['median_campaign_coverage']:.3f}")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
