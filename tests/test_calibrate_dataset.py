"""Measured-data format (`diffwear.calibrate.dataset`): loading, writing, bad input."""

from __future__ import annotations

import math
import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from diffwear.calibrate import Dataset, Parameter, Series, load_dataset, write_dataset
from diffwear.errors import InputError

ROOT = Path(__file__).resolve().parents[1]

MANIFEST = """\
# a hand-written dataset: every series kind, mixed units
[dataset]
name = "synthetic-run-in"
description = "test data"

[rig]
preset = "rig"
bushing_density = "2.25 g/cm^3"

[parameters]
k = { value = "5.05e-4 mm^3/(N m)", std = "2.0e-4 mm^3/(N m)", fit = true }
free_length = { value = "0.2 m", fit = true }
clearance = { value = "33 um", std = "5 um" }
mu = { value = 0.13 }

[calibration]
holdout_from_cycles = 3000

[[series]]
kind = "profile"
file = "profile_02000.csv"
cycles = 2000
uncertainty = "2 um"

[[series]]
kind = "profile"
file = "profile_04000.csv"
cycles = 4000
uncertainty = "2 um"

[[series]]
kind = "volume"
file = "mass.csv"
uncertainty = "0.5 mg"

[[series]]
kind = "max_depth"
file = "max_depth.csv"
uncertainty = "3 um"

[[series]]
kind = "force"
file = "force_01000.csv"
cycles = 1000
uncertainty = "5 N"
"""

CSVS = {
    "profile_02000.csv": "# bushing frame, 2000 cycles\ntheta_deg,depth_um\n0,0\n90,12.5\n"
                         "180,20\n270,3\n",
    "profile_04000.csv": "theta_rad,depth_mm\r\n0.0,0.0\r\n1.5,0.021\r\n3.0,0.030\r\n",
    "mass.csv": "cycles,mass_g\n0,0\n2000,0.1\n\n# last weighing\n21400,0.2616\n",
    "max_depth.csv": "cycles,max_depth_um\n0,0\n2000,20\n4000,30\n",
    "force_01000.csv": "crank_angle_deg,force_N\n0,120\n120,-40.5\n240,150\n",
}


def make(folder: Path, manifest: str = MANIFEST, csvs: dict | None = None) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "dataset.toml").write_text(manifest)
    for name, text in (CSVS if csvs is None else csvs).items():
        (folder / name).write_text(text)
    return folder


def snapshot(folder: Path) -> dict:
    return {p: p.read_bytes() for p in sorted(folder.parent.rglob("*")) if p.is_file()}


# ----------------------------------------------------------------------------- good data
def test_hand_written_dataset_in_si(tmp_path):
    d = load_dataset(make(tmp_path / "ds"))
    assert (d.name, d.description, d.preset) == ("synthetic-run-in", "test data", "rig")
    assert d.bushing_density == 2250.0
    assert d.holdout_from_cycles == 3000.0
    assert list(d.parameters) == ["k", "clearance", "mu", "free_length"]  # canonical order
    assert d.parameters["k"] == Parameter("k", 5.05e-13, 2.0e-13, True)
    assert d.parameters["clearance"] == Parameter("clearance", 33e-6, 5e-6, False)
    assert d.parameters["free_length"].value == 0.2
    assert d.parameters["mu"] == Parameter("mu", 0.13, None, False)
    assert d.fit_names == ("k", "free_length")
    assert d.max_cycles == 21400.0
    p2, p4, mass, depth, force = d.series
    assert [s.name for s in d.series] == ["profile_02000", "profile_04000", "mass", "max_depth",
                                          "force_01000"]
    assert p2.kind == "profile" and p2.cycles == 2000.0 and p2.file == Path("profile_02000.csv")
    assert d.file_of(p2) == tmp_path / "ds" / "profile_02000.csv"
    np.testing.assert_array_equal(p2.x, [0.0, math.pi / 2, math.pi, 1.5 * math.pi])
    np.testing.assert_allclose(p2.y, [0.0, 12.5e-6, 20e-6, 3e-6], rtol=1e-15)
    assert p2.sigma == 2e-6 and not p2.holdout.any()
    np.testing.assert_array_equal(p4.x, [0.0, 1.5, 3.0])
    np.testing.assert_allclose(p4.y, [0.0, 21e-6, 30e-6], rtol=1e-15)
    assert p4.holdout.all()  # 4000 >= holdout_from_cycles
    # 0.2616 g / 2.25 g/cm^3 = 116.2666.. mm^3; 0.5 mg / 2.25 g/cm^3 = 0.2222.. mm^3
    assert mass.basis == "mass" and mass.cycles is None
    np.testing.assert_array_equal(mass.x, [0.0, 2000.0, 21400.0])
    np.testing.assert_allclose(mass.y * 1e9, [0.0, 44.444444444444, 116.266666666667],
                               rtol=1e-12)
    assert mass.sigma * 1e9 == pytest.approx(0.5 / 2.25, rel=1e-14)
    np.testing.assert_array_equal(mass.holdout, [False, False, True])
    np.testing.assert_array_equal(depth.holdout, [False, False, True])
    np.testing.assert_allclose(depth.y, [0.0, 20e-6, 30e-6], rtol=1e-15)
    assert depth.sigma == 3e-6
    np.testing.assert_allclose(force.x, [0.0, 2 * math.pi / 3, 4 * math.pi / 3], rtol=1e-15)
    np.testing.assert_array_equal(force.y, [120.0, -40.5, 150.0])
    assert force.sigma == 5.0 and not force.holdout.any()
    assert d.notes == ()
    with pytest.raises(ValueError):
        p2.y[0] = 1.0  # read-only arrays


