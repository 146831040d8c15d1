"""The start-up transient of a run (`diffwear.mechanism_file.transient`): the
detector against signals whose settling time is known in closed form, and on
shipped mechanism files against a second run started from a settled state."""

from __future__ import annotations

import math

import numpy as np
import pytest

from diffwear.config import load
from diffwear.mechanism_file import (
    force_signals,
    initial_state,
    integrate,
    postprocess,
    settled_part,
    start_up_transient,
)
from diffwear.mechanism_file import transient as tr

PERIOD = 1.0                                # s, the forced motion's
TS = np.linspace(0.0, PERIOD, 401)          # the shipped files' 401 saved states a period
FORCED = 1.0 + 0.5 * np.cos(2 * math.pi * TS / PERIOD)  # size max |p| = 1.5


def ringing(amplitude, tau, freq=50.0):
    """A start-up ringing B exp(-t / tau) cos(2 pi f t): at 50 Hz, 8 saved
    states a cycle (so the samples hit its peaks), 1.6 cycles in the fit's
    window (1/32 s, 13 states)."""
    return amplitude * np.exp(-TS / tau) * np.cos(2 * math.pi * freq * TS)


def savitzky_golay_gain(h, freq, dt):
    """Response of the centred quadratic least-squares fit over 2h + 1 samples
    to cos(2 pi f t), from its closed-form weights (Savitzky & Golay 1964):
    c_j = (3 (3h^2 + 3h - 1) - 15 j^2) / ((2h - 1)(2h + 1)(2h + 3))."""
    j = np.arange(-h, h + 1)
    c = (3 * (3 * h**2 + 3 * h - 1) - 15 * j**2) / ((2 * h - 1) * (2 * h + 1) * (2 * h + 3))
    assert math.isclose(c.sum(), 1.0)
    return float(np.sum(c * np.cos(2 * math.pi * freq * j * dt)))


def test_decaying_ringing_settles_when_its_envelope_reaches_the_tolerance():
    """The residual of the ringing about the fit is (1 - H) B e^(-t/tau) (H:
    the fit's gain at 50 Hz); it falls to the threshold TOLERANCE x 1.5 at
    t* = tau ln((1 - H) B / (0.01 x 1.5)).  The envelope is a running maximum
    over +-h states, so it crosses h dt later.  Allowed: the half cycle
    between the ringing's peaks, and one saved state."""
    amplitude, tau, freq = 2.0, 0.05, 50.0
    s = FORCED + ringing(amplitude, tau, freq)
    dt = TS[1] - TS[0]
    h = tr.half_width(TS, PERIOD)
    assert h == 6  # round(1/32 / 2 / 0.0025)
    gain = savitzky_golay_gain(h, freq, dt)
    expected = tau * math.log((1 - gain) * amplitude / (tr.TOLERANCE * 1.5)) + h * dt
    got = tr.signal_settling(TS, s, PERIOD)
    assert got.settled
    assert got.time_s == pytest.approx(expected, abs=0.5 / freq + dt)
    # what the report gives: the maximum after it is the forced motion's to 1 %
    settled = settled_part(TS, got)
    assert np.max(s[settled]) == pytest.approx(np.max(FORCED[settled]), rel=tr.TOLERANCE)
    assert np.max(s) > 2.5  # the whole run's maximum is the ringing's


def test_forced_motion_alone_has_no_transient():
    """Harmonics up to the 3rd of the driver: the fit follows them to 3e-4 of
    their amplitude (module notes), far below the tolerance: no transient."""
    s = FORCED + 0.3 * np.sin(2 * 2 * math.pi * TS + 0.4) + 0.2 * np.cos(3 * 2 * math.pi * TS)
    assert tr.signal_settling(TS, s, PERIOD).time_s == 0.0
    h = tr.half_width(TS, PERIOD)
    third = np.cos(3 * 2 * math.pi * TS)
    assert np.max(np.abs(third - tr._quadratic_fit(third, h))) < 3e-4


