"""The ``diffwear`` command line, called in-process through `diffwear.cli.main`.

One end-to-end run of the default study is shared by the tests (it is
compile-bound: about 30 s of CPU whatever the simulated duration).
"""

import csv
import json
from pathlib import Path

import pytest

from diffwear.choices import SHIPPED_MECHANISMS
from diffwear.cli import main

# summary.json keeps a status as its `RESULTS` member's code
OK = "ok"  # a summary names the status
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
    assert _header(study_dir / "reaction_crank_rod.csv") == [
        "t_s", "crank_angle_rad", "fx_N", "fy_N"]
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


WEAR = "wear-5000"


def _run_interrupted(out, args=("study", WEAR, "--cycles", "3")) -> int:
    """``diffwear ARGS --out OUT --quiet`` (default: a 3-cycle wear-5000 run)
    with Ctrl-C pressed right after its first checkpoint was saved; its exit
    code."""
    from diffwear.models import execution as common

    real = common.save_checkpoint

    def save_then_interrupt(*args, **kwargs):
        real(*args, **kwargs)
        raise KeyboardInterrupt

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(common, "save_checkpoint", save_then_interrupt)
        return main([*args, "--out", str(out), "--quiet"])


@pytest.fixture(scope="module")
def interrupted_dir(tmp_path_factory):
    """A 3-cycle wear-5000 run (A = 1, 1 slot per chunk) interrupted (Ctrl-C)
    right after its first checkpoint was saved."""
    import numpy as np

    out = tmp_path_factory.mktemp("wear") / "run"
    assert _run_interrupted(out) == 130  # Ctrl-C: exit 130
    assert not (out / "summary.json").exists()
    assert not (out / ".diffwear-lock").exists()
    with np.load(out / "checkpoint.npz") as z:
        assert float(z["state.n"]) == 1.0
    return out


def _copy(src, dst):
    import shutil

    shutil.copytree(src, dst)
    return dst


