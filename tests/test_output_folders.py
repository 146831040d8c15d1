"""Output folders: only a new, an empty or a previous diffwear folder is
written into; --overwrite removes the previous run's own files and only
those; a full disk leaves no truncated file and one line (exit 4)."""

from __future__ import annotations

import errno
import json

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np
import pytest

from diffwear.cli import main
from diffwear.errors import InputError
from diffwear.io import MANIFEST, OutputDir, release_all

RUN = ["run", "ideal_slider_crank", "--quiet"]


@pytest.fixture(autouse=True)
def _release():
    yield
    release_all()


def _listing(folder):
    return sorted(p.name for p in folder.iterdir())


def test_a_folder_of_the_users_own_files_is_refused_and_left_as_it_was(tmp_path, capsys):
    out = tmp_path / "mine"
    out.mkdir()
    mine = {"trajectory.csv": "t,x\n0,1\n", "report.md": "# my notes\n", "notes.txt": "keep"}
    for name, body in mine.items():
        (out / name).write_text(body)
    for extra in ([], ["--overwrite"]):
        assert main([*RUN, "--out", str(out), *extra]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "notes.txt, report.md, trajectory.csv" in err[0]
        assert "did not write" in err[0] or "not a diffwear output" in err[0]
    assert _listing(out) == sorted(mine)
    assert all((out / n).read_text() == body for n, body in mine.items())


@pytest.mark.parametrize("blank", ["", "   "])
def test_an_empty_out_is_refused(blank, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main([*RUN, "--out", blank]) == 2
    assert "empty" in capsys.readouterr().err
    assert _listing(tmp_path) == []


def test_overwrite_removes_the_previous_runs_files_and_only_those(tmp_path):
    out = tmp_path / "run"
    previous = OutputDir(out)  # a previous run that wrote more files than the next one
    previous.csv("contact_0.csv", {"x": [1.0]})
    previous.text("wear_history_0.csv", "n,h\n")
    previous.file("wear.png").write_bytes(b"png")
    previous.json("summary.json", {"files": ["contact_0.csv", "wear_history_0.csv", "wear.png"]})
    release_all()
    assert main([*RUN, "--out", str(out)]) == 2  # results there: refused without --overwrite
    assert main([*RUN, "--out", str(out), "--overwrite"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert _listing(out) == sorted([*summary["files"], MANIFEST])
    assert not {"contact_0.csv", "wear_history_0.csv", "wear.png"} & set(_listing(out))
    assert (out / MANIFEST).read_text().split() == list(dict.fromkeys(
        (out / MANIFEST).read_text().split()))


def test_a_folder_written_before_manifests_is_recognised_by_its_summary(tmp_path):
    out = tmp_path / "old"
    out.mkdir()
    (out / "a.csv").write_text("x\n1\n")
    (out / "summary.json").write_text(json.dumps({"files": ["a.csv", "summary.json"]}))
    OutputDir(out, overwrite=True)
    assert _listing(out) == sorted([".diffwear-lock", MANIFEST])
    (out / "b.txt").write_text("mine")
    release_all()
    with pytest.raises(InputError, match=r"b\.txt"):
        OutputDir(out, overwrite=True)


def test_a_full_disk_leaves_no_truncated_file_and_one_line(tmp_path, capsys, monkeypatch):
    """np.savetxt (the CSV writer) and a figure's savefig cut short by ENOSPC
    after writing part of the file: exit 4, the file named, nothing partial
    left, the files written before it intact."""
    import matplotlib.figure

    def full(target, written: bytes):
        with open(target, "wb") as f:
            f.write(written)
        raise OSError(errno.ENOSPC, "No space left on device")

    real_savetxt = np.savetxt

    def savetxt(target, *a, **k):
        if "reaction_driver" in str(target):
            full(target, b"t,F\n0.0,1.")
        return real_savetxt(target, *a, **k)

    monkeypatch.setattr(np, "savetxt", savetxt)
    out = tmp_path / "csv"
    assert main([*RUN, "--out", str(out)]) == 4
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "reaction_driver.csv" in err[0] and "disk" in err[0] \
        and "full" in err[0] and "Traceback" not in err[0]
    assert not any("reaction_driver" in n for n in _listing(out))
    assert not any(n.endswith(".partial") for n in _listing(out))
    assert (out / "trajectory.csv").read_text().startswith("t_s,")  # written before: intact
    monkeypatch.setattr(np, "savetxt", real_savetxt)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig",
                        lambda self, target, **k: full(target, b"\x89PNG\r\n"))
    out = tmp_path / "png"
    assert main([*RUN, "--out", str(out)]) == 4
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "trajectory.png" in err[0] and "full" in err[0]
    assert "trajectory.png" not in _listing(out)
    assert "trajectory.png" in (out / "INCOMPLETE").read_text()  # a figure's failure too


def test_a_write_cut_short_by_a_kill_is_not_taken_for_a_users_file(tmp_path):
    out = tmp_path / "killed"
    OutputDir(out).csv("a.csv", {"x": [1.0]})
    release_all()
    (out / ".summary.json.partial").write_text('{"fil')  # the rename never happened
    OutputDir(out, overwrite=True)
    assert ".summary.json.partial" not in _listing(out)


def test_study_without_a_name_but_an_out_is_refused_like_design(tmp_path, capsys):
    out = tmp_path / "x"
    assert main(["study", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "name the study" in err and "ideal-slider-crank" in err and not out.exists()
    assert main(["study"]) == 0  # the list, as before


def test_a_killed_runs_files_are_not_mixed_with_a_new_runs(tmp_path):
    out = tmp_path / "killed"
    OutputDir(out).csv("contact_0.csv", {"x": [1.0]})  # killed before its summary
    release_all()
    with pytest.raises(InputError, match=r"did not finish \(contact_0\.csv\).*--overwrite"):
        OutputDir(out)
    OutputDir(out, overwrite=True)
    assert "contact_0.csv" not in _listing(out)


def _snapshot(folder):
    return {p.name: p.read_bytes() for p in folder.iterdir()}


def _checkpoint_of(folder, meta):
    """A checkpoint as a wear run leaves it, recording ``meta``."""
    from diffwear.models import Checkpoint, WearState, save_checkpoint

    folder.mkdir()
    state = jax.tree.map(np.asarray, WearState.initial((np.zeros(3),),
                                                   {"y": np.zeros(2), "t": np.asarray(0.0)}))
    save_checkpoint(folder / "checkpoint.npz", Checkpoint(state, {"cycles": np.zeros(1)}, 1),
                    meta)


def test_a_resume_of_another_files_checkpoint_is_refused_and_touches_nothing(tmp_path, capsys):
    """The checkpoint of a run of another file: exit 2 naming both files, and
    the folder byte for byte as it was (no manifest, no lock left)."""
    from diffwear.choices import SHIPPED_MECHANISMS

    out = tmp_path / "other"
    _checkpoint_of(out, {"mfile": "run rig.toml", "file_crc32": "00000000", "model": "dynamic",
                         "cycles": 10.0})
    before = _snapshot(out)
    assert main(["run", str(SHIPPED_MECHANISMS / "four_bar_wear.toml"), "--resume", str(out),
                 "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "'run rig.toml'" in err and "'run four_bar_wear.toml'" in err
    assert _snapshot(out) == before


def test_a_folder_opened_to_resume_and_left_is_as_it_was(tmp_path):
    """Opening a folder (to resume, or a new one) writes nothing before the
    first result: a refusal after it leaves no manifest and no lock."""
    out = tmp_path / "interrupted"
    _checkpoint_of(out, {"cycles": 10.0})
    before = _snapshot(out)
    OutputDir(out, resume=True)
    release_all()
    assert _snapshot(out) == before
    OutputDir(tmp_path / "new")
    release_all()
    assert not (tmp_path / "new").exists()


def test_a_run_stopped_by_a_full_disk_is_marked_incomplete(tmp_path, capsys, monkeypatch):
    """ENOSPC on the third file: exit 4, and INCOMPLETE beside the files
    written before it, saying why; the next run is refused naming it,
    --overwrite replaces the run and removes the mark."""
    real_savetxt = np.savetxt

    def savetxt(target, *a, **k):
        if "reaction_driver" in str(target):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_savetxt(target, *a, **k)

    monkeypatch.setattr(np, "savetxt", savetxt)
    out = tmp_path / "full"
    assert main([*RUN, "--out", str(out)]) == 4
    assert "marked INCOMPLETE" in capsys.readouterr().err
    names = _listing(out)
    assert "INCOMPLETE" in names and "trajectory.csv" in names and "summary.json" not in names
    why = (out / "INCOMPLETE").read_text()
    assert "reaction_driver.csv" in why and "full" in why and "--overwrite" in why
    monkeypatch.setattr(np, "savetxt", real_savetxt)
    assert main([*RUN, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "did not finish" in err and "INCOMPLETE: cannot write reaction_driver.csv" in err
    assert main([*RUN, "--out", str(out), "--overwrite"]) == 0
    assert "INCOMPLETE" not in _listing(out) and "summary.json" in _listing(out)


def test_a_disk_full_at_the_first_file_still_leaves_a_folder_the_next_run_takes(tmp_path):
    """A stop before anything was listed: INCOMPLETE alone is diffwear's
    (refused as an unfinished run, taken by --overwrite), not a user's file."""
    out = tmp_path / "first"
    folder = OutputDir(out)
    folder.mark_incomplete("cannot write trajectory.csv: the disk holding it is full")
    release_all()
    with pytest.raises(InputError, match="did not finish .*INCOMPLETE: cannot write"):
        OutputDir(out)
    OutputDir(out, overwrite=True)
    assert "INCOMPLETE" not in _listing(out)


def test_overwrite_beside_a_users_file_names_it_and_says_what_to_do(tmp_path, capsys):
    out = tmp_path / "run"
    previous = OutputDir(out)
    previous.csv("trajectory.csv", {"x": [1.0]})
    previous.json("summary.json", {"files": ["trajectory.csv"]})
    release_all()
    (out / "notes.txt").write_text("mine")
    before = _snapshot(out)
    assert main([*RUN, "--out", str(out), "--overwrite"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "(notes.txt)" in err[0]
    assert "removes only the files a run wrote" in err[0] and "move them out" in err[0]
    assert _snapshot(out) == before


def test_a_resumed_run_that_finishes_clears_the_incomplete_mark(tmp_path):
    """A run stopped after its checkpoint and first file: the refusal names
    INCOMPLETE's reason; --resume continues it, and its summary removes the
    mark (from the folder and from the run's list of files)."""
    out = tmp_path / "stopped"
    first = OutputDir(out)
    first.file("checkpoint.npz").write_bytes(b"state")
    first.csv("trajectory.csv", {"t_s": [0.0]})
    first.mark_incomplete("cannot write wear.png: the disk holding it is full")
    release_all()
    with pytest.raises(InputError, match=r"interrupted run .*INCOMPLETE: cannot write wear\.png"):
        OutputDir(out)
    resumed = OutputDir(out, resume=True)
    assert "INCOMPLETE" not in resumed.files
    resumed.json("summary.json", {"files": resumed.files})
    assert "INCOMPLETE" not in _listing(out)
    assert "INCOMPLETE" not in (out / MANIFEST).read_text().split()


def test_a_run_interrupted_after_its_first_files_is_marked_incomplete(tmp_path, capsys,
                                                                      monkeypatch):
    """Ctrl-C while the third file is written: exit 130, and INCOMPLETE
    says the run was interrupted; the next run is refused naming it."""
    real_savetxt = np.savetxt

    def savetxt(target, *a, **k):
        if "reaction_driver" in str(target):
            raise KeyboardInterrupt
        return real_savetxt(target, *a, **k)

    monkeypatch.setattr(np, "savetxt", savetxt)
    out = tmp_path / "stopped"
    assert main([*RUN, "--out", str(out)]) == 130
    assert "interrupted (Ctrl-C)" in (out / "INCOMPLETE").read_text()
    assert "trajectory.csv" in _listing(out) and "summary.json" not in _listing(out)
    monkeypatch.setattr(np, "savetxt", real_savetxt)
    capsys.readouterr()
    assert main([*RUN, "--out", str(out)]) == 2
    assert "INCOMPLETE: the run was interrupted" in capsys.readouterr().err


def test_a_users_file_named_incomplete_is_the_users(tmp_path, capsys):
    """A folder of one's own holding a file named INCOMPLETE (not diffwear's
    words): refused as a user's file, and --overwrite leaves it."""
    out = tmp_path / "mine"
    out.mkdir()
    (out / "INCOMPLETE").write_text("my list of unfinished things\n")
    for extra in ([], ["--overwrite"]):
        assert main([*RUN, "--out", str(out), *extra]) == 2
        assert "(INCOMPLETE)" in capsys.readouterr().err
    assert (out / "INCOMPLETE").read_text() == "my list of unfinished things\n"


def test_a_file_run_resuming_a_studys_checkpoint_is_refused_before_the_folder(tmp_path,
                                                                              capsys):
    from diffwear.choices import SHIPPED_MECHANISMS

    out = tmp_path / "study"
    _checkpoint_of(out, {"study": "wear-5000", "model": "dynamic", "cycles": 10.0})
    before = _snapshot(out)
    assert main(["run", str(SHIPPED_MECHANISMS / "four_bar_wear.toml"), "--resume", str(out),
                 "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "the study 'wear-5000'" in err and "'run four_bar_wear.toml'" in err
    assert _snapshot(out) == before
