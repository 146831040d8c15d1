"""What the figures show, read from their data (`diffwear.plots.captured`),
not their pixels: loci zoomed on the data inside the worn bushing's outline,
legends clear of every data point, angles in degrees, no panel of zeros,
wear titles with the cycles reached and the bushing wall and the depth limit
drawn."""

import json
import math
from types import SimpleNamespace

import numpy as np
import pytest
from figure_checks import assert_legend_names_drawn
from matplotlib.lines import Line2D

from diffwear import plots
from diffwear.choices import SHIPPED_MECHANISMS
from diffwear.cli import main
from diffwear.plots import calibration as plots_calibration
from diffwear.plots import wear as plots_wear
from diffwear.wear.status import RESULTS

# ----------------------------------------------------------------------------- readers


def _display_points(ax, per_segment: int = 40) -> np.ndarray:
    """Every point of the axes' lines and markers in display coordinates,
    segments filled in (a legend over a line's middle covers data too), kept
    where the axes show them (inside its frame)."""
    pts = []
    for line in ax.get_lines():
        xy = line.get_transform().transform(np.asarray(line.get_xydata(), dtype=float))
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if len(xy) > 1 and line.get_linestyle() not in ("None", "", " "):
            s = np.linspace(0.0, 1.0, per_segment, endpoint=False)
            xy = np.concatenate([(xy[:-1, None, :] * (1 - s[:, None])
                                  + xy[1:, None, :] * s[:, None]).reshape(-1, 2), xy[-1:]])
        pts.append(xy)
    for coll in ax.collections:
        off = coll.get_offsets()
        if len(off):
            pts.append(coll.get_offset_transform().transform(np.asarray(off, dtype=float)))
    if not pts:
        return np.zeros((0, 2))
    xy = np.concatenate(pts)
    box = ax.get_window_extent()
    inside = ((xy[:, 0] >= box.x0) & (xy[:, 0] <= box.x1)
              & (xy[:, 1] >= box.y0) & (xy[:, 1] <= box.y1))
    return xy[inside]


def _assert_legends_clear(fig):
    """No legend's box holds a data point of any axes of the figure, every
    legend entry names an artist drawn inside its axes, and nothing is cut
    off at the figure's edge."""
    _assert_inside_the_figure(fig)
    assert_legend_names_drawn(fig)
    points = np.concatenate([_display_points(ax) for ax in fig.axes] + [np.zeros((0, 2))])
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    for leg in legends:
        box = leg.get_window_extent()
        covered = ((points[:, 0] > box.x0) & (points[:, 0] < box.x1)
                   & (points[:, 1] > box.y0) & (points[:, 1] < box.y1))
        assert not covered.any(), f"legend {[t.get_text() for t in leg.get_texts()]} " \
                                  f"covers {covered.sum()} data points"
    return legends


def _assert_inside_the_figure(fig):
    """Every axes' labels, title and legend lie within the figure (none cut
    off at its edge)."""
    fig.canvas.draw()
    page = fig.bbox
    for ax in fig.axes + [None]:
        parts = (list(fig.texts) if ax is None
                 else [ax.xaxis.label, ax.yaxis.label, ax.title, ax.get_legend()])
        for part in parts:
            if part is not None and part.get_visible() and (
                    not hasattr(part, "get_text") or part.get_text()):
                box = part.get_window_extent()
                assert (box.x0 >= page.x0 - 0.5 and box.x1 <= page.x1 + 0.5
                        and box.y0 >= page.y0 - 0.5 and box.y1 <= page.y1 + 0.5), \
                    (getattr(part, "get_text", lambda: "legend")(), box, page)


def _assert_angles_in_degrees(fig):
    """No axis is in radians, and every axis of an angle (its label names an
    angle or starts with its symbol) says deg."""
    labels = [lab for ax in fig.axes for lab in (ax.get_xlabel(), ax.get_ylabel())]
    for lab in labels:
        assert "[rad]" not in lab, lab
        if "angle" in lab or lab.startswith(("θ", "φ", "phi")):
            assert "[deg]" in lab, lab


