"""The ``diffwear`` command line, called in-process through `diffwear.cli.main`.

One end-to-end run of the default study is shared by the tests (it is
compile-bound: about 30 s of CPU whatever the simulated duration).
"""

import csv
import json

import pytest

from diffwear.cli import main

STUDY = "ideal-slider-crank"


@pytest.fixture(scope="module")
def study_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "isc"
    assert main(["study", STUDY, "--out", str(out), "--quiet"]) == 0
    return out


def _header(path):
    with open(path, newline="") as f:
        return next(csv.reader(f))


def test_list(capsys):
    assert main(["study", "--list"]) == 0
    out = capsys.readouterr().out
    assert STUDY in out.split()


def test_study_writes_summary_tables_and_figures(study_dir):
    summary = json.loads((study_dir / "summary.json").read_text())
    for key in ("max_constraint_violation", "max_joint_force_N", "wall_time_s"):
        assert isinstance(summary[key], float), key
    assert 0.0 <= summary["max_constraint_violation"] < 1e-6  # m
    assert summary["max_joint_force_N"] > 0.0
    assert summary["wall_time_s"] > 0.0
    assert _header(study_dir / "reaction_crank_rod.csv") == ["t_s", "crank_angle_rad", "fx_N", "fy_N"]
    assert _header(study_dir / "crank_com.csv") == [
        "t_s", "x_m", "y_m", "vx_m_s", "vy_m_s", "ax_m_s2", "ay_m_s2"]
    pngs = [name for name in summary["files"] if name.endswith(".png")]
    assert len(pngs) >= 5
    for name in pngs:
        assert (study_dir / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    for name in summary["files"]:
        assert (study_dir / name).is_file(), name
    assert (study_dir / "report.md").read_text().startswith(f"# {STUDY}")


def test_second_run_refuses_to_overwrite(study_dir, capsys):
    before = (study_dir / "summary.json").read_bytes()
    assert main(["study", STUDY, "--out", str(study_dir), "--quiet"]) == 2
    assert "already holds results" in capsys.readouterr().err
    assert (study_dir / "summary.json").read_bytes() == before


def test_unknown_study(tmp_path, capsys):
    assert main(["study", "no-such-study", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert "unknown study 'no-such-study'" in err and STUDY in err
    assert not (tmp_path / "x").exists()


def test_missing_out(capsys):
    assert main(["study", STUDY]) == 2
    assert "--out" in capsys.readouterr().err


def test_bad_option_exits_2(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["study", "--no-such-option"])
    assert exc.value.code == 2
    assert "unrecognized arguments" in capsys.readouterr().err