def test_persistent_roughness_is_not_a_transient_but_growth_is_not_settled():
    """A ringing that keeps its size is part of the settled motion (the floor
    of the threshold), one that grows is reported as not settled."""
    steady = FORCED + 0.1 * np.cos(2 * math.pi * 60.0 * TS)
    assert tr.signal_settling(TS, steady, PERIOD).time_s == 0.0
    growing = FORCED + 0.1 * np.exp(TS / 0.1) / np.exp(10.0) * np.cos(2 * math.pi * 60.0 * TS)
    got = tr.signal_settling(TS, growing, PERIOD)
    assert not got.settled and "grows" in got.why
    slow = FORCED + ringing(2.0, 0.5)  # still 0.27 at the end: no settled half
    got = tr.signal_settling(TS, slow, PERIOD)
    assert not got.settled and "did not settle" in got.why
    assert settled_part(TS, got).all()  # all states: whole-run maxima


def test_the_run_takes_its_longest_signal_and_names_one_that_does_not_settle():
    quick, late = FORCED + ringing(2.0, 0.02), FORCED + ringing(2.0, 0.05)
    both = tr.run_settling(TS, {"a": quick, "b": late}, PERIOD)
    assert both.time_s == tr.signal_settling(TS, late, PERIOD).time_s
    assert both.time_s > tr.signal_settling(TS, quick, PERIOD).time_s
    bad = tr.run_settling(TS, {"a": quick, "b": FORCED + ringing(2.0, 0.5)}, PERIOD)
    assert not bad.settled and bad.why.startswith("b: ")
    assert tr.run_settling(TS, {}, PERIOD).time_s == 0.0


def test_too_few_saved_states_cannot_be_judged():
    ts = np.linspace(0.0, 1.0, 15)
    got = tr.signal_settling(ts, np.cos(ts), None)
    assert not got.settled and "too few" in got.why


def _write_synthetic_run(tmp_path, tau):
    """`diffwear run`'s outputs for the ideal slider-crank file with made-up
    forces: each reaction's fx the forced motion plus a ringing of time
    constant ``tau`` (in units of the 1 s of TS; fx stays > 0, so |F| = fx),
    its moment twice the forced motion."""
    from diffwear.cli.run import write
    from diffwear.io import OutputDir
    from diffwear.mechanism_file import Results

    mfile = load("ideal_slider_crank")
    n, coords = mfile.simulation.n_save, mfile.mechanism.n_coords
    ts = np.linspace(0.0, mfile.simulation.duration, n)
    assert np.allclose(ts, 2 * TS)  # 2 s, 401 states: TS stretched to the 2 s period
    fx = FORCED + ringing(0.4, tau)
    wrench = np.stack([fx, np.zeros(n), 2 * FORCED], axis=1)
    r = Results(ts, np.zeros((n, coords)), np.zeros((n, coords)),
                np.zeros((n, mfile.mechanism.n_constraints)),
                {o.joint: wrench for o in mfile.reactions})
    summary = write(mfile, r, OutputDir(tmp_path / f"tau{tau}"), steps=1, simulate_time=1.0,
                    compile_time=0.5)
    report = (tmp_path / f"tau{tau}" / "report.md").read_text()
    return ts, fx, summary, report