def _assert_no_zero_axes(fig):
    for ax in fig.axes:
        lines = [ln for ln in ax.get_lines() if len(ln.get_ydata())]
        if lines:
            assert any(np.any(np.asarray(ln.get_ydata(), dtype=float) != 0) for ln in lines), \
                ax.get_ylabel()


def _line(ax, label_part: str, *, exact: bool = False) -> Line2D:
    """The one line of ``ax`` whose label holds (``exact``: is) ``label_part``."""
    (line,) = [ln for ln in ax.get_lines()
               if (label_part == ln.get_label() if exact else label_part in ln.get_label())]
    return line


def _horizontal_at(ax, value: float, label_part: str) -> Line2D:
    """The labelled horizontal line at ``value``."""
    line = _line(ax, label_part)
    y = np.asarray(line.get_ydata(), dtype=float)
    assert np.all(y == value), (label_part, y)
    return line


# ----------------------------------------------------------------------------- study figures

C_MM = 0.033          # rig clearance, Table 7-2: 9.533 - 9.5 mm
N_THETA = 180


def _rig_like_wear():
    """A worn profile like the Ch. 7 rig's (a 0.445 mm pocket at 170 deg,
    Fig. 7-4's shape) and the pin's loci: the first cycle on the unworn
    bore's rim near 180 deg, the last in the pocket's bottom."""
    theta = 2 * np.pi * np.arange(N_THETA) / N_THETA
    centre = np.radians(170.0)
    gap = np.angle(np.exp(1j * (theta - centre)))
    depth_mm = 0.445 * np.clip(np.cos(gap), 0.0, None) ** 1.5  # one pocket, 180 deg wide
    crank = 2 * np.pi * np.arange(90) / 90
    wobble = np.radians(6.0) * np.sin(crank)
    first = (C_MM + 0.002) * np.stack([np.cos(np.pi + wobble), np.sin(np.pi + wobble)], 1)
    r_last = C_MM + 0.445 + 0.002
    last = r_last * np.stack([np.cos(centre + wobble / 4), np.sin(centre + wobble / 4)], 1)
    force = 130 + 30 * np.cos(crank)

    def hist(offset_mm):
        return SimpleNamespace(offset=offset_mm * 1e-3, force_magnitude=force)

    history = (np.linspace(535, 21400, 40), np.linspace(0.011, 0.445, 40),
               np.linspace(2.6, 106.7, 40))
    return theta, depth_mm, crank, hist(first), hist(last), history


@pytest.fixture(scope="module")
def study_figures(tmp_path_factory):
    theta, depth_mm, crank, first, last, history = _rig_like_wear()
    folder = tmp_path_factory.mktemp("wear")
    out = SimpleNamespace(file=lambda name: folder / name)
    thesis = {"EFM": {"max_wear_depth_mm": 0.426, "wear_volume_mm3": 106.7},
              "measured": {"max_wear_depth_mm": 0.485}}
    with plots.captured() as figures:
        names = plots_wear.wear_figures(
            out, name="rig", theta=theta, depth_mm=depth_mm, history=history, crank=crank,
            first=first, last=last, thesis=thesis,
            lines=plots_wear.Lines(clearance_mm=C_MM, wall_mm=6.342))
    assert sorted(names) == sorted(figures) and all((folder / n).is_file() for n in names)
    return figures, SimpleNamespace(theta=theta, depth_mm=depth_mm, first=first, last=last)