def test_role_overrides_the_holdout_rule_and_empty_holdout_is_noted(tmp_path):
    text = MANIFEST.replace("holdout_from_cycles = 3000", "holdout_from_cycles = 1e9")
    text = text.replace('cycles = 1000\n', 'cycles = 1000\nrole = "holdout"\n')
    d = load_dataset(make(tmp_path / "a", text))
    assert d.series[4].holdout.all() and not d.series[0].holdout.any()
    text = MANIFEST.replace("[calibration]\nholdout_from_cycles = 3000\n", "")
    d = load_dataset(make(tmp_path / "b", text))
    assert d.holdout_from_cycles is None
    assert not any(s.holdout.any() for s in d.series)
    assert "no measurement is held out" in d.notes[0]


def test_volume_basis_and_units(tmp_path):
    text = MANIFEST.replace('uncertainty = "0.5 mg"', 'uncertainty = "0.3 mm^3"\nbasis = "profile"')
    text = text.replace('bushing_density = "2.25 g/cm^3"\n', "")
    csvs = {**CSVS, "mass.csv": "cycles,volume_mm3\n0,0\n21400,116.27\n"}
    d = load_dataset(make(tmp_path / "a", text, csvs))
    mass = d.series[2]
    assert mass.basis == "profile" and d.bushing_density is None
    np.testing.assert_allclose(mass.y, [0.0, 116.27e-9], rtol=1e-15)
    assert mass.sigma == pytest.approx(0.3e-9, rel=1e-15)
    csvs = {**CSVS, "mass.csv": "cycles,mass_mg\n0,0\n21400,261.6\n"}
    d = load_dataset(make(tmp_path / "b", MANIFEST, csvs))
    assert d.series[2].y[1] * 1e9 == pytest.approx(116.2666666666667, rel=1e-12)


def test_write_then_load_round_trip(tmp_path):
    d = load_dataset(make(tmp_path / "ds"))
    out = write_dataset(tmp_path / "copy", name=d.name, description='quote " and \\ and\nline',
                        preset=d.preset, parameters=d.parameters, series=d.series,
                        bushing_density=d.bushing_density,
                        holdout_from_cycles=d.holdout_from_cycles)
    again = load_dataset(tmp_path / "copy")
    for e in (out, again):
        assert e.description == 'quote " and \\ and\nline'
        assert e.parameters == d.parameters  # exact
        assert e.bushing_density == d.bushing_density
        assert e.holdout_from_cycles == d.holdout_from_cycles
        for a, b in zip(d.series, e.series, strict=True):
            assert (a.name, a.kind, a.file, a.cycles, a.basis) == \
                (b.name, b.kind, b.file, b.cycles, b.basis)
            np.testing.assert_array_equal(a.x, b.x)
            np.testing.assert_allclose(b.y, a.y, rtol=1e-15)
            assert b.sigma == pytest.approx(a.sigma, rel=1e-15)
            np.testing.assert_array_equal(a.holdout, b.holdout)
    csv = (tmp_path / "copy" / "mass.csv").read_text()
    assert "cycles,volume_mm3" in csv and "21400,116.2666666666666" in csv
    assert 'basis = "mass"' in (tmp_path / "copy" / "dataset.toml").read_text()


