"""A mechanism file too large to compile in reasonable time or memory is warned
about (with the estimate) or refused before anything is traced.

The files are those the estimate was measured on (``benchmarks/compile_size.py``):
free bodies, and pendulum chains of revolute joints.
"""

import json
from pathlib import Path

import pytest

from diffwear import progress
from diffwear.cli import main
from diffwear.config import load
from diffwear.errors import InputError
from diffwear.mechanism_file import size

RECORD = Path(__file__).resolve().parents[1] / "benchmarks" / "records" / "compile_size.json"


@pytest.fixture(scope="module")
def files(load_benchmark):
    return load_benchmark("compile_size")


def _write(files, tmp_path, kind, n):
    path = tmp_path / f"{kind}{n}.toml"
    path.write_text(files.mechanism_text(kind, n))
    return path


def test_the_estimate_counts_what_the_file_holds_and_follows_the_record(files, tmp_path):
    """A 40-link chain: 40 bodies, 40 revolute joints + gravity = 41 elements,
    120 coordinates; time and memory from the fit's coefficients by hand."""
    est = size.estimate(load(_write(files, tmp_path, "chain", 40)))
    assert (est.bodies, est.elements, est.coordinates) == (40, 41, 120)
    fit = json.loads(RECORD.read_text())["fit"]
    seconds = (fit["seconds"]["base"] + 41 * fit["seconds"]["per_element"]
               + 120 * fit["seconds"]["per_coordinate"])
    memory = (fit["bytes"]["base"] + 41**2 * fit["bytes"]["per_element_squared"]
              + 120 * fit["bytes"]["per_coordinate"])
    assert est.seconds == pytest.approx(seconds, rel=1e-6)
    assert est.bytes == pytest.approx(memory, rel=1e-6)


def test_the_fit_reproduces_its_measurements_within_a_factor_of_two():
    """The record's own rows against the fitted formula: an estimate, but of
    the right size (the warning's "about N min" must not mislead)."""
    record = json.loads(RECORD.read_text())
    fit = record["fit"]
    for row in record["rows"]:
        t = (fit["seconds"]["base"] + row["elements"] * fit["seconds"]["per_element"]
             + row["coordinates"] * fit["seconds"]["per_coordinate"])
        m = (fit["bytes"]["base"] + row["elements"] ** 2 * fit["bytes"]["per_element_squared"]
             + row["coordinates"] * fit["bytes"]["per_coordinate"])
        assert 0.5 < t / row["seconds"] < 2.0, row
        assert 0.5 < m / row["peak_bytes"] < 2.0, row


def test_a_small_file_passes_silently(files, tmp_path):
    assert size.check_size(load(_write(files, tmp_path, "chain", 3))) is None


def test_ten_thousand_free_bodies_are_warned_about_before_compiling(files, tmp_path, capsys,
                                                                  monkeypatch):
    """The warning names the size and the estimate, and comes before the
    first compilation (here stopped at the initial state)."""
    from diffwear.cli import run as run_cli

    class Stop(Exception):
        pass

    def stop(mfile):
        raise Stop

    monkeypatch.setattr(size, "physical_memory", lambda: 10**12)
    monkeypatch.setattr(run_cli, "initial_state", stop)
    path = _write(files, tmp_path, "free", 10_000)
    with pytest.raises(Stop):
        main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert "diffwear: warning:" in err and "10,000 bodies" in err
    assert "30,000 coordinates" in err and "estimated to take about" in err
    assert not (tmp_path / "out").exists()


def test_a_file_beyond_the_machines_memory_is_refused_with_the_estimate(files, tmp_path,
                                                                      capsys, monkeypatch):
    monkeypatch.setattr(size, "physical_memory", lambda: 2 * 10**9)
    path = _write(files, tmp_path, "chain", 400)
    est = size.estimate(load(path))
    assert est.bytes > 2e9
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(path) in err
    assert "400 bodies, 401 joints and force elements" in err
    assert f"{est.bytes / 1e9:.1f} GB of memory, more than this machine's 2.0 GB" in err
    assert not (tmp_path / "out").exists()


def test_the_api_refuses_against_a_given_memory(files, tmp_path):
    mfile = load(_write(files, tmp_path, "chain", 5))
    with pytest.raises(InputError, match="more than this machine's"):
        size.check_size(mfile, memory=1)


def test_a_file_beyond_the_compile_budget_asks_for_yes(files, tmp_path, capsys, monkeypatch):
    """A 1,500-link chain (1,501 elements, 4,500 coordinates) is 1.35 + 0.397 x
    1501 + 0.0064 x 4500 = 627 s by the fit, beyond the 600 s budget.  The
    same rule on a 100-link chain (43 s) against a budget lowered to 30 s:
    refused without --yes (exit 2, the estimate and the flag named, nothing
    written); with --yes it goes on (here stopped at the initial state).
    The API's default runs it."""
    from diffwear.cli import run as run_cli

    def fit(elements, coordinates):
        return (size.SECONDS_BASE + elements * size.SECONDS_PER_ELEMENT
                + coordinates * size.SECONDS_PER_COORDINATE)

    assert fit(1501, 4500) > size.COMPILE_BUDGET_SECONDS == 600.0 > fit(1, 30_000)
    monkeypatch.setattr(size, "COMPILE_BUDGET_SECONDS", 30.0)
    path = _write(files, tmp_path, "chain", 100)
    est = size.estimate(load(path)).seconds
    assert est == pytest.approx(fit(101, 300), rel=1e-12) and est > 30.0
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "beyond the compile budget of 30 s" in err
    assert f"about {est:.0f} s" in err and "--yes" in err
    assert not out.exists()

    class Stop(Exception):
        pass

    def stop(mfile):
        raise Stop

    monkeypatch.setattr(run_cli, "initial_state", stop)
    with pytest.raises(Stop):
        main(["run", str(path), "--out", str(out), "--quiet", "--yes"])
    assert not out.exists()
    assert size.check_size(load(path)) is None  # the API: runs it (below the warning)


def test_a_long_compile_says_its_progress(files, tmp_path, capsys, monkeypatch):
    """A run warned about (the warning threshold lowered to a small file's
    estimate) says, while it compiles, how long it has run against the
    estimate: lines 0.05 s apart over a 0.3 s compile stand-in."""
    import time

    from diffwear.cli import run as run_cli

    class Stop(Exception):
        pass

    def compile_then_stop(mfile, y0, **options):
        time.sleep(0.3)
        raise Stop

    monkeypatch.setattr(size, "WARN_SECONDS", 0.0)
    monkeypatch.setattr(progress, "PROGRESS_EVERY_SECONDS", 0.05)
    monkeypatch.setattr(run_cli, "integrate_timed", compile_then_stop)
    monkeypatch.setattr(run_cli, "initial_state", lambda mfile: None)
    monkeypatch.setattr(run_cli, "check_motion", lambda mfile, y0: None)
    path = _write(files, tmp_path, "chain", 3)
    with pytest.raises(Stop):
        main(["run", str(path), "--out", str(tmp_path / "out")])
    lines = [ln for ln in capsys.readouterr().err.splitlines()
             if "compiling and integrating" in ln]
    est = size.estimate(load(path)).seconds
    assert len(lines) >= 3 and all(f"of an estimated {est:.0f} s" in ln for ln in lines)
    assert lines[0].startswith("diffwear: compiling and integrating: 0 s so far")