def test_the_locus_is_zoomed_on_the_pin_in_its_worn_pocket(study_figures):
    """The locus panel holds the unworn clearance circle (radius c), the worn
    outline (radius c + depth at each bushing angle, the pocket's bottom at
    170 deg), both loci, at equal aspect, all inside the limits with a
    margin, and the limits within twice the data's span (not the 0.5 mm
    strip that hid the pin)."""
    figures, d = study_figures
    fig = figures["contact_locus_and_force.png"]
    fig.canvas.draw()
    ax = fig.axes[0]
    assert ax.get_aspect() == 1.0
    circle = _line(ax, "clearance circle, c = 0.033 mm")
    assert np.hypot(*circle.get_xydata().T) == pytest.approx(C_MM, rel=1e-12)
    outline = _line(ax, "worn bushing")
    r = np.hypot(*outline.get_xydata().T)
    assert r[:-1] == pytest.approx(C_MM + d.depth_mm, rel=1e-12, abs=1e-15)
    bottom = outline.get_xydata()[np.argmax(r)]
    assert np.degrees(np.arctan2(bottom[1], bottom[0])) == pytest.approx(170.0, abs=1.0)
    last = _line(ax, "last cycle").get_xydata()
    assert last == pytest.approx(d.last.offset * 1e3, rel=1e-12)

    data = np.concatenate([ln.get_xydata() for ln in ax.get_lines()])
    lo, hi = data.min(axis=0), data.max(axis=0)
    span = float(np.max(hi - lo))
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    margin = 0.03 * span
    assert x0 < lo[0] - margin and x1 > hi[0] + margin
    assert y0 < lo[1] - margin and y1 > hi[1] + margin
    assert max(x1 - x0, y1 - y0) < 2.0 * span  # zoomed: the data fill the panel
    _assert_legends_clear(fig)
    _assert_angles_in_degrees(fig)
    assert max(_line(fig.axes[1], "first").get_xdata()) > 2 * np.pi  # crank angle in deg


def test_the_wear_profile_is_in_degrees_with_its_legend_off_the_flanks(study_figures):
    """The profile spans 0..360 deg (the grid's 2 deg steps, closed at 360)
    and its legend covers no point of it: not the falling flank at
    225-245 deg that the legend hid."""
    figures, d = study_figures
    fig = figures["wear_profile.png"]
    ax = fig.axes[0]
    x, y = _line(ax, "diffwear").get_data()
    assert x[0] == 0.0 and x[-1] == 360.0 and np.diff(x) == pytest.approx(2.0)
    assert y[:-1] == pytest.approx(d.depth_mm) and y[-1] == y[0]
    assert ax.get_xlim() == (0.0, 360.0)
    _assert_angles_in_degrees(fig)
    assert _assert_legends_clear(fig)
    # the 6.3 mm wall is 14x the wear: not drawn, so not a legend entry, but
    # named in the legend's title
    assert not [ln for ln in ax.get_lines() if "bushing wall" in ln.get_label()]
    assert ax.get_ylim()[1] < 6.342
    legend = fig.axes[-1].get_legend()
    assert legend.get_title().get_text() == "bushing wall 6.342 mm: off this scale"
    assert "bushing wall" not in " ".join(t.get_text() for t in legend.get_texts())


def test_the_wear_history_title_says_the_cycles_reached(study_figures):
    figures, _ = study_figures
    fig = figures["wear_history.png"]
    title = fig.axes[0].get_title()
    assert "after 21,400 cycles" in title and "stopped" not in title
    _assert_legends_clear(fig)
    _assert_no_zero_axes(fig)


# ----------------------------------------------------------------------------- shared panels


def test_stacked_leaves_out_curves_and_panels_of_zeros_and_names_them(tmp_path):
    """A ground-fixed driver's force (exactly 0) is no panel; a slider's y at
    1e-19 m beside a crank's 0.04 m is no curve; a curve 1e-6 of its panel's
    largest (real, if small) stays, and so does a small value on a log axis;
    the title names the two left out."""
    t = np.linspace(0.0, 2.0, 201)
    with plots.captured() as figures:
        plots.stacked(tmp_path / "r.png", t, [
            ("|F| [N]", {"driver on crank": np.zeros_like(t)}),
            ("y [m]", {"crank": 0.04 * np.sin(np.pi * t), "slider": 1e-19 * np.cos(t),
                       "rod": 4e-8 * np.sin(np.pi * t)}),
            ("max |Φ| [m, rad]", {"all constraints": 1e-14 + 1e-13 * t}),
        ], xlabel="time [s]", title="joint reactions", logy=[False, False, True])
    fig = figures["r.png"]
    assert [ax.get_ylabel() for ax in fig.axes] == ["y [m]", "max |Φ| [m, rad]"]
    assert [ln.get_label() for ln in fig.axes[0].get_lines()] == ["crank", "rod"]
    title = fig.axes[0].get_title().replace("\n", " ")
    assert "driver on crank (|F| [N])" in title and "slider (y [m])" in title
    _assert_no_zero_axes(fig)
    _assert_legends_clear(fig)


