"""Malformed mechanism files: each one is an `InputError` whose message names
the problem, ``diffwear run`` exits with code 2, and a results folder given as
--out is left exactly as it was."""


import jax.numpy as jnp
import pytest

from diffwear import cli
from diffwear.choices import SHIPPED_MECHANISMS
from diffwear.config import load
from diffwear.errors import InputError
from diffwear.mechanism_file import motion

DESIGN = SHIPPED_MECHANISMS / "ideal_slider_crank.toml"
TEXT = DESIGN.read_text()
CLEARANCE = (DESIGN.parent / "clearance_slider_crank.toml").read_text()
EFM = ('law = { type = "elastic-foundation", layer_thickness = "13.308686667365992 mm", '
       'depth = "12.8 mm", restitution = 0.8, damping_mass = "15 kg" }')
SPRING = """
[[forces]]
type = "spring"
name = "return_spring"
body_i = "slider"
point_i = ["0 m", "0 m"]
body_j = "ground"
point_j = ["8 m", "0 m"]
stiffness = "525.4 N/m"
free_length = "2 m"
"""


def sub(old: str, new: str, text: str = TEXT) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def line_of(snippet: str) -> int:
    return TEXT[: TEXT.index(snippet)].count("\n") + 1


def csub(old: str, new: str) -> str:
    """The clearance design file with one edit."""
    return sub(old, new, CLEARANCE)


def _before_initial(block: str) -> str:
    return TEXT.replace("\n[initial]", block + "\n[initial]")


