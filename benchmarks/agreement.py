#!/usr/bin/env python3
"""The quasi-static wear model against the dynamic one (the reference).

    python benchmarks/agreement.py [--quick] [--json PATH]

Runs both models on the thesis's wear problems and prints a markdown table;
the JSON (default ``benchmarks/records/agreement.json``) is what the docs'
agreement table quotes:

* rig-21400 (thesis Ch. 7) and wear-5000 (Ch. 5/6): max wear depth, worn
  volume and, for wear-5000, the largest profile difference (the studies'
  own runs, default settings, the dynamic cycles on Tsit5 at rtol 1e-6);
* Ch. 8 two-joint lives at the Table 8-3 box centre, the Table 8-4 design and
  the four (d, h) corners of the box (both joints at the same corner).  The
  dynamic lives converge slowly in their number of wear steps (first order:
  the constant-A bookkeeping within a step), so they are computed at 20 and 40
  steps and extrapolated (Richardson, first order: 2 L40 - L20); the
  quasi-static lives are converged (40 steps; 80 moves them by < 0.2 %).

``--quick``: the rig and Table 8-4 only, dynamic at 10 and 20 steps (minutes).
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT / "src") not in sys.path:
    sys.path.insert(0, str(ROOT / "src"))

DEFAULT_JSON = ROOT / "benchmarks" / "records" / "agreement.json"


def _study(name: str, model: str, tmp: Path) -> tuple[dict, list[float]]:
    from diffwear.io import OutputDir
    from diffwear.studies import rig_21400, wear_5000

    run = {"rig-21400": rig_21400.run, "wear-5000": wear_5000.run}[name]
    out = OutputDir(tmp / f"{name}-{model}", overwrite=True)
    # the dynamic reference on the explicit integrator at rtol 1e-6, whatever
    # integrator the study itself defaults to
    kw = {"integrator": "tsit5"} if model == "dynamic" else {}
    summary = run(out, model=model, log=lambda *a, **k: None, **kw)
    with open(Path(out.path) / "wear_profile.csv") as f:
        depth = [float(r["depth_mm"]) for r in csv.DictReader(f)]
    return summary, depth


def wear_studies(names) -> dict:
    import numpy as np

    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            (dyn, h_dyn), (qs, h_qs) = (_study(name, m, Path(tmp))
                                        for m in ("dynamic", "quasi-static"))
            h_dyn, h_qs = np.asarray(h_dyn), np.asarray(h_qs)
            if h_dyn.size != h_qs.size:  # compare on the coarser grid
                n = min(h_dyn.size, h_qs.size)
                h_dyn, h_qs = h_dyn[:: h_dyn.size // n], h_qs[:: h_qs.size // n]
            rows[name] = {
                "dynamic": {k: dyn[k] for k in ("max_wear_depth_mm", "wear_volume_mm3",
                                                "wall_time_s")},
                "quasi_static": {k: qs[k] for k in ("max_wear_depth_mm", "wear_volume_mm3",
                                                    "wall_time_s", "contact_margin",
                                                    "contact_margin_worn")},
                "depth_rel_diff": qs["max_wear_depth_mm"] / dyn["max_wear_depth_mm"] - 1,
                "volume_rel_diff": qs["wear_volume_mm3"] / dyn["wear_volume_mm3"] - 1,
                "profile_max_diff_of_peak": float(np.max(np.abs(h_qs - h_dyn)) / h_dyn.max()),
            }
    return rows


def ch8_lives(quick: bool) -> dict:
    import numpy as np

    from diffwear.design import TwoJointLife
    from diffwear.design.two_joint import LOWER, TABLE_8_4, UPPER
    from diffwear.models import Dynamic, QuasiStatic

    designs = {"Table 8-4": TABLE_8_4}
    if not quick:
        designs["box centre"] = 0.5 * (LOWER + UPPER)
        for d in (LOWER[0], UPPER[0]):
            for h in (LOWER[2], UPPER[2]):
                designs[f"d {d * 1e3:.0f} mm, h {h * 1e3:.0f} mm"] = np.array([d, d, h, h])
    coarse, fine = (10, 20) if quick else (20, 40)
    qs = TwoJointLife().prepared()
    dyn = {s: TwoJointLife(wear_model=Dynamic(steps=s)) for s in (coarse, fine)}
    rows = {}
    for name, x in designs.items():
        t0 = time.perf_counter()
        lq = qs.life(x)
        t_qs = time.perf_counter() - t0
        ld = {s: m.life(x) for s, m in dyn.items()}
        extrapolated = 2 * ld[fine] - ld[coarse]
        rows[name] = {"x_mm": (np.asarray(x) * 1e3).tolist(), "quasi_static": lq.tolist(),
                      f"dynamic_{coarse}": ld[coarse].tolist(),
                      f"dynamic_{fine}": ld[fine].tolist(),
                      "dynamic_extrapolated": extrapolated.tolist(),
                      "rel_diff_to_extrapolated": (lq / extrapolated - 1).tolist(),
                      f"rel_diff_to_dynamic_{fine}": (lq / ld[fine] - 1).tolist(),
                      "quasi_static_s": t_qs}
        print(f"  {name}: qs {np.round(lq).tolist()}, dynamic {np.round(ld[fine]).tolist()} "
              f"({fine} steps), extrapolated {np.round(extrapolated).tolist()}", flush=True)
    return {"steps": [coarse, fine], "designs": rows,
            "quasi_static_settings": {"steps": QuasiStatic().steps,
                                      "samples": QuasiStatic().samples}}


def markdown(result: dict) -> str:
    """The agreement table (also the docs' "Quasi-static against dynamic" page)."""
    def pct(x):
        return f"{100 * x:+.2f} %"

    lines = ["| problem | quantity | dynamic | quasi-static | difference |",
             "|---|---|---:|---:|---:|"]
    for name, r in result["wear_studies"].items():
        for key, label in (("max_wear_depth_mm", "max depth [mm]"),
                           ("wear_volume_mm3", "volume [mm^3]")):
            d, q = r["dynamic"][key], r["quasi_static"][key]
            lines.append(f"| {name} | {label} | {d:.4g} | {q:.4g} | {pct(q / d - 1)} |")
        lines.append(f"| {name} | profile: largest difference / peak | | | "
                     f"{100 * r['profile_max_diff_of_peak']:.2f} % |")
    for name, r in result["ch8"]["designs"].items():
        for j in (0, 1):
            d, q = r["dynamic_extrapolated"][j], r["quasi_static"][j]
            lines.append(f"| Ch. 8, {name} | life, joint {j + 1} [cycles] | {d:,.0f} | "
                         f"{q:,.0f} | {pct(q / d - 1)} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--json", type=Path, default=DEFAULT_JSON)
    args = ap.parse_args(argv)
    import jax

    jax.config.update("jax_enable_x64", True)
    t0 = time.perf_counter()
    result = {"wear_studies": wear_studies(["rig-21400"] if args.quick
                                           else ["rig-21400", "wear-5000"]),
              "ch8": ch8_lives(args.quick), "quick": args.quick}
    result["wall_time_s"] = time.perf_counter() - t0
    print(markdown(result))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=1))
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