def test_a_wear_run_stopped_at_the_wall_says_so_and_draws_wall_and_limit(tmp_path):
    """wear.png of a run that wore through its 1 mm wall at 122,862 of the
    200,000 cycles asked: the title gives the cycles reached and why, both
    panels draw the wall and the limit as labelled lines, the y axis shows
    the wall, and the history marks the limit's cycle."""
    theta = 2 * np.pi * np.arange(N_THETA) / N_THETA
    depth = 1e-3 * np.clip(np.cos(theta - np.pi), 0.0, None) ** 2
    cycles = np.linspace(0.0, 122862.0, 30)
    peak = 1e-3 * cycles / cycles[-1]
    title = plots.wear_title("new rig", {"crank_rod": 122862.0},
                             {"crank_rod": RESULTS.wall_reached}, model="quasi-static")
    assert title == ("new rig: wear after 122,862 cycles (stopped: wall reached) "
                     "(quasi-static model)")
    with plots.captured() as figures:
        plots.wear_panels(tmp_path / "wear.png", {"crank_rod": (theta, depth)},
                          {"crank_rod": (cycles, peak)}, title=title,
                          walls={"crank_rod": 1e-3}, limit=0.5e-3,
                          lives={"crank_rod": 61431.0})
    fig = figures["wear.png"]
    assert fig.texts[0].get_text().replace("\n", " ") == title
    for ax in fig.axes:
        _horizontal_at(ax, 1.0, "bushing wall: 1 mm")
        _horizontal_at(ax, 0.5, "depth limit 0.5 mm")
        assert ax.get_ylim()[1] > 1.0
    at_limit = _line(fig.axes[1], "at the limit").get_xydata()
    assert at_limit.tolist() == [[61431.0, 0.5]]
    assert fig.axes[0].get_xlabel() == "bushing angle [deg]"
    assert max(fig.axes[0].get_lines()[0].get_xdata()) == 360.0
    _assert_legends_clear(fig)


def test_the_commands_wear_figure_of_a_run_stopped_at_the_wall(tmp_path):
    """`diffwear run`'s wear writer, given a joint that wore through its 1 mm
    wall at 122,862 of the 200,000 cycles asked (as the quasi-static model
    returns it): wear.png says the cycles reached and why, not the cycles
    asked, and draws the wall and the --limit on both panels."""
    from diffwear.cli.run import wear_outputs
    from diffwear.io import OutputDir

    theta = 2 * np.pi * np.arange(N_THETA) / N_THETA
    cycles = np.linspace(0.0, 122862.0, 41)
    wear = {"crank_rod": {
        "theta": theta, "depth": 1e-3 * np.clip(np.cos(theta - 3.0), 0.0, None) ** 2,
        "history_cycles": cycles, "history_peak": 1e-3 * cycles / cycles[-1],
        "volume": 5e-8, "cycles": 122862.0, "wall": 1e-3, "status": RESULTS.wall_reached,
        "contact_margin": 3.0, "contact_margin_worn": 2.0, "cycles_to_limit": 61431.0,
        "model": "quasi-static"}}
    mfile = SimpleNamespace(title="new rig", file="new_rig.toml")
    with plots.captured() as figures:
        written = wear_outputs(mfile, wear, limit=0.5e-3)
        assert not figures   # gathered, not drawn: the files are written together
        OutputDir(tmp_path / "run").write(written["outputs"])
    assert written["stopped"] and written["figure"] == "wear.png"
    assert written["outputs"].names == ["wear_profile_crank_rod.csv",
                                        "wear_history_crank_rod.csv", "wear.png"]
    assert sorted(p.name for p in (tmp_path / "run").iterdir()
                  if not p.name.startswith(".")) == sorted(written["outputs"].names)
    fig = figures["wear.png"]
    title = fig.texts[0].get_text().replace("\n", " ")
    assert title == ("new rig: wear after 122,862 cycles (stopped: wall reached) "
                     "(quasi-static model)")
    for ax in fig.axes:
        _horizontal_at(ax, 1.0, "bushing wall: 1 mm")
        _horizontal_at(ax, 0.5, "depth limit 0.5 mm")
    history = _line(fig.axes[1], "crank_rod", exact=True).get_xydata()
    assert history[-1].tolist() == [122862.0, 1.0]
    _assert_legends_clear(fig)
    _assert_angles_in_degrees(fig)