# (id, file content (str or bytes), words the message must contain)
CASES = [
    ("empty", "", ["file is empty"]),
    ("only-comments", "# nothing here\n\n", ["no keys or tables"]),
    ("non-utf8", TEXT.encode().replace(b"# Conventions", b"# Conventions \xff\xfe"),
     ["not UTF-8", f"line {line_of('# Conventions')}"]),
    ("toml-syntax", sub('n_save = 401', 'n_save = = 401'),
     ["invalid TOML", f"line {line_of('n_save = 401')}"]),
    ("unclosed-array", sub('point_j = ["0 m", "0 m"]', 'point_j = ["0 m", "0 m"'),
     ["invalid TOML", "line"]),
    ("no-bodies", TEXT.replace("[[bodies]]", "[[bodys]]"), ["bodys", "did you mean 'bodies'"]),
    ("bodies-single-table", "[bodies]\nname = 'a'\n", ["bodies", "write [[bodies]]"]),
    ("missing-mass", sub('mass = "10 kg"           # Table 2-1, m1', ""),
     ["bodies[0].mass", "missing key", "kg"]),
    ("bare-number-mass", sub('mass = "10 kg"', "mass = 10"),
     ["bodies[0].mass", "bare number 10", "mass_kg"]),
    ("bare-number-point", sub('point_i = ["1 m", "0 m"]', "point_i = [1, 0]"),
     ["joints[1].point_i[0]", "bare number", "point_i_m"]),
    ("string-number-no-unit", sub('inertia = "45 kg m^2"', 'inertia = "45"'),
     ["bodies[0].inertia", "has no unit"]),
    ("negative-mass", sub('mass = "15 kg"', 'mass = "-15 kg"'),
     ["bodies[1].mass", "out of range", "> 0 kg"]),
    ("zero-inertia", sub('inertia = "35 kg m^2"', 'inertia = "0 kg m^2"'),
     ["bodies[1].inertia", "out of range"]),
    ("wrong-dimension", sub('mass = "30 kg"', 'mass = "30 m"'),
     ["bodies[2].mass", "length unit, not mass", "allowed: kg, g"]),
    ("unknown-unit", sub('point_i = ["1.75 m", "0 m"]', 'point_i = ["1.75 meters", "0 m"]'),
     ["joints[2].point_i[0]", "unknown unit 'meters'", "allowed: m, cm, mm, um"]),
    ("typo-key", sub('inertia = "45 kg m^2"', 'intertia = "45 kg m^2"'),
     ["bodies[0].intertia", "unknown key", "did you mean 'inertia'"]),
    ("typo-section", sub("[simulation]", "[simulaton]"),
     ["simulaton", "did you mean 'simulation'"]),
    ("unknown-joint-type", sub('type = "translational"', 'type = "prismatic"'),
     ["joints[3].type", "unknown joint type 'prismatic'", "translational"]),
    ("force-as-joint", sub('type = "driver"', 'type = "gravity"'),
     ["joints[4].type", "belongs under [[forces]]"]),
    ("missing-type", sub('type = "driver"\n', ""), ["joints[4].type", "missing key", "driver"]),
    ("unknown-body", sub('body_j = "rod"', 'body_j = "conrod"'),
     ["joints[1].body_j", "unknown body 'conrod'", "crank, rod, slider, ground"]),
    ("driver-on-ground", sub('body = "crank"', 'body = "ground"'),
     ["joints[4].body", "ground cannot be used"]),
    ("self-joint", sub('body_j = "rod"', 'body_j = "crank"'),
     ["joints[1]", "connects body 'crank' to itself"]),
    ("vector-length", sub('point_j = ["-1.75 m", "0 m"]', 'point_j = ["-1.75 m"]'),
     ["joints[1].point_j", "array of 2 values"]),
    ("zero-axis", sub('body_j = "ground"             # slides',
                      'axis_j = [0, 0]\nbody_j = "ground"             # slides'),
     ["joints[3].axis_j", "zero vector"]),
    ("nan-rtol", sub("rtol = 1e-8", "rtol = nan"), ["simulation.rtol", "not finite"]),
    ("inf-mass", sub('mass = "10 kg"', 'mass = "inf kg"'), ["bodies[0].mass", "not finite"]),
    ("huge-number", sub('mass = "10 kg"', 'mass = "1e999 kg"'),
     ["bodies[0].mass", "out of the float64 range"]),
    ("zero-duration", sub('duration = "2 s"', 'duration = "0 s"'),
     ["simulation.duration", "out of range", "(0, 100000] s"]),
    ("absurd-duration", sub('duration = "2 s"', 'duration = "30 h"'),
     ["simulation.duration", "108000 s is out of range"]),
    ("absurd-n-save", sub("n_save = 401", "n_save = 100_000_000"),
     ["simulation.n_save", "out of range", "1e+07"]),
    ("float-n-save", sub("n_save = 401", "n_save = 4e2"),
     ["simulation.n_save", "expected an integer", "write 400"]),
    ("tolerance-too-tight", sub("rtol = 1e-8", "rtol = 1e-20"),
     ["simulation.rtol", "out of range"]),
    ("negative-baumgarte", sub('baumgarte_beta = "250 1/s"', 'baumgarte_beta = "-5 1/s"'),
     ["simulation.baumgarte_beta", "out of range"]),
    ("omega-hz", sub('omega = "30 rpm"', 'omega = "0.5 Hz"'),
     ["joints[4].omega", "unknown unit 'Hz'", "rad/s, deg/s, rev/s, rpm"]),
    ("both-spellings", sub('mass = "10 kg"', 'mass = "10 kg"\nmass_kg = 10'),
     ["bodies[0].mass", "given twice"]),
    ("suffix-with-string", sub('mass = "10 kg"', 'mass_kg = "10 kg"'),
     ["bodies[0].mass_kg", "must be a plain number"]),
    ("boolean-mass", sub('mass = "10 kg"', "mass = true"), ["bodies[0].mass", "boolean"]),
    ("date-duration", sub('duration = "2 s"', "duration = 2024-01-01"),
     ["simulation.duration", "date/time"]),
    ("duplicate-body", sub('name = "slider"', 'name = "rod"'),
     ["bodies[2].name", "already the name of bodies[1]"]),
    ("body-named-ground", sub('name = "slider"', 'name = "ground"'),
     ["bodies[2].name", "reserved"]),
    ("bad-name", sub('name = "crank_rod"', 'name = "crank rod"'),
     ["joints[1].name", "not a valid name"]),
    ("non-ascii-name", sub('name = "slider"', 'name = "schieber_\u00e4"'),
     ["bodies[2].name", "ASCII"]),
    ("duplicate-element", sub('name = "driver"', 'name = "crank_rod"'),
     ["joints[4].name", "already the name of joints[1]"]),
    ("initial-missing-body", sub('slider = { x = "5.5 m",  y = "0 m", phi = "0 deg" }', ""),
     ["initial.slider", "missing guess"]),
    ("initial-unknown-body", sub("slider = {", "slidr = {"),
     ["initial.slidr", "did you mean 'slider'"]),
    ("initial-missing-phi", sub(', phi = "0 deg" }', " }"), ["initial.crank.phi", "missing key"]),
    ("no-initial", TEXT.replace("[initial]", "[initial_guess]"), ["initial_guess", "unknown key"]),
    ("no-simulation", TEXT.replace("[simulation]", "[outputs2]"), ["outputs2", "unknown key"]),
    ("no-duration", sub('duration = "2 s"               # one crank revolution', ""),
     ["simulation.duration", "missing key", "time"]),
    ("output-unknown-joint", sub('"ground_crank", "driver"]', '"ground_crank", "drive"]'),
     ["outputs.reactions[2]", "unknown joint 'drive'", "did you mean 'driver'"]),
    ("output-force-element", sub('"ground_crank", "driver"]', '"ground_crank", "gravity"]'),
     ["outputs.reactions[2]", "force element, not a joint"]),
    ("output-wrong-body", sub('on = "rod"', 'on = "slider"'),
     ["outputs.reactions[0].on", "not a (non-ground) body of joint 'crank_rod'"]),
    ("spring-negative-stiffness",
     _before_initial(SPRING.replace('"525.4 N/m"', '"-525.4 N/m"')),
     ["forces[1].stiffness", "out of range", ">= 0 N/m"]),
    ("spring-stiffness-unit", _before_initial(SPRING.replace('"525.4 N/m"', '"525.4 N"')),
     ["forces[1].stiffness", "'N' is a force unit, not stiffness", "N/m"]),
    ("gravity-bad-field", sub('g = ["0 m/s^2"', 'g_ms2 = ["0 m/s^2"'),
     ["forces[0].g_ms2", "unknown key", "did you mean 'g_m_per_s2'", "g_m_per_s2)"]),
    # clearance joints (the shipped clearance_slider_crank.toml)
    ("clearance-negative", csub('clearance = "0.5 mm"', 'clearance = "-0.5 mm"'),
     ["joints[1].clearance", "out of range", ">= 0 m"]),
    ("clearance-pin-larger", csub('clearance = "0.5 mm"', 'bushing_radius = "19.5 mm"'),
     ["joints[1].bushing_radius", "smaller than the pin radius", ">= pin_radius"]),
    ("clearance-and-radius", csub('clearance = "0.5 mm"',
                                  'clearance = "0.5 mm"\nbushing_radius = "20.5 mm"'),
     ["joints[1].clearance", "together with bushing_radius", "exactly one of"]),
    ("clearance-neither", csub('clearance = "0.5 mm"', 'clearence = "0.5 mm"'),
     ["joints[1].clearence", "unknown key", "did you mean 'clearance'"]),
    ("clearance-no-radius", csub('clearance = "0.5 mm"', ""),
     ["joints[1].bushing_radius", "missing key", "exactly one of bushing_radius and clearance"]),
    ("clearance-zero-modulus", csub('youngs_modulus = "0.5 GPa"', 'youngs_modulus = "-1 GPa"'),
     ["joints[1].bushing_material.youngs_modulus", "out of range", "> 0 Pa"]),
    ("clearance-poisson", csub("poisson_ratio = 0.38", "poisson_ratio = -1"),
     ["joints[1].bushing_material.poisson_ratio", "out of range", "(-1, 0.5)"]),
    ("clearance-material-name", csub('pin_material = "steel"', 'pin_material = "titanium"'),
     ["joints[1].pin_material", "unknown material 'titanium'", "'steel' | 'ptfe'"]),
    ("clearance-negative-friction", csub("coefficient = 0.13", "coefficient = -0.13"),
     ["joints[1].friction.coefficient", "out of range", ">= 0"]),
    ("clearance-restitution", csub("restitution = 0.8", "restitution = 1.5"),
     ["joints[1].law.restitution", "out of range", "(0, 1]"]),
    ("clearance-n-theta", csub("n_theta = 180", "n_theta = 7"),
     ["joints[1].n_theta", "out of range", "[8, 100000]"]),
    ("clearance-unknown-law", csub('type = "elastic-foundation"', 'type = "lankarani"'),
     ["joints[1].law.type", "unknown law type 'lankarani'", "did you mean 'lankarani-nikravesh'",
      "'kelvin-voigt'"]),
    ("clearance-wear-point-law",
     csub(EFM, 'law = { type = "lankarani-nikravesh" }\n'
               'wear = { coefficient = "5.05e-4 mm^3/(N m)" }'),
     ["joints[1].wear", "pressure distribution", "'lankarani-nikravesh' point law",
      "law.type = 'elastic-foundation'"]),
    ("clearance-wear-unit", csub(EFM, EFM + '\nwear = { coefficient = "5.05e-4 mm^3/N" }'),
     ["joints[1].wear.coefficient", "unknown unit", "mm^3/(N m)"]),
    ("clearance-as-reaction", csub('reactions = ["ground_crank", "driver"]',
                                   'reactions = ["crank_rod"]'),
     ["outputs.reactions[0]", "clearance joint", "contact = ['crank_rod']"]),
    ("contact-of-ideal-joint", csub('contact = ["crank_rod"]', 'contact = ["rod_slider"]'),
     ["outputs.contact[0]", "not a clearance joint", "'crank_rod'"]),
]


