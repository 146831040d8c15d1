"""A lubricated clearance joint in a mechanism file (``lubricant = {...}``):
its units, its checks, the shipped lubricated rig, and what ``diffwear run
--cycles`` reports of its film."""

import csv
import json
import math

import jax
import numpy as np
import pytest

from diffwear.choices import SHIPPED_MECHANISMS
from diffwear.cli import main
from diffwear.config import load
from diffwear.config import units as U
from diffwear.contact import MixedLubrication, ShippedFiniteFilm

LUBRICATED = SHIPPED_MECHANISMS / "rig_lubricated.toml"
OIL = 'lubricant = { grade = "ISO VG 10", temperature = "25 degC", roughness = "0.65 um" }'
ROUGH = 'roughness = "0.65 um"'  # the last key of the shipped rig's lubricant
GRADE = 'grade = "ISO VG 10", temperature = "25 degC"'
FILM_KEYS = ("min_film_thickness_um", "film_ratio_min", "asperity_load_share")


def _file(tmp_path, name, *edits, text=None):
    """The shipped lubricated rig with ``edits`` (old, new), on a 90-node grid
    and a short motion (the wear and the film come from the cycle's loads,
    not from the motion)."""
    text = LUBRICATED.read_text() if text is None else text
    for old, new in (("n_theta = 180", "n_theta = 90"),
                     ('duration = "2 s"', 'duration = "0.01 s"'),
                     ("n_save = 401", "n_save = 11"), *edits):
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


def test_viscosity_units():
    assert U.parse_quantity("1 cP", "viscosity") == 1e-3
    assert U.parse_quantity("1 mPa s", "viscosity") == 1e-3
    assert U.parse_quantity("1 P", "viscosity") == 0.1
    assert U.parse_quantity("68 mPa*s", "viscosity") == 0.068
    assert U.to_si(50, "cP", "viscosity") == 0.05
    with pytest.raises(Exception, match="'Pa' is a pressure unit, not viscosity"):
        U.parse_quantity("0.05 Pa", "viscosity")