def test_a_run_that_reached_its_cycles_is_titled_by_them():
    assert plots.wear_title("f", {"a": 5e4, "b": 5e4}, {"a": RESULTS.ok, "b": RESULTS.ok},
                            model="dynamic") == "f: wear after 50,000 cycles (dynamic model)"
    two = plots.wear_title("f", {"a": 3e4, "b": 5e4}, {"a": RESULTS.wall_reached, "b": RESULTS.ok},
                           model="quasi-static")
    assert two == ("f: wear after 30,000 cycles (a), 50,000 cycles (b) "
                   "(stopped: a: wall reached) (quasi-static model)")


def test_the_other_figures_keep_their_legends_and_labels_clear(tmp_path):
    """The pin-pivot, design, contact-locus and sweep figures: legends off
    the data, nothing cut off, angles in degrees."""
    from diffwear.plots import design as plots_design
    from diffwear.plots import pin_pivot as plots_pin_pivot
    from diffwear.plots import sweep as plots_sweep

    angle = np.linspace(-180.0, 178.0, 180)
    bump = np.clip(np.cos(np.radians(angle)), 0.0, None)
    sweeps = np.linspace(1e4, 2e5, 20)
    d, h = np.linspace(40e-3, 55e-3, 6), np.linspace(10e-3, 40e-3, 7)
    x = np.array([46.58e-3, 48.60e-3, 37.25e-3, 14.00e-3])  # Table 8-4
    with plots.captured() as figures:
        plots_pin_pivot.profile_figure(
            tmp_path / "pp_profiles.png", angle_deg=angle,
            simulated={"pin, 200,000 sweeps": 1.2 * bump, "pivot, 200,000 sweeps": 0.4 * bump},
            direct={"pin (direct)": 1.1 * bump}, pressure=30 * bump, title="pin-pivot")
        plots_pin_pivot.history_figure(
            tmp_path / "pp_history.png", sweeps=sweeps, max_pin_mm=sweeps * 6e-6,
            max_pivot_mm=sweeps * 2e-6, fit_pin=(6e-9, 0.0), fit_pivot=(2e-9, 0.0),
            target=408000, direct=None, thesis={"model": 1.867, "measured": 2.0},
            title="pin-pivot")
        plots_design.life_map(tmp_path / "life.png",
                              {"d_m": d, "h_m": h, "cyc1": np.outer(d, h) * 1e9}, 1, x, x * 1.01)
        plots.polar_loci(tmp_path / "loci.png",
                         {"EFM, c = 0.5 mm": (np.radians(angle) + np.pi, 1 + 0 * bump)},
                         title="contact locus")
        plots_sweep.line(tmp_path / "line.png", d, d ** 2, xlabel="d [m]", ylabel="y",
                         title="a sweep")
    assert len(figures) == 5
    for name, fig in figures.items():
        _assert_legends_clear(fig)
        _assert_angles_in_degrees(fig)
        _assert_no_zero_axes(fig)