def test_write_dataset_from_arrays(tmp_path):
    x = np.linspace(0.0, 2 * np.pi, 73)[:-1]
    series = [
        Series("early", "profile", "p/profile_01000.csv", 1000, x, 1e-5 * (1 + np.cos(x)), 2e-6),
        Series("late", "profile", "p/profile_05000.csv", 5000, x, 3e-5 * (1 + np.cos(x)), 2e-6,
               holdout=np.ones(72, bool)),
        Series("volume", "volume", "volume.csv", None, [0, 1e3, 4e3], [0, 1e-8, 1e-7], 1e-10,
               basis="mass"),
    ]
    params = {"k": Parameter("k", 5.05e-13, 2e-13, True), "mu": Parameter("mu", 0.13, 0.02, True)}
    d = write_dataset(tmp_path / "new", name="gen", parameters=params, series=series,
                      holdout_from_cycles=5000)
    assert d.fit_names == ("k", "mu")
    assert d.series[0].name == "early" and d.series[0].file == Path("p/profile_01000.csv")
    assert d.series[1].holdout.all() and not d.series[2].holdout.any()
    assert "role" not in (tmp_path / "new" / "dataset.toml").read_text()  # the rule gives it
    np.testing.assert_allclose(d.series[0].y, series[0].y, rtol=1e-15)
    # a per-point holdout the format cannot express is refused before anything is written
    odd = Series("odd", "profile", "odd.csv", 1000, [0.0, 1.0], [0.0, 1e-6], 1e-6,
                 holdout=[True, False])
    with pytest.raises(InputError, match="neither role nor holdout_from_cycles"):
        write_dataset(tmp_path / "odd", name="gen", parameters=params, series=[odd])
    assert not (tmp_path / "odd").exists()
    # bad values are caught by loading a temporary copy: the target is never created
    bad = Series("bad", "profile", "bad.csv", 1000, [0.0, 1.0], [0.0, -1e-5], 1e-6)
    with pytest.raises(InputError) as err:
        write_dataset(tmp_path / "bad", name="gen", parameters=params, series=[bad])
    assert "would not load back" in str(err.value)
    assert "'-0.01' is 10.0 uncertainties below zero" in str(err.value)
    assert str(tmp_path / "bad" / "bad.csv") in str(err.value)
    assert not (tmp_path / "bad").exists()


def test_write_dataset_refuses_to_overwrite(tmp_path):
    folder = make(tmp_path / "ds")
    before = snapshot(folder)
    d = load_dataset(folder)
    kwargs = dict(name="other", parameters=d.parameters, series=d.series[:1],
                  bushing_density=d.bushing_density)
    with pytest.raises(InputError) as err:
        write_dataset(folder, **kwargs)
    assert str(folder) in str(err.value) and "not empty" in str(err.value)
    assert "overwrite=True" in str(err.value)
    assert snapshot(folder) == before
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="not a folder"):
        write_dataset(tmp_path / "file", **kwargs)
    (tmp_path / "empty").mkdir()
    assert write_dataset(tmp_path / "empty", **kwargs).name == "other"
    assert write_dataset(folder, **kwargs, overwrite=True).name == "other"
    assert load_dataset(folder).name == "other"


def test_documented_example_loads(tmp_path):
    doc = (ROOT / "docs" / "reference" / "dataset-format.md").read_text()
    manifest = re.search(r"```toml\n(.*?)```", doc, re.S).group(1)
    csvs = dict(re.findall(r"`([\w.-]+\.csv)`:\n\n```csv\n(.*?)```", doc, re.S))
    assert len(csvs) >= 3
    d = load_dataset(make(tmp_path / "doc", manifest, csvs))
    assert d.name == "synthetic-run-in" and d.fit_names
    for s in d.series:
        assert s.holdout.any() == (s.cycle_counts >= 3000).any()


# ----------------------------------------------------------------------------- bad input
def toml(old, new):
    def edit(folder):
        text = (folder / "dataset.toml").read_text()
        assert old in text, old
        (folder / "dataset.toml").write_text(text.replace(old, new, 1))
    return edit


def csv(name, content):
    def edit(folder):
        data = content.encode() if isinstance(content, str) else content
        (folder / name).write_bytes(data)
    return edit


def manifest_bytes(content: bytes):
    return csv("dataset.toml", content)


def remove(name):
    return lambda folder: (folder / name).unlink()


def outside(folder):
    (folder.parent / "x.csv").write_text(CSVS["profile_02000.csv"])
    toml('file = "profile_02000.csv"', 'file = "../x.csv"')(folder)


def a_folder(folder):
    (folder / "sub.csv").mkdir()
    toml('file = "profile_02000.csv"', 'file = "sub.csv"')(folder)