def _check_message(msg: str, file: str, words):
    assert msg.startswith(f"{file}: "), msg
    for w in words:
        assert w in msg, f"{w!r} not in {msg!r}"


@pytest.mark.parametrize("content, words", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_file(tmp_path, capsys, content, words):
    path = tmp_path / "model.toml"
    (path.write_bytes if isinstance(content, bytes) else path.write_text)(content)
    with pytest.raises(InputError) as info:
        load(path)
    _check_message(str(info.value), str(path), words)

    out = tmp_path / "results"
    out.mkdir()
    keep = out / "earlier.csv"
    keep.write_text("t_s\n0\n")
    stamp = keep.stat().st_mtime_ns
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    _check_message(err.removeprefix("diffwear: error: "), str(path), words)
    assert [p.name for p in out.iterdir()] == ["earlier.csv"]
    assert keep.read_text() == "t_s\n0\n" and keep.stat().st_mtime_ns == stamp


def test_missing_file_and_directory(tmp_path, capsys):
    out = tmp_path / "results"
    assert cli.main(["run", str(tmp_path / "nope.toml"), "--out", str(out)]) == 2
    assert "no such file" in capsys.readouterr().err and not out.exists()
    assert cli.main(["run", str(tmp_path), "--out", str(out)]) == 2
    assert "is a directory" in capsys.readouterr().err and not out.exists()


def test_unassemblable_mechanism_fails_before_output(tmp_path, capsys):
    """Valid file, impossible model: the slider guide 10 m above the crank pivot
    is out of reach (crank + rod = 5.5 m).  Bad input (exit 2), --out untouched.
    Same structure as the design file, so the compiled assembly is shared."""
    path = tmp_path / "model.toml"
    path.write_text(sub('body_j = "ground"             # slides',
                        'point_j = ["0 m", "10 m"]\nbody_j = "ground"             # slides'))
    study = load(path)  # the file itself is well-formed
    with pytest.raises(InputError) as info:
        motion.initial_state(study)
    _check_message(str(info.value), str(path), ["initial", "cannot be assembled"])
    out = tmp_path / "results"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    assert "cannot be assembled" in capsys.readouterr().err and not out.exists()


def test_diverged_assembly_is_diagnosed_at_the_guess(tmp_path, monkeypatch):
    """Newton ending in NaN (here forced) must give an InputError, not a LinAlgError
    from the SVD: a second driver on the crank makes the Jacobian singular."""
    extra = '\n[[joints]]\ntype = "driver"\nname = "driver2"\nbody = "crank"\nomega = "30 rpm"\n'
    path = tmp_path / "model.toml"
    path.write_text(TEXT.replace("\n[[forces]]", extra + "\n[[forces]]", 1))
    study = load(path)
    monkeypatch.setattr(motion, "_consistent_state",
                        lambda mech, q: jnp.full(mech.n_state, jnp.nan))
    with pytest.raises(InputError) as info:
        motion.initial_state(study)
    _check_message(str(info.value), str(path), ["initial", "singular", "driver2"])


def test_at_least_25_cases():
    assert len(CASES) >= 25


def test_a_near_zero_inertia_is_refused_naming_the_body_and_key(tmp_path, capsys):
    """1e-30 kg m^2 on a 0.5 kg crank (radius of gyration 1.4e-15 m): refused
    at the file's key, not an assembly failure with a tiny residual."""
    text = (SHIPPED_MECHANISMS / "four_bar_wear.toml").read_text()
    path = tmp_path / "tiny.toml"
    path.write_text(text.replace('inertia = "0.000417 kg m^2"', 'inertia = "1e-30 kg m^2"'))
    out = tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bodies[0].inertia" in err[0] and "'crank'" in err[0]
    assert "radius of gyration of 1.41e-15 m" in err[0] and not out.exists()


@pytest.mark.parametrize("old, new, cause", [
    ('bushing_radius = "6.05 mm"', 'bushing_radius = "20 mm"',
     "its clearance (14 mm) is larger than its pin radius (6 mm)"),
    ('layer_thickness = "4 mm"', 'layer_thickness = "0.01 mm"',
     "its bushing wall (law.layer_thickness 0.01 mm) is thinner than its clearance (0.05 mm)"),
])
def test_a_failed_cycle_model_names_the_input_that_makes_it(old, new, cause, tmp_path, capsys):
    text = (SHIPPED_MECHANISMS / "four_bar_wear.toml").read_text()
    assert old in text
    path = tmp_path / "joint.toml"
    path.write_text(text.replace(old, new))
    out = tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet", "--cycles", "2000"]) == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "the cycle model failed" in err[0]
    assert f"likely cause: {cause}" in err[0]