def test_a_sweeps_long_title_is_wrapped_inside_the_figure(tmp_path):
    """The heatmap and line of a sweep are titled "<file title>: <output>"; the
    shipped rig sweep file's title makes that wider than the figure, so it
    is broken into lines that all lie inside it."""
    from diffwear.plots import sweep as plots_sweep

    title = ("Rig: clearance x wear coefficient (Ch. 7, 21,400 cycles): "
             "mean_joint_force_N")  # design_studies/sweep_rig_clearance_k.toml's title
    c, k = np.array([2e-5, 3.3e-5, 5e-5, 1e-4]), np.geomspace(2.525e-13, 7.575e-13, 4)
    with plots.captured() as figures:
        plots_sweep.heatmap(tmp_path / "map.png", k, c, np.outer(c, k) * 1e15,
                            xlabel="k [1/Pa]", ylabel="clearance [m]", title=title)
        plots_sweep.line(tmp_path / "line.png", c, c ** 2, xlabel="clearance [m]",
                         ylabel="y", title=title)
    assert len(figures) == 2
    for fig in figures.values():
        text = fig.axes[0].get_title()
        assert "\n" in text and text.replace("\n", " ") == title
        _assert_inside_the_figure(fig)

# ----------------------------------------------------------------------------- calibration


def test_calibration_fits_plot_angles_in_degrees(tmp_path):
    """The measured profile and force trace go to the plots in degrees (the
    command's unit table converts the datasets' radians): a full turn spans
    0..358 deg on axes labelled deg, the legends off the data."""
    from diffwear.calibrate.outputs import UNIT

    theta = 2 * np.pi * np.arange(180) / 180
    fits = []
    for kind, name in (("profile", "profile_21400"), ("force", "force_trace")):
        scale, unit, xlabel, xscale = UNIT[kind]
        y = 1e-4 * (1 + np.cos(theta)) if kind == "profile" else 100 + 20 * np.sin(theta)
        fits.append(plots_calibration.SeriesFit(
            name=name, kind=kind, unit=unit, xlabel=xlabel, scale=scale, x=theta * xscale,
            y=y, sigma=float(np.std(y)) / 10, holdout=np.zeros(180, bool), base=y * 1.01,
            chosen=y, chosen_label="with run-in", cycles=21400.0))
    with plots.captured() as figures:
        for f in fits:
            plots_calibration.series_fit(tmp_path / f"fit_{f.name}.png", f)
        plots_calibration.residual_structure(
            tmp_path / "residual_structure.png", fits, [np.sin(3 * theta)] * 2,
            [np.full(180, 21400.0)] * 2, None)
    for name, fig in figures.items():
        _assert_angles_in_degrees(fig)
        _assert_legends_clear(fig)
    for f in fits:
        ax = figures[f"fit_{f.name}.png"].axes[0]
        assert "[deg]" in ax.get_xlabel()
        assert max(_line(ax, "base fit").get_xdata()) == pytest.approx(358.0)
    ax = figures["residual_structure.png"].axes[0]
    assert ax.get_xlabel() == "bushing angle [deg]"
    assert max(ax.get_lines()[0].get_xdata()) == pytest.approx(358.0)


def test_a_pooled_band_says_so_in_the_legend(tmp_path):
    """An open answer's band pools both models while the line is the first
    model's: the legend says both, and the band spans the given bounds."""
    x = np.linspace(0.0, 10.0, 11)
    y = np.ones(11)
    f = plots_calibration.SeriesFit(
        name="worn_volume", kind="volume", unit="mm^3", xlabel="cycles", scale=1.0, x=x, y=y,
        sigma=0.1, holdout=np.zeros(11, bool), base=y, chosen=1.1 * y,
        chosen_label="with run_in (the first of two explanations)", cycles=None,
        band=(y - 0.5, y + 2.0), band_label="90 % predictive band, pooled over both")
    with plots.captured() as figures:
        plots_calibration.series_fit(tmp_path / "fit.png", f)
    ax = figures["fit.png"].axes[0]
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "90 % predictive band, pooled over both" in texts
    assert "with run_in (the first of two explanations)" in texts
    (band,) = ax.collections[:1]
    ys = band.get_paths()[0].vertices[:, 1]
    assert ys.min() == pytest.approx(0.5) and ys.max() == pytest.approx(3.0)


