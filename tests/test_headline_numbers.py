"""The README's headline results, pinned.  Each number in its table is the
record or stored run it comes from (to the digits printed), and those that
take seconds are recomputed here: a change of the model that moves a
headline number fails until the README, the record and this file agree
again."""

import json
import re
from pathlib import Path

import pytest
from calibration_answers import answer_entry

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
RECORDS = ROOT / "benchmarks" / "records"
AGREEMENT = json.loads((RECORDS / "agreement.json").read_text())
DESIGN = json.loads((ROOT / "design_studies" / "results" / "design_two_joint" /
                     "summary.json").read_text())
CALIBRATION_RESULTS = ROOT / "design_studies" / "calibration" / "results"


def _cell(row_start: str) -> str:
    """The diffwear cell of the README headline row starting with ``row_start``."""
    rows = [line for line in README.splitlines() if line.startswith(f"| {row_start}")]
    assert len(rows) == 1, row_start
    return rows[0].split("|")[2]


def _numbers(text: str) -> list[float]:
    return [float(x.replace(",", "")) for x in re.findall(r"\d[\d,]*(?:\.\d+)?", text)]


def _quasi_static_wear_study(name: str, folder: Path) -> dict:
    """The summary of wear study ``name`` on the quasi-static model (seconds)."""
    from diffwear.io import OutputDir
    from diffwear.models import QuasiStatic
    from diffwear.studies import STUDIES

    return STUDIES[name].run(OutputDir(folder / name), model=QuasiStatic(),
                             log=lambda *a: None)


def test_rig_depth_is_the_record_and_the_quasi_static_model_still_gives_it(tmp_path):
    dynamic, quasi_static = _numbers(_cell("Ch. 7 rig, 21,400 cycles"))
    rig = AGREEMENT["wear_studies"]["rig-21400"]
    assert dynamic == round(rig["dynamic"]["max_wear_depth_mm"], 3)
    assert quasi_static == round(rig["quasi_static"]["max_wear_depth_mm"], 3)
    live = _quasi_static_wear_study("rig-21400", tmp_path)
    assert live["max_wear_depth_mm"] == pytest.approx(rig["quasi_static"]["max_wear_depth_mm"],
                                                      rel=1e-6)
    assert live["wear_volume_mm3"] == pytest.approx(rig["quasi_static"]["wear_volume_mm3"],
                                                    rel=1e-6)


def test_wear_5000_depth_and_volume_are_the_record(tmp_path):
    depth, volume = _numbers(_cell("Ch. 5-6 wear example"))[:2]
    study = AGREEMENT["wear_studies"]["wear-5000"]
    assert depth == round(study["dynamic"]["max_wear_depth_mm"], 3)
    assert volume == round(study["dynamic"]["wear_volume_mm3"])
    live = _quasi_static_wear_study("wear-5000", tmp_path)
    assert live["max_wear_depth_mm"] == pytest.approx(study["quasi_static"]["max_wear_depth_mm"],
                                                      rel=1e-6)


def test_quasi_static_agreement_bound_is_the_records():
    bound = _numbers(_cell("Quasi-static against dynamic model"))[0] / 100
    diffs = [abs(v) for s in AGREEMENT["wear_studies"].values()
             for v in (s["depth_rel_diff"], s["volume_rel_diff"])]
    diffs += [abs(v) for d in AGREEMENT["ch8"]["designs"].values()
              for v in d["rel_diff_to_extrapolated"]]
    assert max(diffs) <= bound < max(diffs) + 0.001


def test_design_row_is_the_stored_run():
    gap_percent, runs, seconds = _numbers(_cell("Ch. 8 equal-life design"))[:3]
    assert gap_percent == round(100 * DESIGN["rel_gap"], 2)
    assert runs == DESIGN["dynamic_runs"]
    assert seconds == pytest.approx(DESIGN["total_wall_time_s"], abs=5.0)


def test_calibration_row_is_the_stored_runs():
    strength, spread, scale, truth, truth_scale, seconds = _numbers(
        _cell("Calibration of a 21,400-cycle campaign"))[:6]
    run = json.loads((CALIBRATION_RESULTS / "campaign_slow_run_in" / "summary.json").read_text())
    run_in = answer_entry(run, "run_in")
    assert strength == round(run_in["strength"], 2)
    assert spread == round(run_in["strength_std"], 2)
    assert scale == round(run_in["shape"], -1)
    assert (truth, truth_scale) == (1.5, 3000.0)
    record = json.loads((RECORDS / "calibration.json").read_text())["cases"]["calibration loop"]
    assert seconds == round(record["run_s"])
    crank = json.loads((CALIBRATION_RESULTS / "campaign_long_crank" / "summary.json").read_text())
    assert "1.5x longer crank" in crank["suspect"] and "1.5x longer crank" in README


@pytest.mark.slow  # ~30 s: the study's meshes and its 100,000 sweeps
def test_pin_pivot_row_is_recomputed(tmp_path):
    from diffwear.io import OutputDir
    from diffwear.studies import pin_pivot

    pin_mm = _numbers(_cell("Ch. 4 pin-pivot"))[0]
    summary = pin_pivot.run(OutputDir(tmp_path / "pp"), sensitivity=False, log=lambda *a: None)
    assert pin_mm == round(summary["max_pin_mm_at_408000_test_cycles"], 2)