def test_resume_finishes_an_interrupted_wear_study(interrupted_dir, tmp_path):
    out = _copy(interrupted_dir, tmp_path / "run")
    assert main(["study", WEAR, "--cycles", "3", "--resume", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["finished"] is True and summary["resumed_from_cycles"] == 1.0
    assert summary["cycles"] == 3.0 and summary["dynamic_cycles_simulated"] == 1 + 3
    assert summary["status"] == OK and (out / "checkpoint.npz").is_file()
    assert "checkpoint.npz" in summary["files"]
    assert not list(out.glob(".*.partial"))
    rows = (out / "wear_history.csv").read_text().splitlines()
    assert len(rows) == 1 + 1 + 3  # header, cycle 0, three cycles (one before the cut)
    # a finished run is not resumed again
    assert main(["study", WEAR, "--cycles", "3", "--resume", str(out), "--quiet"]) == 2


def test_resume_reads_its_options_from_the_checkpoint(interrupted_dir, tmp_path):
    out = _copy(interrupted_dir, tmp_path / "run")
    assert main(["study", WEAR, "--resume", str(out), "--quiet"]) == 0  # no --cycles
    summary = json.loads((out / "summary.json").read_text())
    assert summary["cycles"] == 3.0 and summary["resumed_from_cycles"] == 1.0


def test_plain_rerun_on_an_interrupted_folder_refuses(interrupted_dir, tmp_path, capsys):
    out = _copy(interrupted_dir, tmp_path / "run")
    before = (out / "checkpoint.npz").read_bytes()
    assert main(["study", WEAR, "--cycles", "3", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "interrupted run" in err and f"--resume {out}" in err and "--overwrite" in err
    assert (out / "checkpoint.npz").read_bytes() == before


def test_ctrl_c_says_where_the_checkpoint_is(tmp_path, capsys):
    out = tmp_path / "run"
    assert _run_interrupted(out) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in err[0]
    assert f"diffwear study {WEAR} --resume {out}" in err[0]
    assert str(out / "checkpoint.npz") in err[0]


def test_ctrl_c_before_any_result_leaves_no_empty_folder(tmp_path, capsys, monkeypatch):
    from diffwear.studies import STUDIES

    def interrupt(out, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(STUDIES[STUDY], "run", interrupt)
    out = tmp_path / "never"
    assert main(["study", STUDY, "--out", str(out), "--quiet"]) == 130
    assert "no results were written" in capsys.readouterr().err
    assert not out.exists()


def test_out_folder_that_cannot_be_created_is_refused_before_computing(tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    assert main(["study", STUDY, "--out", str(blocker / "sub"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "cannot create the folder" in err and "Traceback" not in err


def test_a_second_run_on_a_locked_folder_is_refused(tmp_path, capsys):
    out = tmp_path / "busy"
    out.mkdir()
    (out / ".diffwear-lock").write_text("1\n")  # process 1 is alive
    assert main(["study", STUDY, "--out", str(out), "--quiet"]) == 2
    assert "another diffwear run (process 1)" in capsys.readouterr().err
    # a lock left by a process that no longer runs is taken over
    (out / ".diffwear-lock").write_text("999999999\n")
    from diffwear.io import OutputDir, release_all

    OutputDir(out)
    assert (out / ".diffwear-lock").read_text().strip() != "999999999"
    release_all()
    assert not (out / ".diffwear-lock").exists()


def test_resume_with_other_options_exits_2_naming_the_key(interrupted_dir, tmp_path, capsys):
    out = _copy(interrupted_dir, tmp_path / "run")
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert main(["study", WEAR, "--cycles", "4", "--resume", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "cycles = 3.0" in err and "cycles = 4.0" in err
    # refused: the folder byte for byte as it was (no manifest, lock or mark added)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_integrator_option_is_checked(interrupted_dir, tmp_path, capsys):
    """--integrator: a resumed run keeps the integrator it started with, the
    quasi-static model has none, and a study without dynamic cycles takes none."""
    out = _copy(interrupted_dir, tmp_path / "run")
    assert main(["study", WEAR, "--integrator", "rodas4", "--resume", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "integrator = 'tsit5'" in err and "integrator = 'rodas4'" in err
    assert main(["study", WEAR, "--model", "quasi-static", "--integrator", "rodas4", "--out",
                 str(tmp_path / "qs"), "--quiet"]) == 2
    assert "--integrator rodas4 belongs to the dynamic model" in capsys.readouterr().err
    assert main(["study", STUDY, "--integrator", "rodas4", "--out", str(tmp_path / "x")]) == 2
    assert "does not take --integrator" in capsys.readouterr().err
    assert not (tmp_path / "qs").exists() and not (tmp_path / "x").exists()


def test_a_checkpoint_without_an_integrator_resumes_on_tsit5(interrupted_dir, tmp_path):
    """Checkpoints written before the integrator was recorded ran on Tsit5:
    --resume reads them so, whatever the study's own integrator is now."""
    import argparse

    from diffwear.cli.command import _options_from_checkpoint
    from diffwear.models.execution import load_checkpoint, save_checkpoint

    out = _copy(interrupted_dir, tmp_path / "run")
    ckpt, meta = load_checkpoint(out / "checkpoint.npz")
    del meta["integrator"]
    save_checkpoint(out / "checkpoint.npz", ckpt, meta)
    names = ("cycles", "method", "contact", "model", "integrator")
    args = argparse.Namespace(resume=str(out), **dict.fromkeys(names))
    _options_from_checkpoint(args)
    assert args.integrator == "tsit5" and args.cycles == 3
    args = argparse.Namespace(resume=str(out), **dict.fromkeys(names))
    args.integrator = "rodas4"  # given explicitly: kept, the study then checks it
    _options_from_checkpoint(args)
    assert args.integrator == "rodas4"


def test_resume_needs_a_checkpoint_and_a_wear_study(tmp_path, capsys):
    assert main(["study", WEAR, "--resume", str(tmp_path), "--quiet"]) == 2
    assert "no checkpoint.npz" in capsys.readouterr().err
    assert main(["study", STUDY, "--resume", str(tmp_path), "--quiet"]) == 2
    assert "does not take --resume" in capsys.readouterr().err
    assert main(["study", WEAR, "--resume", str(tmp_path), "--out", str(tmp_path / "x")]) == 2
    assert "same folder" in capsys.readouterr().err


@pytest.mark.slow
def test_resumed_wear_study_equals_uninterrupted(interrupted_dir, tmp_path):
    import numpy as np

    out = _copy(interrupted_dir, tmp_path / "resumed")
    assert main(["study", WEAR, "--cycles", "3", "--resume", str(out), "--quiet"]) == 0
    ref = tmp_path / "ref"
    assert main(["study", WEAR, "--cycles", "3", "--out", str(ref), "--quiet"]) == 0
    for name in ("wear_profile.csv", "wear_history.csv", "joint_force_last_cycle.csv"):
        np.testing.assert_allclose(np.loadtxt(out / name, delimiter=",", skiprows=1),
                                   np.loadtxt(ref / name, delimiter=",", skiprows=1),
                                   rtol=1e-12, atol=1e-15, err_msg=name)
    a, b = (json.loads((d / "summary.json").read_text()) for d in (out, ref))
    for key in ("max_wear_depth_mm", "wear_volume_mm3", "archard_k_times_load_sliding_mm3"):
        assert a[key] == pytest.approx(b[key], rel=1e-12), key


@pytest.mark.parametrize("command", [[], ["study"], ["run"], ["sweep"], ["design"],
                                     ["calibrate"]])
def test_every_command_has_help(command, capsys):
    """`diffwear [COMMAND] --help` prints usage with the consistent options and exits 0."""
    with pytest.raises(SystemExit) as e:
        main([*command, "--help"])
    assert e.value.code == 0
    text = capsys.readouterr().out
    assert "usage: diffwear" in text
    assert "Exit codes: 0 success, 2 bad input, 3 " in " ".join(text.split())
    if command:
        assert "--out" in text and "--quiet" in text


def test_version(capsys):
    from importlib.metadata import version

    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    assert capsys.readouterr().out.strip() == f"diffwear {version('diffwear')}"


def test_design_with_an_output_folder_but_no_problem_is_refused(tmp_path, capsys):
    out = tmp_path / "d"
    assert main(["design", "--out", str(out)]) == 2
    assert "name the problem" in capsys.readouterr().err and not out.exists()


def test_calibrate_refuses_too_few_dynamic_cycles_in_the_users_words(tmp_path, capsys):
    """The model's limit is reported with the option's name, not a class name."""

    data = Path(__file__).resolve().parents[1] / "design_studies" / "calibration" / \
        "synthetic_run_in"
    out = tmp_path / "c"
    assert main(["calibrate", str(data), "--dynamic-cycles", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--dynamic-cycles 8 or more" in err and "RigHistory" not in err
    assert not out.exists()


@pytest.mark.slow  # a real process; the in-process interrupt tests above run by default
def test_sigint_to_a_real_run_then_resume(tmp_path):
    """A real process, a real SIGINT after its first checkpoint: exit 130 and one
    line naming the resume command, which then finishes the run."""
    import os
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "run"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "diffwear.cli", "study", WEAR, "--cycles",
                             "40", "--method", "constant", "--out", str(out), "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + 300
    while not (out / "checkpoint.npz").exists() and proc.poll() is None:
        assert time.monotonic() < deadline, "no checkpoint within 300 s"
        time.sleep(0.2)
    if proc.poll() is not None:
        pytest.skip("the run finished before it could be interrupted")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    if proc.returncode == 0:
        pytest.skip("the run finished before the signal arrived")
    assert proc.returncode == 130, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and f"diffwear study {WEAR} --resume {out}" in lines[0], err
    assert not (out / ".diffwear-lock").exists()
    assert main(["study", WEAR, "--resume", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["cycles"] == 40.0 and summary["resumed_from_cycles"] > 0


def _rig_file(tmp_path, *edits):
    text = (SHIPPED_MECHANISMS / "rig.toml").read_text()
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / "rig_edit.toml"
    path.write_text(text)
    return path


def test_run_refuses_a_speed_beyond_the_step_budget_up_front(tmp_path, capsys):
    path = _rig_file(tmp_path, ('omega = "30 rpm"', 'omega = "1e9 rpm"'))
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "driver 'driver' turns 3.33e+07 revolutions" in err and "max_steps" in err
    assert not out.exists()


def test_run_refuses_a_rod_shorter_than_the_crank_before_computing(tmp_path, capsys):
    """Rod 40 mm, crank 76.2 mm: the rod's slider end leaves the slider's line
    once 76.2 sin(phi) > 40 mm, i.e. beyond 31.7 deg; the first of the 5-deg
    samples past it is 35 deg."""
    path = _rig_file(tmp_path, ('bushing_point = ["-0.1016 m", "0 m"]',
                                'bushing_point = ["-0.02 m", "0 m"]'),
                     ('point_i = ["0.1016 m", "0 m"]', 'point_i = ["0.02 m", "0 m"]'))
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "cannot move through its cycle" in err and "at 35 deg of its cycle" in err
    assert not out.exists()


def test_run_warns_when_a_clearance_joint_never_makes_contact(tmp_path, capsys):
    path = _rig_file(tmp_path, ('bushing_radius = "9.533 mm"', 'bushing_radius = "1009.5 mm"'),
                     ('duration = "2 s"', 'duration = "0.05 s"'))
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "warning: clearance joint 'crank_rod' never made contact" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["contacts"]["crank_rod"]["fraction_in_contact"] == 0.0
    assert any("never made contact" in w for w in summary["warnings"])
    assert "## Warnings" in (out / "report.md").read_text()


def test_penetration_through_the_bushing_is_fatal():
    from types import SimpleNamespace

    from diffwear.mechanism_file import contact_warnings

    joint = SimpleNamespace(name="j", pin_radius=0.0095, law=None)
    ok = contact_warnings(joint, {"fraction_in_contact": 0.9, "max_penetration_m": 2e-6})
    assert ok == []
    (msg, fatal), = contact_warnings(joint, {"fraction_in_contact": 0.9,
                                              "max_penetration_m": 0.040})
    assert fatal and "40 mm" in msg and "421% of the pin radius" in msg


@pytest.mark.slow  # minutes; the other mechanism-file wear tests run by default
def test_four_bar_mechanism_file_wears_from_the_cli_and_from_python(tmp_path):
    """A four-bar file with a worn coupler-rocker joint: the wear study and the
    life to a depth limit from the CLI; from Python, the evolution run to the
    reported life ends at the limit depth (a second computation of it), and
    the worn volume agrees with Archard's law summed over the loads."""
    import numpy as np

    from diffwear.config import load
    from diffwear.mechanism_file import initial_state
    from diffwear.mechanism_file import wear as mechanism_wear
    from diffwear.models import QuasiStatic

    path = SHIPPED_MECHANISMS / "four_bar_wear.toml"
    out = tmp_path / "fb"
    assert main(["run", str(path), "--out", str(out), "--cycles", "50000", "--limit", "0.05",
                 "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    j = s["joints"]["coupler_rocker"]
    assert j["cycles"] == 50000 and j["status"] == OK and s["warnings"] == []
    assert 0.0 < j["max_wear_depth_mm"] < 0.05 < j["limit_mm"] + 1e-12
    for f in ("wear_profile_coupler_rocker.csv", "wear_history_coupler_rocker.csv", "wear.png"):
        assert (out / f).is_file()
    assert "## Wear (quasi-static model)" in (out / "report.md").read_text()
    life = j["cycles_to_limit"]
    assert life > 50000

    study = load(path)
    y0 = initial_state(study)
    at_life = mechanism_wear.evolve_file(study, y0, cycles=life)["coupler_rocker"]
    assert float(np.max(at_life["depth"])) == pytest.approx(0.05e-3, rel=0.01)
    # Archard: volume = k x sum over the cycle of (normal load x sliding distance) x cycles
    el = study.mechanism.element("coupler_rocker")
    model = QuasiStatic()
    loads = model.loads(study.mechanism, ("coupler_rocker",), y0,
                        mechanism_wear.drive_period(study)).joints[0]
    joint = model.joints(study.mechanism, ("coupler_rocker",))[0]
    _, load_sliding, _ = joint.cycle_wear(np.zeros(joint.n), loads)
    archard = float(el.wear.coefficient) * float(load_sliding) * 50000
    assert j["wear_volume_mm3"] * 1e-9 == pytest.approx(archard, rel=0.02)


@pytest.mark.extended
def test_a_mechanism_file_joint_worn_through_its_wall_stops_there(tmp_path, capsys):
    """The four-bar with a 1000x wear coefficient, asked for 1e6 cycles: the
    joint reaches its 4 mm wall (the layer thickness) first; the run stops
    there (exit 3 after writing), and the life to 3.9 mm, computed apart, is
    short of the cycles reported at the wall.  (The life and the run step the
    wear ODE on different depth grids, limit / steps and wall / steps, so on
    this 4 mm groove they agree to the step rule's ~1 %, not to the 0.25 %
    between 3.99 mm and the wall: measured 0.976-0.98 of the wall's cycles
    for 3.9 mm.)"""
    path = SHIPPED_MECHANISMS / "four_bar_wear.toml"
    text = path.read_text().replace('coefficient = "5.05e-4 mm^3/(N m)"',
                                    'coefficient = "5.05e-1 mm^3/(N m)"')
    edited = tmp_path / "fast_wear.toml"
    edited.write_text(text)
    out = tmp_path / "fb"
    assert main(["run", str(edited), "--out", str(out), "--cycles", "1000000",
                 "--limit", "3.9", "--quiet"]) == 3
    err = capsys.readouterr().err
    j = json.loads((out / "summary.json").read_text())["joints"]["coupler_rocker"]
    # the peak between the nodes is at the wall; the deepest node short of it
    # by the groove's curvature over half a node spacing (measured 3.988-3.999
    # mm as the right-hand side's rounding changed: the path to the wall is
    # sensitive)
    assert 3.95 < j["max_wear_depth_mm"] <= 4.0
    assert f"wore through its 4 mm bushing wall after {j['cycles']:,.0f} cycles" in err
    assert 0.95 * j["cycles"] < j["cycles_to_limit"] < j["cycles"] < 1e6
    assert "**stopped: clearance joint 'coupler_rocker'" in (out / "report.md").read_text()


def test_a_depth_limit_beyond_the_wall_is_refused(tmp_path, capsys):
    path = SHIPPED_MECHANISMS / "four_bar_wear.toml"
    out = tmp_path / "fb"
    assert main(["run", str(path), "--out", str(out), "--cycles", "10", "--limit", "5",
                 "--quiet"]) == 2
    assert "--limit 5 mm is not less than the bushing wall" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize("model", [
    "dynamic", pytest.param("quasi-static", marks=pytest.mark.slow)])  # the same report; minutes
def test_a_run_stopped_at_the_wall_reports_what_it_reached(tmp_path, capsys, model):
    """Asked for 1e8 cycles, the wear-5000 joint wears through its wall long
    before: stdout, report and summary give the same cycles (fewer than asked)
    and a depth at the wall, not the overshoot of the last step."""
    out = tmp_path / "w"
    assert main(["study", "wear-5000", "--cycles", "100000000", "--model", model,
                 "--out", str(out), "--quiet"]) == 3
    err = capsys.readouterr().err
    assert "reached the bushing wall" in err
    summary = json.loads((out / "summary.json").read_text())
    cycles, depth = summary["cycles"], summary["max_wear_depth_mm"]
    assert summary["cycles_requested"] == 1e8 and 1e5 < cycles < 3e5
    # bushing outer radius 33.31 mm, pin 20 mm, clearance 0.005 mm: the wall
    # is at most 13.31 mm deep, and the stop lands on it
    assert 13.2 < depth <= 13.31
    report = (out / "report.md").read_text()
    assert f"| max wear depth [mm] | {depth:.4f} |" in report
    assert f"cycles: {cycles:.0f}" in report
    assert f"after {cycles:.0f} cycles (max depth {depth:.4f} mm" in err


def test_a_motion_the_integrator_cannot_finish_is_written_up_to_where_it_stopped(
        tmp_path, capsys):
    """The ideal slider-crank takes about 2,300 steps per revolution: with a
    budget of 600 it stops part way.  Exit 3, and the folder holds the states
    reached (the trajectory's times, up to the stop), a report that opens with
    where and why it stopped, and the stop in summary.json."""
    text = (SHIPPED_MECHANISMS / "ideal_slider_crank.toml").read_text()
    assert "max_steps = 2_000_000" in text
    path = tmp_path / "short_budget.toml"
    path.write_text(text.replace("max_steps = 2_000_000", "max_steps = 600"))
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 3
    err = capsys.readouterr().err
    assert "maximum number of solver steps" in err and "results written to" in err
    summary = json.loads((out / "summary.json").read_text())
    stop = summary["stopped"]["at_time_s"]
    assert 0.0 < stop < 2.0
    with open(out / "trajectory.csv") as f:
        t = [float(row["t_s"]) for row in csv.DictReader(f)]
    # 401 saved states over 2 s, 0.005 s apart: those up to the stop, all finite
    assert t[-1] == stop and len(t) == round(stop / 0.005) + 1
    report = (out / "report.md").read_text()
    assert report.index("## Stopped early") < report.index("## Joint reactions")
    assert f"stopped at t = {stop:.6g} s of the 2 s" in report


FOUR_BAR = SHIPPED_MECHANISMS / "four_bar_wear.toml"


@pytest.mark.extended
def test_mechanism_file_dynamic_wear_resumes_and_agrees_with_the_quasi_static_model(
        tmp_path, capsys):
    """The four-bar's joint on the dynamic model (50 simulated cycles, A = 400)
    interrupted after its first checkpoint, resumed from the folder alone
    (cycles and model read from the checkpoint), agrees with the quasi-static
    model over the same 20,000 cycles: depth and volume within 1 % (the two
    models' agreement on the Ch. 7 rig is 0.1 %)."""
    out = tmp_path / "dyn"
    assert _run_interrupted(out, ("run", str(FOUR_BAR), "--cycles", "20000",
                                  "--model", "dynamic")) == 130
    assert f"diffwear run {FOUR_BAR} --resume {out}" in capsys.readouterr().err
    assert main(["run", str(FOUR_BAR), "--resume", str(out), "--quiet"]) == 0
    dyn = json.loads((out / "summary.json").read_text())["joints"]["coupler_rocker"]
    assert dyn["model"] == "dynamic" and dyn["cycles"] == 20000 and dyn["status"] == OK
    assert dyn["resumed_from_cycles"] > 0 and dyn["dynamic_cycles"] == 51

    qs_out = tmp_path / "qs"
    assert main(["run", str(FOUR_BAR), "--cycles", "20000", "--out", str(qs_out),
                 "--quiet"]) == 0
    qs = json.loads((qs_out / "summary.json").read_text())["joints"]["coupler_rocker"]
    assert qs["model"] == "quasi-static"
    assert dyn["max_wear_depth_mm"] == pytest.approx(qs["max_wear_depth_mm"], rel=0.01)
    assert dyn["wear_volume_mm3"] == pytest.approx(qs["wear_volume_mm3"], rel=0.01)
    assert "## Wear (dynamic model)" in (out / "report.md").read_text()


@pytest.mark.parametrize("options, words", [
    (["--cycles", "10", "--method", "adaptive"], "--method adaptive belongs to the dynamic model"),
    (["--model", "dynamic"], "give --cycles N"),
    (["--cycles", "10", "--resume", "nowhere"], "no checkpoint.npz there"),
])
def test_run_wear_options_are_checked_before_the_folder(tmp_path, capsys, options, words):
    out = tmp_path / "out"
    args = ["run", str(FOUR_BAR), *options]
    if "--resume" not in options:
        args += ["--out", str(out)]
    assert main(args) == 2
    assert words in capsys.readouterr().err
    assert not out.exists()


def test_the_dynamic_model_wears_one_joint_of_a_file(tmp_path, capsys):
    ideal = """[[joints]]
type = "revolute"
name = "crank_coupler"
body_i = "crank"
body_j = "coupler"
point_i = ["0.05 m", "0 m"]
point_j = ["-0.2 m", "0 m"]
"""
    worn = """[[joints]]
type = "clearance"
name = "crank_coupler"
pin_body = "crank"
pin_point = ["0.05 m", "0 m"]
bushing_body = "coupler"
bushing_point = ["-0.2 m", "0 m"]
pin_radius = "6 mm"
bushing_radius = "6.05 mm"
bushing_material = "ptfe"
n_theta = 90
law = { type = "elastic-foundation", layer_thickness = "4 mm", depth = "10 mm" }
wear = { coefficient = "5.05e-4 mm^3/(N m)" }
"""
    text = FOUR_BAR.read_text()
    assert ideal in text
    path = tmp_path / "two_worn.toml"
    path.write_text(text.replace(ideal, worn))
    out = tmp_path / "out"
    assert main(["run", str(path), "--cycles", "10", "--model", "dynamic", "--out", str(out),
                 "--quiet"]) == 2
    assert "this file wears 2 (crank_coupler, coupler_rocker)" in capsys.readouterr().err
    assert not out.exists()


def _lost_interrupt():
    """SIGINT delivered and its KeyboardInterrupt swallowed, as inside one of
    JAX's garbage-collection callbacks ("Exception ignored in ...")."""
    import os
    import signal

    try:
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(100):  # the handler runs at the next bytecode boundary
            pass
    except KeyboardInterrupt:
        pass


def test_a_ctrl_c_lost_in_a_callback_still_ends_the_run_with_130(tmp_path, capsys):
    """A wear run whose Ctrl-C was swallowed stops at the next chunk, after
    its checkpoint (resumable, the resume line printed), never finishing
    with exit 0."""
    from diffwear.models import execution as common

    real = common.save_checkpoint
    calls = []

    def save_and_lose_an_interrupt(*args, **kwargs):
        real(*args, **kwargs)
        calls.append(1)
        if len(calls) == 1:
            _lost_interrupt()

    out = tmp_path / "run"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(common, "save_checkpoint", save_and_lose_an_interrupt)
        assert main(["study", WEAR, "--cycles", "3", "--out", str(out), "--quiet"]) == 130
    assert len(calls) == 1  # stopped at the chunk where it was pressed
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"--resume {out}" in err[0]
    assert (out / "checkpoint.npz").is_file() and not (out / "summary.json").exists()


def test_a_ctrl_c_lost_as_a_command_ends_is_still_130(tmp_path, capsys, monkeypatch):
    from diffwear.studies import STUDIES

    def finishes(out, **kwargs):
        _lost_interrupt()
        out.json("summary.json", {"files": []})

    import signal

    before = signal.getsignal(signal.SIGINT)
    monkeypatch.setattr(STUDIES[STUDY], "run", finishes)
    assert main(["study", STUDY, "--out", str(tmp_path / "x"), "--quiet"]) == 130
    assert "interrupted as the run ended; its results were written" in capsys.readouterr().err
    assert signal.getsignal(signal.SIGINT) is before  # handler restored


def test_an_interrupt_lost_in_a_callback_is_not_printed_but_other_lost_errors_are():
    """Python prints an exception raised where it cannot propagate (a
    finaliser, one of JAX's garbage-collection callbacks) as "Exception
    ignored ... Traceback"; while the command's handler is installed a lost
    Ctrl-C is recorded and not printed (the command ends with its own one
    line), and any other lost exception is printed as before."""
    import subprocess
    import sys

    script = """
import gc, os, signal
from diffwear import interrupt

class Finaliser:
    def __init__(self, interrupt_it):
        self.interrupt_it = interrupt_it
    def __del__(self):
        if self.interrupt_it:
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):
                pass
        raise ValueError("a lost error")

signal.signal(signal.SIGINT, signal.default_int_handler)  # as from a terminal
previous = interrupt.install()
Finaliser(True)
gc.collect()
print("requested", interrupt.requested())
Finaliser(False)
interrupt.restore(previous)
print("restored", signal.getsignal(signal.SIGINT) is signal.default_int_handler)
"""
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == ["requested", "True", "restored", "True"]
    assert "KeyboardInterrupt" not in p.stderr
    assert p.stderr.count("Exception ignored") == 1 and "ValueError: a lost error" in p.stderr


def test_a_command_started_with_sigint_ignored_keeps_ignoring_it(tmp_path):
    """A process started with SIGINT ignored (``nohup``, a script's background
    job) is not made interruptible by the command: the console entry run
    that way finishes a study though SIGINT arrives while it starts and
    after it ends, with exit 0 and no interrupt line, and `install` /
    `hold` leave the ignored disposition in place."""
    import signal
    import subprocess
    import sys

    script = f"""
import os, signal, sys
signal.signal(signal.SIGINT, signal.SIG_IGN)
import diffwear_launcher
from diffwear import interrupt
previous = interrupt.install()
os.kill(os.getpid(), signal.SIGINT)
print("ignored", signal.getsignal(signal.SIGINT) is signal.SIG_IGN)
interrupt.hold()
print("held", signal.getsignal(signal.SIGINT) is signal.SIG_IGN)
interrupt.restore(previous)
os.kill(os.getpid(), signal.SIGINT)
sys.argv = ["diffwear", "study", "{STUDY}", "--out", r"{tmp_path / 'x'}", "--quiet"]
diffwear_launcher.entry()
"""
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split()[:4] == ["ignored", "True", "held", "True"]
    assert "interrupted" not in p.stderr and (tmp_path / "x" / "summary.json").is_file()
    assert signal.getsignal(signal.SIGINT) is not signal.SIG_IGN  # this process untouched


@pytest.mark.slow  # three real interrupts of a dynamic file run: about a minute
def test_ctrl_c_on_the_command_is_exit_130_at_any_moment(tmp_path):
    """``diffwear run four_bar_wear --model dynamic`` interrupted by SIGINT at
    three moments once it runs (its folder locked: compiling, early, later):
    exit 130 and one line every time, no traceback, no segmentation fault; a
    run interrupted after its first checkpoint resumes."""
    import os
    import signal
    import subprocess
    import sys
    import time

    exe = os.path.join(os.path.dirname(sys.executable), "diffwear")
    for k, delay in enumerate((0.0, 3.0, 8.0)):
        out = tmp_path / f"run{k}"
        p = subprocess.Popen([exe, "run", "four_bar_wear", "--model", "dynamic", "--cycles",
                              "2000", "--out", str(out), "--quiet"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        for _ in range(600):  # started: its output folder is locked
            if (out / ".diffwear-lock").exists():
                break
            time.sleep(0.1)
        time.sleep(delay)
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=120)
        assert p.returncode == 130, (delay, p.returncode, err[-2000:])
        lines = [ln for ln in err.strip().splitlines() if ln]
        assert "Traceback" not in err and lines[-1].startswith("diffwear: interrupted"), err
        if (out / "checkpoint.npz").is_file():
            assert subprocess.run([exe, "run", "four_bar_wear", "--resume", str(out),
                                   "--quiet"], capture_output=True).returncode == 0


def test_ctrl_c_while_the_command_starts_up_is_exit_130_without_a_traceback():
    """SIGINT while the command imports JAX (made certain here by sending it
    from inside the import of ``jax``): exit 130 and the one line, where the
    console script's own import would have ended in a traceback."""
    import subprocess
    import sys

    script = """
import importlib.abc, os, signal, sys
class InterruptInsideTheImport(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name == "jax":
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):  # the handler runs at a bytecode boundary
                pass
        return None
sys.meta_path.insert(0, InterruptInsideTheImport())
sys.argv = ["diffwear", "run", "four_bar_wear"]
import diffwear_launcher
diffwear_launcher.entry()
print("not interrupted")
"""
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 130, p.stderr[-2000:]
    assert p.stderr == "diffwear: interrupted; no results were written\n" and not p.stdout


def test_ctrl_c_while_the_finished_command_exits_is_exit_130_with_its_line():
    """SIGINT after the run wrote its results, while the process ends (sent
    here from an exit handler): recorded, not raised, and reported as an
    interrupt after the results were written, never a traceback or a silent
    death by the signal."""
    import subprocess
    import sys

    script = """
import atexit, os, signal, sys, time
from diffwear.cli import command

def late_ctrl_c():
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(0.2)
    print("exit handlers ran")

atexit.register(late_ctrl_c)
command.main = lambda: 0
command.entry()
"""
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 130, (p.returncode, p.stderr[-2000:])
    assert p.stdout == "exit handlers ran\n"
    assert p.stderr == "diffwear: interrupted as the run ended; its results were written\n"


@pytest.mark.long  # 50 real runs interrupted at random moments: about ten minutes
def test_fifty_ctrl_cs_at_random_moments_are_all_exit_130_and_the_run_resumes(tmp_path):
    """``diffwear run four_bar_wear --model dynamic`` interrupted 50 times, each
    after a random delay (0-16 s: importing, compiling, simulating, wearing,
    writing), each run resuming the last one's checkpoint: exit 130 and one
    line every time, no traceback or crash; the run finished at the end holds
    the same wear as one run never interrupted."""
    import os
    import random
    import signal
    import subprocess
    import sys
    import time

    exe = os.path.join(os.path.dirname(sys.executable), "diffwear")
    args = ["four_bar_wear", "--model", "dynamic", "--cycles", "2000", "--quiet"]
    reference = tmp_path / "reference"
    assert subprocess.run([exe, "run", *args, "--out", str(reference)],
                          capture_output=True).returncode == 0

    def command(out):
        if (out / "checkpoint.npz").is_file() and not (out / "summary.json").is_file():
            return [exe, "run", "four_bar_wear", "--resume", str(out), "--quiet"]
        return [exe, "run", *args, "--out", str(out), "--overwrite"]

    rng = random.Random(20261127)
    out = tmp_path / "run"
    resumed = 0
    for k in range(50):
        cmd = command(out)
        resumed += "--resume" in cmd
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        delay = rng.uniform(0.0, 16.0)
        time.sleep(delay)
        finished_first = p.poll() is not None
        if not finished_first:
            p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=180)
        where = (k, round(delay, 2), p.returncode, err[-2000:])
        assert "Traceback" not in err and "Segmentation" not in err, where
        if finished_first:
            assert p.returncode == 0, where
            continue
        assert p.returncode == 130, where
        lines = [ln for ln in err.strip().splitlines() if ln]
        assert len(lines) == 1 and lines[0].startswith("diffwear: interrupted"), where
        assert not (out / ".diffwear-lock").exists(), where
    assert resumed >= 5  # the interrupts fell in the wear loop, after checkpoints
    final = subprocess.run(command(out), capture_output=True, text=True)
    assert final.returncode == 0, final.stderr[-2000:]

    def wear(folder):
        return json.loads((folder / "summary.json").read_text())["joints"]

    joints, ref_joints = wear(out), wear(reference)
    for name, joint in ref_joints.items():
        assert joints[name]["cycles"] == joint["cycles"] == 2000.0
        for key in ("max_wear_depth_mm", "wear_volume_mm3"):
            assert joints[name][key] == pytest.approx(joint[key], rel=1e-9), (name, key)