# ----------------------------------------------------------------------------- a user's file

# A new user's slider-crank: the shipped Ch. 7 rig file (Tables 7-1, 7-2)
# copied and edited, as the README's tour starts one, to a 1 mm bushing wall
# and 100x the PTFE wear coefficient: the joint wears through in a few
# hundred cycles on the quasi-static model.
def _edited(text: str, *edits: tuple[str, str]) -> str:
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new, 1)
    return text


THIN_WALL_RIG = _edited(
    (SHIPPED_MECHANISMS / "rig.toml").read_text(),
    ('layer_thickness = "6.342 mm", depth = "13.1 mm", restitution = 0.8',
     'layer_thickness = "1 mm", depth = "13.1 mm"'),
    ('coefficient = "5.05e-4 mm^3/(N m)"', 'coefficient = "5.05e-2 mm^3/(N m)"'),
    ("n_save = 401", "n_save = 201"))


@pytest.mark.extended  # ~80 s: the command compiles the motion, the wear and the life
def test_a_users_file_worn_through_its_wall_has_it_in_its_figures(tmp_path):
    """The run stops at the 1 mm wall (exit 3, outputs written); wear.png's
    title gives the cycles reached (summary.json's), not the 100,000 asked,
    and why; both panels draw the wall and the 0.5 mm limit; the history
    ends at the wall.  reactions.png draws no panel of zeros (the
    ground-fixed driver's force) and names it; trajectory.png draws the
    crank angle in degrees (one turn in the 2 s: 360 deg)."""
    path = tmp_path / "thin.toml"
    path.write_text(THIN_WALL_RIG)
    out = tmp_path / "thin"
    with plots.captured() as figures:
        assert main(["run", str(path), "--cycles", "100000", "--limit", "0.5",
                     "--model", "quasi-static", "--out", str(out), "--quiet"]) == 3
    joint = json.loads((out / "summary.json").read_text())["joints"]["crank_rod"]
    assert joint["status"] == "wall_reached" and 100 < joint["cycles"] < 100000
    report = (out / "report.md").read_text()
    assert "compiling the motion's integrator and the quasi-static wear model" in report
    assert "dynamic wear model" not in report
    wear = figures["wear.png"]
    title = wear.texts[0].get_text().replace("\n", " ")
    assert f"wear after {joint['cycles']:,.0f} cycles (stopped: wall reached)" in title
    assert "100,000" not in title
    for ax in wear.axes:
        _horizontal_at(ax, 1.0, "bushing wall: 1 mm")
        _horizontal_at(ax, 0.5, "depth limit 0.5 mm")
    history = _line(wear.axes[1], "crank_rod", exact=True).get_xydata()
    assert history[-1, 0] == joint["cycles"] and history[-1, 1] == pytest.approx(1.0, rel=0.01)
    assert joint["cycles_to_limit"] == pytest.approx(joint["cycles"] / 2, rel=0.1)  # linear
    _assert_legends_clear(wear)

    reactions = figures["reactions.png"]
    assert [ax.get_ylabel() for ax in reactions.axes] == ["M about COM [N m]"]
    assert "driver on crank (|F| [N])" in reactions.axes[0].get_title().replace("\n", " ")
    trajectory = figures["trajectory.png"]
    phi = [ax for ax in trajectory.axes if ax.get_ylabel().startswith("φ")][0]
    assert phi.get_ylabel() == "φ [deg]"
    assert max(_line(phi, "crank").get_ydata()) == pytest.approx(360.0, rel=1e-6)
    for fig in figures.values():
        _assert_no_zero_axes(fig)
        _assert_angles_in_degrees(fig)
        _assert_legends_clear(fig)
    assert math.isfinite(joint["max_wear_depth_mm"])