P = "profile_02000.csv"
BAD = {
    # folder and manifest
    "no dataset.toml": (remove("dataset.toml"), ["dataset.toml", "no such file"]),
    "empty manifest": (manifest_bytes(b"  \n"), ["dataset.toml", "the file is empty"]),
    "comments only": (manifest_bytes(b"# nothing\n"), ["dataset.toml", "no keys or tables"]),
    "manifest not UTF-8": (manifest_bytes(b'[dataset]\nname = "caf\xe9"\n'),
                           ["dataset.toml", "line 2", "not UTF-8", "b'\\xe9'"]),
    "bad TOML": (toml("[rig]", "[rig"), ["dataset.toml", "invalid TOML", "TOML 1.0"]),
    "unknown section": (toml("[calibration]", "[calibation]"),
                        ["dataset.toml", "calibation", "did you mean 'calibration'"]),
    "missing [dataset]": (toml('[dataset]\nname = "synthetic-run-in"', "[datasett]"),
                          ["datasett", "did you mean 'dataset'"]),
    "[dataset] missing": (toml('[dataset]\nname = "synthetic-run-in"\ndescription = "test data"\n',
                               ""), ["dataset.toml", "dataset: missing section", "name = "]),
    "bad dataset name": (toml('name = "synthetic-run-in"', 'name = "run in!"'),
                         ["dataset.name", "'run in!'", "letters, digits"]),
    "unknown preset": (toml('preset = "rig"', 'preset = "rigg"'),
                       ["dataset.toml", "rig.preset", "'rigg'", "did you mean 'rig'", "'rig'"]),
    "density wrong dimension": (toml('"2.25 g/cm^3"', '"2.25 g"'),
                                ["rig.bushing_density", "'g' is a mass unit, not density"]),
    # parameters
    "unknown parameter": (toml("clearance = {", "clearence = {"),
                          ["parameters.clearence", "did you mean 'clearance'", "free_length"]),
    "parameter not a table": (toml('clearance = { value = "33 um", std = "5 um" }',
                                   'clearance = "33 um"'),
                              ["parameters.clearance", "expected a table", "'33 um'"]),
    "missing value": (toml('k = { value = "5.05e-4 mm^3/(N m)", std', 'k = { std'),
                      ["parameters.k.value", "missing", "fit = true"]),
    "unknown parameter key": (toml('std = "5 um"', 'sd = "5 um"'),
                              ["parameters.clearance.sd", "did you mean 'std'"]),
    "wrong dimension": (toml('"33 um"', '"33 kg"'),
                        ["parameters.clearance.value", "'kg' is a mass unit, not length"]),
    "unknown unit": (toml('"33 um"', '"33 umm"'),
                     ["parameters.clearance.value", "unknown unit 'umm'", "allowed: m, cm"]),
    "bare number": (toml('"5.05e-4 mm^3/(N m)", std', "5.05e-4, std"),
                    ["parameters.k.value", "bare number 0.000505", "mm^3/(N m)"]),
    "zero value": (toml('"33 um"', '"0 um"'),
                   ["parameters.clearance.value", "'0 um'", "out of range", "> 0"]),
    "NaN value": (toml('"0.2 m"', '"nan m"'), ["parameters.free_length.value", "not finite"]),
    "inf value": (toml('"0.2 m"', '"inf m"'), ["parameters.free_length.value", "not finite"]),
    "negative std": (toml('"5 um"', '"-5 um"'),
                     ["parameters.clearance.std", "'-5 um'", "out of range"]),
    "mu above 1": (toml("mu = { value = 0.13 }", "mu = { value = 1.3 }"),
                   ["parameters.mu.value", "1.3", "[0, 1]"]),
    "mu as string": (toml("mu = { value = 0.13 }", 'mu = { value = "0.13" }'),
                     ["parameters.mu.value", "expected a number", "'0.13'"]),
    "fit not boolean": (toml("fit = true }\nfree", 'fit = "yes" }\nfree'),
                        ["parameters.k.fit", "expected true or false", "'yes'"]),
    "nothing to fit": (lambda f: (toml(", fit = true }\nfree", " }\nfree")(f),
                                  toml('"0.2 m", fit = true', '"0.2 m"')(f)),
                       ["dataset.toml", "parameters", "no parameter has fit = true"]),
    "negative holdout_from_cycles": (toml("= 3000", "= -1"),
                                     ["calibration.holdout_from_cycles", "-1", ">= 0"]),
    # series entries
    "no series": (lambda f: (f / "dataset.toml").write_text(MANIFEST.split("[[series]]")[0]),
                  ["dataset.toml", "series", "missing section", "[[series]]"]),
    "single [series] table": (lambda f: (f / "dataset.toml").write_text(
        MANIFEST.split("[[series]]")[0] + '[series]\nkind = "profile"\n'),
        ["series", "single table", "[[series]]"]),
    "unknown kind": (toml('kind = "profile"', 'kind = "profil"'),
                     ["series[0].kind", "'profil'", "did you mean 'profile'", "'max_depth'"]),
    "unknown series key": (toml('uncertainty = "2 um"', 'uncertanty = "2 um"'),
                           ["series[0].uncertanty", "did you mean 'uncertainty'"]),
    "missing file": (toml(f'file = "{P}"', 'file = "nothere.csv"'),
                     ["series[0].file", "'nothere.csv'", "no such file"]),
    "file escapes folder": (outside, ["series[0].file", "'../x.csv'", "outside the dataset"]),
    "absolute file": (toml(f'file = "{P}"', 'file = "/etc/passwd"'),
                      ["series[0].file", "'/etc/passwd'", "absolute path"]),
    "file is a folder": (a_folder, ["series[0].file", "'sub.csv'", "not a file"]),
    "cycles on volume": (toml('file = "mass.csv"', 'file = "mass.csv"\ncycles = 100'),
                         ["series[2].cycles", "not allowed for a volume series", "cycles column"]),
    "cycles missing on profile": (toml("cycles = 2000\n", ""),
                                  ["series[0].cycles", "missing key", "cycles = 2000"]),
    "negative cycles": (toml("cycles = 2000", "cycles = -2"),
                        ["series[0].cycles", "-2", ">= 0"]),
    "uncertainty missing": (toml('uncertainty = "2 um"\n', ""),
                            ["series[0].uncertainty", "missing key"]),
    "uncertainty wrong dimension": (toml('uncertainty = "2 um"', 'uncertainty = "2 N"'),
                                    ["series[0].uncertainty", "'N' is a force unit, not length"]),
    "volume uncertainty as length": (toml('"0.5 mg"', '"2 um"'),
                                     ["series[2].uncertainty", "length unit, not volume",
                                      "a mass"]),
    "zero uncertainty": (toml('"5 N"', '"0 N"'), ["series[4].uncertainty", "out of range"]),
    "mass series without density": (toml('bushing_density = "2.25 g/cm^3"\n', ""),
                                    ["dataset.toml", "rig.bushing_density", "missing",
                                     "mass.csv", "mass_g"]),
    "volume_mm3 without basis": (csv("mass.csv", "cycles,volume_mm3\n0,0\n1,2\n"),
                                 ["series[2].basis", "missing key", "volume_mm3",
                                  "'mass' (from weighing)"]),
    "basis contradicts mass column": (toml('"0.5 mg"', '"0.5 mg"\nbasis = "profile"'),
                                      ["series[2].basis", "contradicts", "mass_g"]),
    "mass uncertainty on a profile-basis volume": (
        lambda f: (csv("mass.csv", "cycles,volume_mm3\n0,0\n1,2\n")(f),
                   toml('"0.5 mg"', '"0.5 mg"\nbasis = "profile"')(f)),
        ["series[2].uncertainty", "'0.5 mg' is a mass", "basis = 'profile'"]),
    "basis on a profile": (toml('uncertainty = "2 um"', 'uncertainty = "2 um"\nbasis = "mass"'),
                           ["series[0].basis", "not allowed for a profile series"]),
    "bad role": (toml('uncertainty = "2 um"', 'uncertainty = "2 um"\nrole = "train"'),
                 ["series[0].role", "'train'", "'fit' | 'holdout'"]),
    "duplicate series name": (toml('file = "mass.csv"', 'file = "mass.csv"\nname = "max_depth"'),
                              ["series[3].name", "'max_depth'", "already the name of series[2]"]),
    "all held out": (toml("= 3000", "= 0"),
                     ["dataset.toml", "series", "held out", "nothing is left to fit"]),
    # CSV files
    "empty CSV": (csv(P, ""), [P, "the file is empty", "theta_rad or theta_deg"]),
    "comments only CSV": (csv(P, "# nothing\n\n"), [P, "the file is empty"]),
    "header only": (csv(P, "theta_deg,depth_um\n"), [P, "no data rows", "line 1"]),
    "no header": (csv(P, "0,1\n90,2\n"), [P, "line 1", "header row is missing"]),
    "missing column": (csv(P, "theta_deg\n0\n"), [P, "line 1", "missing column",
                                                   "depth_mm, depth_um"]),
    "extra column": (csv(P, "theta_deg,depth_um,temp_C\n0,1,20\n"),
                     [P, "line 1", "unknown column 'temp_C'"]),
    "misspelt column": (csv(P, "theta_deg,depht_um\n0,1\n"),
                        [P, "'depht_um'", "did you mean 'depth_um'"]),
    "column of another kind": (csv(P, "theta_deg,force_N\n0,1\n"),
                               [P, "'force_N'", "another kind of series"]),
    "two angle columns": (csv(P, "theta_deg,theta_rad,depth_um\n0,0,1\n"),
                          [P, "theta_deg and theta_rad", "exactly one of"]),
    "repeated column": (csv(P, "theta_deg,theta_deg\n0,0\n"), [P, "named twice"]),
    "empty column name": (csv(P, "theta_deg,depth_um,\n0,0,\n"), [P, "empty column name"]),
    "non-numeric cell": (csv(P, "# c\ntheta_deg,depth_um\n0,0\n90,abc\n"),
                         [P, "line 4", "column 'depth_um'", "'abc' is not a number"]),
    "empty cell": (csv(P, "theta_deg,depth_um\n0,\n"), [P, "line 2", "empty cell"]),
    "NaN cell": (csv(P, "theta_deg,depth_um\n0,0\n90,nan\n"),
                 [P, "line 3", "column 'depth_um'", "'nan' is not finite"]),
    "inf cell": (csv(P, "theta_deg,depth_um\n0,-inf\n"), [P, "line 2", "'-inf' is not finite"]),
    "overflowing cell": (csv(P, "theta_deg,depth_um\n0,1e999\n"),
                         [P, "line 2", "'1e999' is out of the float64 range"]),
    "wrong cell count": (csv(P, "theta_deg,depth_um\n0,0\n90,1,2\n"),
                         [P, "line 3", "3 cells", "names 2 columns"]),
    "depth far below zero": (csv(P, "theta_deg,depth_um\n0,0\n90,1\n180,-9\n"),
                             [P, "line 4", "column 'depth_um'",
                              "'-9' is 4.5 uncertainties below zero",
                              "depth_um >= -4 x the series' uncertainty"]),
    "angles not increasing": (csv(P, "theta_deg,depth_um\n0,0\n90,1\n90,2\n"),
                              [P, "line 4", "'90' is not greater than the value on line 3",
                               "strictly increasing theta_deg"]),
    "angle of 360 deg": (csv(P, "theta_deg,depth_um\n0,0\n360,1\n"),
                         [P, "line 3", "'360' is outside [0, 2 pi)", "theta_deg < 360"]),
    "negative angle": (csv("profile_04000.csv", "theta_rad,depth_mm\n-0.1,0\n"),
                       ["profile_04000.csv", "line 2", "'-0.1' is outside"]),
    "force angle of 7 rad": (csv("force_01000.csv", "crank_angle_rad,force_N\n7,1\n"),
                             ["force_01000.csv", "'7' is outside", "2 pi = 6.28"]),
    "cycles not increasing": (csv("mass.csv", "cycles,mass_g\n0,0\n2000,0.1\n1000,0.2\n"),
                              ["mass.csv", "line 4", "column 'cycles'", "not greater"]),
    "negative cycles cell": (csv("max_depth.csv", "cycles,max_depth_um\n-5,0\n"),
                             ["max_depth.csv", "line 2", "'-5' is negative"]),
    "negative mass": (csv("mass.csv", "cycles,mass_g\n0,-0.1\n"),
                      ["mass.csv", "column 'mass_g'", "'-0.1' is 200.0 uncertainties below"]),
    "CSV not UTF-8": (csv(P, b"theta_deg,depth_um\n0,\xff\n"),
                      [P, "line 2", "not UTF-8", "CSV files are UTF-8"]),
}