def test_the_shipped_lubricated_rig_is_the_rig_with_its_oil():
    el = load("rig_lubricated").mechanism.element("crank_rod")
    dry = load("rig").mechanism.element("crank_rod")
    # the finite film by default: L/D = 13.1 / 19 = 0.69 is no short bearing
    assert isinstance(el.law, MixedLubrication) and isinstance(el.law.film, ShippedFiniteFilm)
    assert float(el.law.film.radius) == float(dry.pin_radius) == 0.0095
    assert float(el.law.film.max_eccentricity_ratio) == pytest.approx(1 - 0.65 / 33, rel=1e-12)
    # ISO VG 10 at 25 degC by ASTM D341 (hand computation: the Walther line through
    # log log 10.7 at log 313.15 and log log 3.2 at log 373.15 gives nu = 17.35 mm^2/s,
    # times 870 (1 - 6.5e-4 x 10) kg/m^3)
    assert float(el.law.film.viscosity) == pytest.approx(17.3488e-6 * 864.345, rel=1e-4)
    assert float(el.law.roughness) == 0.65e-6  # m
    assert float(el.law.film.length) == float(dry.law.depth) == 0.0131
    assert float(el.law.film.clearance) == pytest.approx(33e-6, rel=1e-9)
    # its asperities are the dry rig's foundation, leaf by leaf
    for a, b in zip(jax.tree.leaves(el.law.asperity), jax.tree.leaves(dry.law), strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """``diffwear run --cycles 2000`` on the lubricated rig at 3 and
    200 mPa s (boundary and mixed lubrication on its finite film), and on
    the same file without its oil."""
    tmp = tmp_path_factory.mktemp("lubricant")
    cases = {"thin": _file(tmp, "thin", (GRADE, 'viscosity = "3 mPa s"')),
             "thick": _file(tmp, "thick", (GRADE, 'viscosity = "200 mPa s"')),
             "dry": _file(tmp, "dry", (OIL, ""))}
    out = {}
    for name, path in cases.items():
        folder = tmp / f"out-{name}"
        assert main(["run", str(path), "--cycles", "2000", "--out", str(folder),
                     "--quiet"]) == 0, name
        out[name] = folder
    return out


def _joint(folder):
    return json.loads((folder / "summary.json").read_text())["joints"]["crank_rod"]


@pytest.mark.slow  # four 21,400-cycle orbit runs of the rig: ~10 min
def test_a_thicker_oil_keeps_a_thicker_film_and_wears_less_than_dry(runs):
    thin, thick, dry = (_joint(runs[k]) for k in ("thin", "thick", "dry"))
    assert thick["min_film_thickness_um"] > thin["min_film_thickness_um"]
    assert thick["asperity_load_share"] < thin["asperity_load_share"]
    assert thick["max_wear_depth_mm"] < thin["max_wear_depth_mm"]
    for oiled in (thin, thick):
        assert dry["max_wear_depth_mm"] >= oiled["max_wear_depth_mm"]
        assert dry["wear_volume_mm3"] >= oiled["wear_volume_mm3"]
    assert "lubricant" not in dry and "min_film_thickness_um" not in dry
    assert thin["lubricant"] == {"viscosity_Pa_s": 0.003, "roughness_um": 0.65,
                                 "bearing": "finite"}
    for w in (thin, thick):
        assert w["min_film_thickness_um"] >= 0.0 and w["max_interference_um"] >= 0.0
        for key in FILM_KEYS:
            for k in (key, key + "_worn"):
                assert isinstance(w[k], float) and math.isfinite(w[k]), k
        assert 0.0 <= w["asperity_load_share"] <= 1.0


@pytest.mark.slow  # the runs above
def test_the_film_files_and_the_report(runs):
    folder = runs["thin"]
    summary = json.loads((folder / "summary.json").read_text())
    assert {"film_crank_rod.csv", "film_crank_rod.png"} <= set(summary["files"])
    with open(folder / "film_crank_rod.csv", newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["crank_angle_deg", "h_min_um", "film_ratio", "interference_um",
                       "asperity_share", "film_load_N", "asperity_load_N", "h_min_um_worn",
                       "film_ratio_worn", "interference_um_worn", "asperity_share_worn",
                       "film_load_N_worn", "asperity_load_N_worn"]
    data = np.array(rows[1:], dtype=float)
    assert data.shape == (180, 13) and np.all(np.isfinite(data))
    # a film thickness is never negative; where no gap is left the overlap is the
    # asperities' interference, and one of the two is zero at every sample
    assert np.all(data[:, [1, 2, 3, 7, 8, 9]] >= 0.0)
    assert np.all(data[:, 1] * data[:, 3] == 0.0) and np.all(data[:, 7] * data[:, 9] == 0.0)
    assert data[0, 0] == 0.0 and data[-1, 0] == pytest.approx(358.0)
    w = summary["joints"]["crank_rod"]
    assert np.min(data[:, 1]) == pytest.approx(w["min_film_thickness_um"])
    assert np.mean(data[:, 4]) == pytest.approx(w["asperity_load_share"])
    assert np.max(data[:, 3]) == pytest.approx(w["max_interference_um"])
    assert (folder / "film_crank_rod.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    report = (folder / "report.md").read_text()
    assert "## Lubrication" in report and "(film_crank_rod.png)" in report
    assert "boundary" in report  # lambda < 1 at 3 mPa s


@pytest.mark.parametrize("old, new, words", [
    (GRADE, 'viscosity = "0 Pa s"',
     ["joints[1].lubricant.viscosity", "'0 Pa s'", "out of range", "(0, 10] Pa s"]),
    (GRADE, 'viscosity = "-1 Pa s"',
     ["joints[1].lubricant.viscosity", "'-1 Pa s'", "(0, 10] Pa s"]),
    (GRADE, 'viscosity = "20 Pa s"',
     ["joints[1].lubricant.viscosity", "'20 Pa s'", "(0, 10] Pa s"]),
    (GRADE, 'viscosity = "0.05 m"',
     ["joints[1].lubricant.viscosity", "'m' is a length unit, not viscosity",
      "Pa s, mPa s, cP, P"]),
    ('roughness = "0.65 um"', 'roughness = "12 um"',
     ["joints[1].lubricant.roughness", "12 um", "radial clearance 33 um",
      "< clearance / 3 = 11 um"]),
    (ROUGH, ROUGH + ', bearing = "short", viscocity = "1 cP"',
     ["joints[1].lubricant.viscocity", "unknown key", "did you mean 'viscosity'"]),
    (ROUGH, ROUGH + ', bearing = "journal"',
     ["joints[1].lubricant.bearing", "'journal' is not allowed", "'short'", "'long'"]),
    (GRADE, 'grade = "ISO VG 11", temperature = "25 degC"',
     ["joints[1].lubricant.grade", "'ISO VG 11'", "ISO VG 10, ISO VG 15", "ISO VG 1500"]),
    (GRADE, 'grade = "ISO VG 10", temperature = "140 degC"',
     ["joints[1].lubricant.temperature", "140 degC", "ASTM D341",
      "-20 degC to 114.8 degC"]),
    (GRADE, 'grade = "ISO VG 10", temperature = "-40 degC"',
     ["joints[1].lubricant.temperature", "-40 degC", "-20 degC to 114.8 degC"]),
    (GRADE, 'grade = "ISO VG 10", temperature = "warm"',
     ["joints[1].lubricant.temperature", "'warm'", "degC, K or degF"]),
    (GRADE, 'grade = "ISO VG 10"',
     ["joints[1].lubricant.temperature", "missing key", "25 degC"]),
    (GRADE, 'grade = "ISO VG 10", viscosity = "1 cP"',
     ["joints[1].lubricant.grade", "given together with lubricant.viscosity"]),
    (GRADE, 'viscosity = "1 cP", temperature = "25 degC"',
     ["joints[1].lubricant.temperature", "already the viscosity"]),
    (GRADE, 'temperature = "25 degC"',
     ["joints[1].lubricant.viscosity", "missing key", "lubricant.grade"]),
    ('roughness = "0.65 um"', 'roughness = "0 um"',
     ["joints[1].lubricant.roughness", "0 um is out of range", "> 0 and < clearance / 3 = 11 um"]),
    ('roughness = "0.65 um"', 'roughness = "-1 um"',
     ["joints[1].lubricant.roughness", "-1 um is out of range", "< clearance / 3 = 11 um"]),
    (GRADE, 'grade = "ISO VG 5", temperature = "25 degC"',
     ["joints[1].lubricant.grade", "'ISO VG 5'", "ISO VG 10, ISO VG 15"]),
    (GRADE, 'grade = "ISO VG 1500", temperature = "160 degC"',
     ["joints[1].lubricant.temperature", "160 degC", "ASTM D341", "-20 degC to 150 degC"]),
    (ROUGH, ROUGH + ', bearing = "Short"',
     ["joints[1].lubricant.bearing", "'Short' is not allowed", "'finite'"]),
    # the finite film's grid: the rig saturates at eps_max = 1 - 0.65 / 33 = 0.9803;
    # 8 nodes across the minimum film's half width sqrt(2 (1 - eps) / eps) = 0.2005
    # with the finest spacing (1 - 0.9 eps) 2 pi / n need n >= 8 x 0.1177 x 2 pi /
    # 0.2005 = 29.5, the even 30
    (ROUGH, ROUGH + ', bearing = "finite", film_n_theta = 28',
     ["joints[1].lubricant.film_n_theta", "28 nodes", "too coarse", "eps_max",
      "0.9803", "an even integer >= 30"]),
    (ROUGH, ROUGH + ', bearing = "finite", film_n_theta = 31',
     ["joints[1].lubricant.film_n_theta", "31 is odd", "an even integer in [16, 4096]"]),
    (ROUGH, ROUGH + ', bearing = "finite", film_n_theta = 8',
     ["joints[1].lubricant.film_n_theta", "out of range", "[16, 4096]"]),
    (ROUGH, ROUGH + ', bearing = "finite", film_n_z = 1',
     ["joints[1].lubricant.film_n_z", "out of range", "[2, 1024]"]),
    (ROUGH, ROUGH + ', bearing = "short", film_n_theta = 96',
     ["joints[1].lubricant.film_n_theta", "given for bearing = 'short'",
      'bearing = "finite", or no grid key']),
    (ROUGH, ROUGH + ', bearing = "short", cavitation = "mass-conserving"',
     ["joints[1].lubricant.cavitation", "'mass-conserving' given for bearing = 'short'",
      'bearing = "finite", or no cavitation key']),
    (ROUGH, ROUGH + ', bearing = "finite", cavitation = "jfo"',
     ["joints[1].lubricant.cavitation", "'jfo' is not allowed", "'reynolds'",
      "'mass-conserving'"]),
    ('law = { type = "elastic-foundation", layer_thickness = "6.342 mm", depth = "13.1 mm", '
     'restitution = 0.8 }\nwear = { coefficient = "5.05e-4 mm^3/(N m)" }   # Table 7-2',
     'law = { type = "lankarani-nikravesh" }\npin_material = "steel"',
     ["joints[1].lubricant", "'lankarani-nikravesh'", "law.type = 'elastic-foundation'"]),
])
def test_a_bad_lubricant_exits_2_naming_the_key_and_the_range(tmp_path, capsys, old, new,
                                                               words):
    path = _file(tmp_path, "bad", (old, new))
    before = path.read_bytes()
    out = tmp_path / "out"
    assert main(["run", str(path), "--cycles", "2000", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert str(path) in err
    for w in words:
        assert w in err, (w, err)
    assert not out.exists()
    assert path.read_bytes() == before  # the user's file is left as it was


def test_a_finite_film_grid_that_resolves_the_saturation_is_taken(tmp_path):
    """30 nodes round the bushing resolve the rig's film at eps_max = 0.9803
    (28 do not: above); the grid reaches the film law."""
    from diffwear.contact import FiniteBearingFilm

    grid = ', bearing = "finite", film_n_theta = 30, film_n_z = 6'
    path = _file(tmp_path, "grid", (ROUGH, ROUGH + grid))
    film = load(path).mechanism.element("crank_rod").law.film
    assert isinstance(film, FiniteBearingFilm)
    assert (film.n_theta, film.n_z) == (30, 6)
    assert float(film.max_eccentricity_ratio) == pytest.approx(1 - 0.65 / 33, rel=1e-9)
    assert film.cavitation == "reynolds"


def test_the_cavitation_condition_reaches_the_finite_film(tmp_path):
    path = _file(tmp_path, "jfo", (ROUGH,
                                   ROUGH + ', bearing = "finite", cavitation = "mass-conserving"'))
    assert load(path).mechanism.element("crank_rod").law.film.cavitation == "mass-conserving"


def test_the_film_figure_draws_the_onset_line_over_the_crank_angle(tmp_path):
    from diffwear import plots

    crank = np.arange(180) * 2.0
    h = 2e-6 + 1e-6 * np.cos(np.radians(crank))
    share = np.clip(1.5e-6 - h, 0.0, None) / 1e-6
    with plots.captured() as figures:
        plots.film_panels(tmp_path / "film_j.png", crank, {"unworn": (h, share),
                                                            "worn": (h + 2e-7, share / 2)},
                          onset=1.95e-6, onset_ratio=3.0, roughness=0.65e-6, title="j")
    top, bottom = figures["film_j.png"].axes
    assert bottom.get_xlabel() == "crank angle [deg]" and bottom.get_xlim() == (0.0, 360.0)
    onset = [line for line in top.get_lines() if "onset" in line.get_label()]
    assert len(onset) == 1 and np.allclose(onset[0].get_ydata(), 1.95)  # um
    assert "3 × 0.65 µm" in onset[0].get_label()
    assert np.isclose(np.min(top.get_lines()[0].get_ydata()), 1.0)  # h_min drawn in um
    assert [t.get_text() for t in bottom.get_legend().get_texts()] == ["unworn", "worn"]
    # the share in percent, its axis scaled to the largest share
    assert np.isclose(np.max(bottom.get_lines()[0].get_ydata()), 100.0 * share.max())
    assert bottom.get_ylim()[1] == pytest.approx(1.08 * 100.0 * share.max())
    for ax in (top, bottom):  # legends right of the data
        assert ax.get_legend().get_window_extent().x0 > ax.get_window_extent().x1
    # where the pin presses the asperities past the mean surfaces (no film left),
    # a middle panel draws how far, in um; the film itself stays at 0
    pressed = np.clip(1.5e-6 - h, 0.0, None)
    with plots.captured() as figures:
        plots.film_panels(tmp_path / "film_k.png", crank,
                          {"unworn": (np.zeros_like(h), share, pressed),
                           "worn": (h, share / 2, np.zeros_like(h))},
                          onset=1.95e-6, onset_ratio=3.0, roughness=0.65e-6, title="k")
    top, middle, bottom = figures["film_k.png"].axes
    assert [line.get_label() for line in middle.get_lines()] == ["unworn"]
    assert np.allclose(middle.get_lines()[0].get_ydata(), pressed * 1e6)
    assert middle.get_ylim()[0] == 0.0 and "interference" in middle.get_ylabel()
    assert min(float(np.min(line.get_ydata())) for line in top.get_lines()) >= 0.0


@pytest.mark.parametrize("grade, celsius, nu_mm2_s", [
    # ISO 3448 midpoint at 40 degC and the table's 100 degC value, exactly
    ("ISO VG 10", 40.0, 10.0), ("ISO VG 10", 100.0, 2.5), ("VG 68", 40.0, 68.0),
    ("iso vg 68", 100.0, 8.5),
    # ASTM D341 by hand: log log(nu + 0.7) linear in log T through those two points
    ("ISO VG 10", 25.0, 17.3488), ("ISO VG 68", 25.0, 158.0),
])
def test_grade_viscosity_follows_walther(grade, celsius, nu_mm2_s):
    from diffwear.contact import oils

    oil = oils.grade(grade)
    kelvin = oils.parse_temperature(f"{celsius} degC")
    assert oil.kinematic_viscosity(kelvin) * 1e6 == pytest.approx(nu_mm2_s, rel=1e-3)
    # mu = rho nu with rho = 870 kg/m^3 at 15 degC, 6.5e-4 /K
    rho = 870.0 * (1 - 6.5e-4 * (celsius - 15.0))
    assert oil.viscosity(kelvin) == pytest.approx(rho * oil.kinematic_viscosity(kelvin),
                                                  rel=1e-12)
    assert oils.parse_temperature("77 degF") == pytest.approx(298.15)
    assert oils.parse_temperature("298.15 K") == 298.15