def test_report_gives_the_settled_maxima_and_labels_the_whole_runs(tmp_path):
    ts, fx, summary, report = _write_synthetic_run(tmp_path, 0.05)
    expected = tr.signal_settling(ts, fx, 2.0).time_s   # the ringing sets it, not |M|
    assert expected > 0.2
    assert summary["start_up_transient"] == {"settled": True, "length_s": expected}
    driver = summary["reactions"]["driver"]
    assert driver["settled_max_force_N"] == np.max(fx[ts >= expected])
    assert driver["max_force_N"] == np.max(fx) > 1.8
    assert driver["settled_max_force_N"] == pytest.approx(1.5, rel=tr.TOLERANCE)
    assert f"| start-up transient | {expected:.4g} s |" in report
    assert "max abs(F) [N] after the transient" in report
    assert "max abs(F) [N], whole run, incl. the start-up transient" in report
    assert (f"| driver | crank | {driver['settled_max_force_N']:.4g} | {np.max(fx):.4g} | "
            "3 | 3 |") in report
    for words in ("run time", "compile time"):
        assert report.count(words) == 1, words


def test_a_run_that_does_not_settle_reports_whole_run_maxima(tmp_path):
    ts, fx, summary, report = _write_synthetic_run(tmp_path, 0.25)
    t = summary["start_up_transient"]
    assert t["settled"] is False and t["length_s"] is None and "did not settle" in \
        t["why_not_settled"]
    assert summary["reactions"]["driver"]["settled_max_force_N"] is None
    assert "the run did not settle" in report and "max abs(F) [N] (whole run)" in report
    assert f"| driver | crank | {np.max(fx):.4g} | 3 |" in report


def _maxima(mfile, r, mask):
    return {k: float(np.max(v[mask])) for k, v in force_signals(mfile, r).items()}


def _check_against_settled_rerun(name):
    """The settled maxima of the file's run against the maxima of one full
    period (the file's duration) run on from the first run's end, a state
    well after the detected transient; that second run has no transient."""
    mfile = load(name)
    duration = mfile.simulation.duration
    y0 = initial_state(mfile)
    traj = integrate(mfile, y0)
    first = postprocess(mfile, traj)
    transient = start_up_transient(mfile, first)
    assert transient.settled
    assert 0.0 < transient.time_s < duration / 2
    settled = _maxima(mfile, first, settled_part(first.ts, transient))
    whole = _maxima(mfile, first, np.ones(first.ts.shape, bool))

    again = postprocess(mfile, integrate(mfile, traj.ys[-1], t0=duration))
    assert again.ts[0] == pytest.approx(duration) and again.ts[-1] == pytest.approx(2 * duration)
    periodic = _maxima(mfile, again, np.ones(again.ts.shape, bool))
    for k, v in periodic.items():
        if v == 0.0:  # a driver's force: none
            assert settled[k] == 0.0
            continue
        assert settled[k] == pytest.approx(v, rel=0.01), k
    # the transient was there: some whole-run maximum is off by more than 1 %
    assert any(whole[k] > 1.01 * periodic[k] for k in periodic if periodic[k] > 0)
    # no transient in a run started settled (at most one saved state: the fit's edge)
    assert start_up_transient(mfile, again).time_s <= 1.5 * (again.ts[1] - again.ts[0])
    return transient.time_s


@pytest.mark.extended  # two 1 s runs of the four-bar and a compilation: ~20 s
def test_four_bar_settled_maxima_are_the_periodic_motions():
    t = _check_against_settled_rerun("four_bar_wear")
    assert 0.04 <= t <= 0.1  # the pin's first impact at 5 ms, rung out in ~60 ms


@pytest.mark.extended  # two 2 s runs of the rig and a compilation: ~15 s
def test_rig_settled_maxima_are_the_periodic_motions():
    t = _check_against_settled_rerun("rig")
    assert 0.1 <= t <= 0.3  # the pin's first impact at 10 ms, rung out in ~0.2 s


@pytest.mark.extended  # two 2 s runs and a compilation: ~15 s
def test_a_pin_that_leaves_the_wall_every_cycle_is_no_transient():
    """The 0.5 mm clearance slider-crank: its pin flies across the clearance
    and strikes the wall in every cycle (roughness of hundreds of N after the
    transient); the settled run started from the first run's end still
    reports no transient, and the settled maxima are the next cycle's."""
    _check_against_settled_rerun("clearance_slider_crank")