@pytest.mark.parametrize("edit,fragments", BAD.values(), ids=BAD.keys())
def test_bad_input(tmp_path, edit, fragments):
    folder = make(tmp_path / "ds")
    edit(folder)
    before = snapshot(folder)
    with pytest.raises(InputError) as err:
        load_dataset(folder)
    message = str(err.value)
    for fragment in fragments:
        assert fragment in message, (fragment, message)
    assert "; allowed: " in message or "cannot be read" in message
    assert snapshot(folder) == before  # loading never writes


def test_bad_folder(tmp_path):
    with pytest.raises(InputError, match=r"nope: no such folder; allowed: a dataset folder"):
        load_dataset(tmp_path / "nope")
    (tmp_path / "file").write_text("")
    with pytest.raises(InputError, match=r"file: is a file, not a folder"):
        load_dataset(tmp_path / "file")


# ----------------------------------------------------------------------------- properties
PARAMS = {"k": Parameter("k", 5.05e-13, 2e-13, True)}
angle = st.floats(0.0, 2 * math.pi, exclude_max=True, allow_subnormal=False)
small = st.one_of(st.just(0.0), st.floats(1e-12, 1e-3))
count = st.one_of(st.integers(0, 10**7).map(float), st.floats(0.0, 1e7, allow_subnormal=False))