@pytest.mark.extended  # ~70 s: the study compiles the quasi-static evolution
def test_the_rig_studys_locus_shows_the_pin_in_its_worn_pocket(tmp_path):
    """The Ch. 7 rig on the quasi-static model, 21,400 cycles: the last
    cycle's pin centre (contact_locus_last_cycle.csv) sits on the drawn worn
    outline, within the EFM springs' few-um penetration of c + depth at its
    angle (wear_profile.csv), and the panel is zoomed on the outline with
    nothing cut off."""
    out = tmp_path / "rig"
    with plots.captured() as figures:
        assert main(["study", "rig-21400", "--model", "quasi-static", "--out", str(out),
                     "--quiet"]) == 0
    profile = np.loadtxt(out / "wear_profile.csv", delimiter=",", skiprows=1)
    locus = np.loadtxt(out / "contact_locus_last_cycle.csv", delimiter=",", skiprows=1)
    e = locus[:, 1:3]  # offset_x_mm, offset_y_mm
    angle = np.mod(np.arctan2(e[:, 1], e[:, 0]), 2 * np.pi)
    reach = C_MM + np.interp(angle, profile[:, 0], profile[:, 1], period=2 * np.pi)
    assert np.hypot(*e.T) == pytest.approx(reach, abs=0.01)
    fig = figures["contact_locus_and_force.png"]
    fig.canvas.draw()
    ax = fig.axes[0]
    outline = _line(ax, "worn bushing").get_xydata()
    assert np.max(np.hypot(*outline.T)) == pytest.approx(C_MM + profile[:, 1].max(), rel=1e-9)
    assert _line(ax, "last cycle").get_xydata() == pytest.approx(e, rel=1e-6)
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    data = np.concatenate([ln.get_xydata() for ln in ax.get_lines()])
    assert x0 < data[:, 0].min() and x1 > data[:, 0].max()
    assert y0 < data[:, 1].min() and y1 > data[:, 1].max()
    assert max(x1 - x0, y1 - y0) < 1.3 * np.ptp(data, axis=0).max()
    for fig in figures.values():
        _assert_legends_clear(fig)
        _assert_angles_in_degrees(fig)
        _assert_no_zero_axes(fig)


def test_long_calibration_titles_stay_inside_their_figures(tmp_path):
    """The discrepancy's title of an open answer's first explanation and the
    posterior's over one number (a figure 3.2 inches wide) are wrapped, not
    cut off at the figure's edge."""
    from diffwear.plots.files import captured

    x = np.linspace(0.0, 16050.0, 50)
    with captured() as figures:
        plots_calibration.discrepancy(
            tmp_path / "discrepancy.png", x, 0.3 * np.sin(x / 3000.0), np.full(x.size, 0.1),
            "cycles", "learned discrepancy of k over the cycle count (the first of two "
            "explanations)", (0.0, 16050.0))
        plots_calibration.posterior(
            tmp_path / "posterior.png", {"k [mm^3/(N m)]": np.linspace(6.39, 6.44, 200)},
            np.full(200, 1 / 200), "posterior of the first of two explanations (Laplace, "
            "importance-weighted)")
    for fig in figures.values():
        _assert_inside_the_figure(fig)
    assert "\n" in figures["discrepancy.png"].axes[0].get_title()


def test_the_best_candidate_shows_in_the_candidates_figure(tmp_path):
    """Bars are drawn above the best candidate's criterion, so the best one's
    has no length: every bar's end is a dot, at its criterion above the
    best, and the best is labelled."""
    from diffwear.plots.files import captured

    criteria = [1200.0, 1203.0, 1250.0, 5000.0]
    with captured() as figures:
        plots_calibration.candidates(tmp_path / "candidates.png",
                                     ["angle", "run_in", "pressure_exponent", "third_body"],
                                     criteria, [True, True, False, True], ["run_in"], 6.0)
    ax = figures["candidates.png"].axes[0]
    top = 60.0   # the axis ends at ten windows
    ends = ax.collections[0].get_offsets()
    np.testing.assert_allclose(ends[:, 0], np.minimum(np.subtract(criteria, 1200.0), top))
    assert [t.get_text() for t in ax.texts] == ["best", " 3,800 "]