@st.composite
def datasets(draw):
    thetas = sorted(set(draw(st.lists(angle, min_size=1, max_size=30))))
    profile = Series("profile", "profile", "profile.csv", draw(count), thetas,
                     draw(st.lists(small, min_size=len(thetas), max_size=len(thetas))),
                     draw(st.floats(1e-9, 1e-3)))
    cycles = sorted(set(draw(st.lists(count, min_size=1, max_size=30))))
    volumes = draw(st.lists(st.one_of(st.just(0.0), st.floats(1e-15, 1e-5)),
                            min_size=len(cycles), max_size=len(cycles)))
    volume = Series("volume", "volume", "sub/volume.csv", None, cycles, volumes,
                    draw(st.floats(1e-13, 1e-8)), basis=draw(st.sampled_from(["mass", "profile"])))
    holdout_from = draw(st.one_of(st.none(), count))
    return [profile, volume], holdout_from


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(datasets())
def test_property_write_load_round_trip(data):
    series, holdout_from = data
    expected = [np.zeros(s.x.shape, bool) if holdout_from is None
                else s.cycle_counts >= holdout_from for s in series]
    series = [Series(s.name, s.kind, s.file, s.cycles, s.x, s.y, s.sigma, h, s.basis)
              for s, h in zip(series, expected)]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "ds"
        if all(h.all() for h in expected):
            with pytest.raises(InputError, match="nothing is left to fit"):
                write_dataset(folder, name="p", parameters=PARAMS, series=series,
                              holdout_from_cycles=holdout_from)
            return
        write_dataset(folder, name="p", parameters=PARAMS, series=series,
                      holdout_from_cycles=holdout_from)
        d = load_dataset(folder)
    assert isinstance(d, Dataset)
    for a, b in zip(series, d.series, strict=True):
        np.testing.assert_array_equal(b.x, a.x)  # rad and cycles are written as they are
        np.testing.assert_allclose(b.y, a.y, rtol=1e-12, atol=0)
        assert b.sigma == pytest.approx(a.sigma, rel=1e-12)
        np.testing.assert_array_equal(b.holdout, a.holdout)
        assert (b.cycles, b.basis) == (a.cycles, a.basis)


@pytest.fixture(scope="module")
def good_folder(tmp_path_factory):
    return make(tmp_path_factory.mktemp("garbage") / "ds")


@settings(max_examples=150, deadline=None)
@given(st.one_of(st.binary(max_size=300),
                 st.binary(max_size=200).map(lambda b: b"theta_deg,depth_um\n0,0\n" + b),
                 st.text(alphabet="0123456789.,-+eE#\n naninf\r_", max_size=80)
                 .map(lambda t: ("theta_rad,depth_mm\n" + t).encode())))
def test_property_garbage_csv_is_an_input_error(good_folder, garbage):
    folder = good_folder
    (folder / P).write_bytes(garbage)
    try:
        d = load_dataset(folder)
    except InputError as err:
        assert str(folder / P) in str(err) or "dataset.toml" in str(err)
    else:  # rarely, garbage is a valid profile: then it obeys the rules
        s = d.series[0]
        assert np.all(np.diff(s.x) > 0) and np.all((s.x >= 0) & (s.x < 2 * math.pi))
        assert np.all(s.y >= 0)


def test_small_negative_depths_are_noise_and_kept_as_measured(tmp_path):
    """A profilometer reads noise around zero in the unworn arc: depths down to
    4 uncertainties below zero load unchanged (clipping would bias the fit)."""
    csvs = {**CSVS, P: "theta_deg,depth_um\n0,-7.9\n90,1\n180,-2\n270,12\n"}  # sigma 2 um
    d = load_dataset(make(tmp_path / "noisy", MANIFEST, csvs))
    s = next(s for s in d.series if s.file.name == P)
    np.testing.assert_allclose(s.y, np.array([-7.9, 1.0, -2.0, 12.0]) * 1e-6, rtol=1e-12)


def test_declared_angle_convention_maps_profiles_into_the_model_frame(tmp_path):
    """[rig] bushing_angle_zero / bushing_angle_sense: a profile measured from
    another zero, or clockwise, is loaded in the model's bushing frame (counter-
    clockwise from the rod axis); the default is the model's own convention."""
    csvs = {**CSVS, P: "theta_deg,depth_um\n0,10\n90,20\n180,30\n270,40\n"}
    plain = load_dataset(make(tmp_path / "plain", MANIFEST, csvs))
    turned = MANIFEST.replace('preset = "rig"', 'preset = "rig"\nbushing_angle_zero = "90 deg"\n'
                              'bushing_angle_sense = "clockwise"')
    assert turned != MANIFEST
    d = load_dataset(make(tmp_path / "turned", turned, csvs))

    def profile(ds):
        s = next(s for s in ds.series if s.file.name == P)
        return np.degrees(s.x), s.y * 1e6

    x, y = profile(plain)
    np.testing.assert_allclose(x, [0, 90, 180, 270], atol=1e-9)
    np.testing.assert_allclose(y, [10, 20, 30, 40])
    # data 0 -> model 90, data 90 (clockwise) -> model 0, data 180 -> 270, data 270 -> 180
    x, y = profile(d)
    np.testing.assert_allclose(x, [0, 90, 180, 270], atol=1e-9)
    np.testing.assert_allclose(y, [20, 10, 40, 30])
    bad = MANIFEST.replace('preset = "rig"', 'preset = "rig"\nbushing_angle_sense = "cw"')
    with pytest.raises(InputError, match="bushing_angle_sense"):
        load_dataset(make(tmp_path / "bad", bad, csvs))


# ------------------------------------------------------- plausibility
THESIS_RIG = Path(__file__).resolve().parents[1] / "design_studies" / "calibration" / "thesis_rig"


def _thesis_rig_with_depth(tmp_path, depth_mm: str) -> Path:
    import shutil

    folder = tmp_path / "rig"
    shutil.copytree(THESIS_RIG, folder)
    (folder / "max_depth.csv").write_text(f"cycles,max_depth_mm\n21400,{depth_mm}\n")
    return folder


def test_a_depth_beyond_the_bushing_wall_is_refused_before_fitting(tmp_path, capsys):
    from diffwear.cli import main

    folder = _thesis_rig_with_depth(tmp_path, "485")
    out = tmp_path / "out"
    assert main(["calibrate", str(folder), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "max_depth.csv" in err[0] and "485 mm" in err[0]
    assert "beyond the bushing wall of 6.342 mm" in err[0]  # the rig's wall (presets)
    assert not out.exists()


def test_unit_slip_factors_are_powers_of_a_thousand_within_half_a_decade():
    from diffwear.calibrate.plausibility import _slip

    assert [_slip(f) for f in (1e-3, 3e-3, 0.4e-3, 1.0, 20.0, 1e3, 2.5e3, 1e-6, 1e6)] == \
        [-1, -1, -1, 0, 0, 1, 1, -2, 2]
    assert _slip(3.5e-3) == 0 and _slip(0.0) == 0 and _slip(float("nan")) == 0


def test_a_series_off_by_a_thousand_against_the_others_is_named():
    """Hand-made predictions: the depth series reads 1/1000 of what the model
    gives while the volume agrees; the fitted k at the stated one."""
    from types import SimpleNamespace

    from diffwear.calibrate.plausibility import unit_slips

    s = [SimpleNamespace(name="mass", kind="volume", file=Path("worn_mass.csv"),
                         y=np.array([1.0e-7, 2.0e-7]), sigma=1e-9),
         SimpleNamespace(name="depth", kind="max_depth", file=Path("max_depth.csv"),
                         y=np.array([2.0e-7, 4.0e-7]), sigma=1e-8),
         SimpleNamespace(name="force", kind="force", file=Path("force.csv"),
                         y=np.array([5.0, 6.0]), sigma=1.0)]
    data = SimpleNamespace(series=s)
    problem = SimpleNamespace(series_of_point=np.repeat([0, 1, 2], 2), fit_names=("k",))
    prediction = np.array([1.0e-7, 2.0e-7, 2.0e-4, 4.0e-4, 5.0, 6.0])
    base = SimpleNamespace(prediction=prediction, params={"k": 1e-13})
    found = unit_slips(data, problem, base, 1e-13)
    assert [w["series"] for w in found] == ["depth"]
    assert found[0]["factor"] == pytest.approx(1e-3)
    assert "metres in a millimetre column" in found[0]["message"]
    # every series agreeing, the fitted k 1/1000 of the stated: all in one wrong unit
    prediction[2:4] = s[1].y
    base = SimpleNamespace(prediction=prediction, params={"k": 1e-16})
    found = unit_slips(data, problem, base, 1e-13)
    assert len(found) == 1 and found[0]["series"] is None
    assert "every wear series reads 0.001 times" in found[0]["message"]
    assert unit_slips(data, problem, SimpleNamespace(prediction=prediction,
                                                     params={"k": 3e-13}), 1e-13) == []


@pytest.mark.slow  # a base fit of the thesis rig: about a minute
def test_metres_in_a_millimetre_column_is_named_beside_a_fit_at_the_noise_level(tmp_path):
    import json

    from diffwear.cli import main

    folder = _thesis_rig_with_depth(tmp_path, "0.000485")  # Table 7-6's 0.485 mm, in metres
    out = tmp_path / "out"
    assert main(["calibrate", str(folder), "--out", str(out), "--quiet",
                 "--no-dynamic-check"]) == 0
    s = json.loads((out / "summary.json").read_text())
    (w,) = s["unit_warnings"]
    assert w["series"] == "max_depth" and 0.5e-3 < w["factor"] < 2e-3
    assert "metres in a millimetre column" in (out / "report.md").read_text()


def test_the_manifest_is_written_without_the_unit_conversions_noise(tmp_path):
    """k = 5.05e-13 1/Pa is written 0.000505 mm^3/(N m) (not the conversion's
    0.0005050000000000001), a clearance of 9.533 - 9.5 mm as 0.033 mm (not
    0.032999999999999474) and reads back within 1e-12; the series' data keep
    their round-trip digits."""
    x = np.linspace(0.0, 2 * np.pi, 37)[:-1]
    y = 1e-5 * (1 + np.cos(x)) / 3  # digits to the last bit
    params = {"k": Parameter("k", 5.05e-13, 0.3 * 5.05e-13, True),
              "clearance": Parameter("clearance", 9.533e-3 - 9.5e-3)}
    d = write_dataset(tmp_path / "ds", name="noise", parameters=params,
                      series=[Series("p", "profile", "p.csv", 1000, x, y, 2e-6)])
    text = (tmp_path / "ds" / "dataset.toml").read_text()
    assert 'k = { value = "0.000505 mm^3/(N m)", std = "0.0001515 mm^3/(N m)"' in text
    assert 'clearance = { value = "0.033 mm" }' in text
    assert d.parameters["k"].value == pytest.approx(5.05e-13, rel=1e-12)
    assert d.parameters["clearance"].value == pytest.approx(3.3e-5, rel=1e-12)
    np.testing.assert_allclose(d.series[0].y, y, rtol=1e-15)
