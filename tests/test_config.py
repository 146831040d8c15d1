"""Mechanism files: units, the loader's validation rules, the design-study round
trip against `presets.slider_crank`, and ``diffwear run``."""

import csv
import json
import math
import re
import tomllib
from fractions import Fraction
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from diffwear import cli
from diffwear.choices import SHIPPED_MECHANISMS
from diffwear.config import FORCE_TYPES, JOINT_TYPES, ElementType, load, load_dict, loads, schema
from diffwear.config import units as U
from diffwear.dynamics import Baumgarte, simulate
from diffwear.errors import InputError
from diffwear.mechanism import LinearSpring
from diffwear.mechanism_file import motion
from diffwear.presets import slider_crank

ROOT = Path(__file__).resolve().parents[1]
DESIGN = SHIPPED_MECHANISMS / "ideal_slider_crank.toml"
TEXT = DESIGN.read_text()
SHORT_T = 0.5  # s
SHORT_N = 51


def short_text(extra: str = "") -> str:
    """The design file with a 0.5 s run (shared by the round trip and the CLI test,
    so that both use one compiled integrator)."""
    text = TEXT.replace('duration = "2 s"', f'duration = "{SHORT_T} s"')
    return text.replace("n_save = 401", f"n_save = {SHORT_N}") + extra


def with_(old: str, new: str, text: str = TEXT) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def error_of(text: str) -> str:
    with pytest.raises(InputError) as info:
        loads(text, file="m.toml")
    return str(info.value)


# ----------------------------------------------------------------------------- units
@pytest.mark.parametrize("text, dim, si", [
    ("20 mm", "length", 0.02), ("1.75 m", "length", 1.75), ("1750 mm", "length", 1.75),
    ("-3 cm", "length", -0.03), ("5 um", "length", 5e-6), ("5 µm", "length", 5e-6),
    ("30 rpm", "angular speed", math.pi), ("3.14159 rad/s", "angular speed", 3.14159),
    ("180 deg/s", "angular speed", math.pi), ("0.5 rev/s", "angular speed", math.pi),
    ("90 deg", "angle", math.pi / 2), ("1 rev", "angle", 2 * math.pi),
    ("10 kg", "mass", 10.0), ("500 g", "mass", 0.5),
    ("45 kg m^2", "inertia", 45.0), ("45 kg*m^2", "inertia", 45.0), ("45 kg·m²", "inertia", 45.0),
    ("2e6 g mm^2", "inertia", 2e-3),
    ("525.4 N/m", "stiffness", 525.4), ("1 N/mm", "stiffness", 1000.0),
    ("2 ms", "time", 2e-3), ("1 min", "time", 60.0), ("250 1/s", "rate", 250.0),
    ("3 kN", "force", 3000.0), ("207 GPa", "pressure", 207e9), ("1.5 N m", "torque", 1.5),
    ("20 N s/m", "damping", 20.0), ("-9.80665 m/s^2", "acceleration", -9.80665),
    ("  7.5e-1   m ", "length", 0.75), (".5mm", "length", 5e-4),
])
def test_parse_quantity(text, dim, si):
    assert U.parse_quantity(text, dim) == si  # exact: one rounding, then pi once


@pytest.mark.parametrize("text, dim, words", [
    ("10", "mass", ["no unit", "kg"]),
    ("10 kgs", "mass", ["unknown unit 'kgs'", "did you mean 'kg'", "allowed: kg, g"]),
    ("10 m", "mass", ["'m' is a length unit, not mass", "allowed: kg, g"]),
    ("kg", "mass", ["does not start with a number"]),
    ("nan kg", "mass", ["not finite"]), ("-inf m", "length", ["not finite"]),
    ("1e400 m", "length", ["out of the float64 range"]),
    ("30 Hz", "angular speed", ["unknown unit 'Hz'", "rpm"]),
    ("1 MPA", "pressure", ["did you mean 'MPa'"]),
])
def test_parse_quantity_errors(text, dim, words):
    with pytest.raises(InputError) as info:
        U.parse_quantity(text, dim)
    for w in words:
        assert w in str(info.value)


def test_key_suffixes():
    assert [U.key_suffix(u) for u in ("kg", "kg m^2", "rad/s", "N/m", "1/s", "N s/m", "m/s^2")] == [
        "kg", "kg_m2", "rad_per_s", "N_per_m", "per_s", "N_s_per_m", "m_per_s2"]
    assert U.to_si(30, "rpm", "angular speed") == math.pi
    assert U.to_si(1.75, "m", "length") == 1.75


_UNIT_CASES = [(d, u) for d, dim in U.DIMENSIONS.items() for u in dim.units]


def _factor(dim, unit):
    u = U.DIMENSIONS[dim].units[unit]
    return float(u.scale) * math.pi**u.pi_power


@settings(max_examples=200, deadline=None)
@given(v=st.floats(min_value=1e-300, max_value=1e300),
       unit=st.sampled_from(list(U.DIMENSIONS["length"].units)))
def test_any_positive_length_round_trips_to_si(v, unit):
    si = U.parse_quantity(f"{v!r} {unit}", "length")
    assert si == float(Fraction(repr(v)) * U.DIMENSIONS["length"].units[unit].scale)  # exact
    assert math.isclose(si / _factor("length", unit), v, rel_tol=1e-15)
    # the key-named-unit spelling gives the same number
    assert U.to_si(v, unit, "length") == si


@settings(max_examples=200, deadline=None)
@given(v=st.floats(min_value=-1e200, max_value=1e200), case=st.sampled_from(_UNIT_CASES))
def test_any_finite_quantity_in_any_unit(v, case):
    dim, unit = case
    si = U.parse_quantity(f"{v!r} {unit}", dim)
    assert math.isclose(si, v * _factor(dim, unit), rel_tol=1e-15, abs_tol=1e-300)


@settings(max_examples=300, deadline=None)
@given(text=st.text(max_size=30), dim=st.sampled_from(list(U.DIMENSIONS)))
def test_garbage_quantity_strings_give_input_error_only(text, dim):
    try:
        value = U.parse_quantity(text, dim)
    except InputError as err:
        assert "allowed:" in str(err)
    else:
        assert math.isfinite(value)


@settings(max_examples=200, deadline=None)
@given(number=st.from_regex(r"[+-]?\d{1,4}(\.\d{0,3})?([eE][+-]?\d{1,3})?", fullmatch=True),
       unit=st.sampled_from([u for _, u in _UNIT_CASES] + ["", "x", "kg m", "m/s/s", "1/m"]),
       dim=st.sampled_from(list(U.DIMENSIONS)))
def test_number_unit_combinations_never_crash(number, unit, dim):
    try:
        U.parse_quantity(f"{number} {unit}", dim)
    except InputError:
        pass


# ----------------------------------------------------------------------------- loader
def test_design_file_matches_preset_structure_and_numbers():
    study = load(DESIGN)
    mech, q_guess = slider_crank()
    assert jax.tree_util.tree_structure(study.mechanism) == jax.tree_util.tree_structure(mech)
    for a, b in zip(jax.tree_util.tree_leaves(study.mechanism), jax.tree_util.tree_leaves(mech),
                    strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(study.q_guess, q_guess)
    sim = study.simulation
    assert (sim.duration, sim.n_save, sim.rtol, sim.atol) == (2.0, 401, 1e-8, 1e-8)
    base = Baumgarte()
    assert (sim.baumgarte_alpha, sim.baumgarte_beta) == (float(base.alpha), float(base.beta))
    assert [(r.joint, r.on) for r in study.reactions] == [
        ("crank_rod", "rod"), ("ground_crank", "crank"), ("driver", "crank")]
    assert study.title and "Table 2-1" in study.source


def test_defaults_are_the_python_api_defaults():
    text = re.sub(r"(?ms)^\[simulation\].*?^\[outputs\]",
                  '[simulation]\nduration = "1 s"\n\n[outputs]', TEXT)
    sim = loads(text).simulation
    assert (sim.rtol, sim.atol, sim.max_steps) == (1e-8, 1e-8, 2_000_000)
    assert (sim.baumgarte_alpha, sim.baumgarte_beta) == (250.0, 250.0)


def test_key_named_units_and_aliases_equal_strings():
    text = with_('mass = "10 kg"', "mass_kg = 10")
    text = with_('point_i = ["1 m", "0 m"]', "point_i_m = [1.0, 0]", text)
    text = with_('omega = "30 rpm"', "omega_rad_per_s = 3.141592653589793", text)
    text = with_('inertia = "45 kg m^2"', 'inertia = "45e6 kg mm^2"', text)
    text = with_('duration = "2 s"', "duration_ms = 2000", text)
    a, b = load(DESIGN), loads(text)
    for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b), strict=True):
        np.testing.assert_array_equal(x, y)
    assert b.simulation.duration == 2.0


def test_bom_and_bytes_accepted():
    study = loads(b"\xef\xbb\xbf" + TEXT.encode())
    assert study.mechanism.body_names == ("crank", "rod", "slider")


@pytest.mark.parametrize("old, new, words", [
    ('mass = "10 kg"', "mass = 10", ["bodies[0].mass", "bare number 10", "mass_kg"]),
    ('mass = "10 kg"', 'mas = "10 kg"', ["bodies[0].mas", "unknown key", "did you mean 'mass'"]),
    ('mass = "10 kg"', 'mass = "0 kg"', ["bodies[0].mass", "out of range", "> 0 kg"]),
    ('rtol = 1e-8', "rtol = nan", ["simulation.rtol", "not finite"]),
    ('type = "revolute"', 'type = "pin"',
     ["joints[0].type", "unknown joint type 'pin'", "revolute"]),
    ('body_i = "rod"', 'body_i = "rdo"',
     ["joints[2].body_i", "unknown body 'rdo'", "did you mean 'rod'"]),
    ('duration = "2 s"', 'duration = "-1 s"',
     ["simulation.duration", "out of range", "(0, 100000] s"]),
    ('n_save = 401', "n_save = 20_000_000", ["simulation.n_save", "out of range"]),
    ('point_i = ["1 m", "0 m"]', 'point_i = ["1 m", "0 kg"]',
     ["joints[1].point_i[1]", "mass unit"]),
])
def test_validation_rules(old, new, words):
    msg = error_of(with_(old, new))
    assert msg.startswith("m.toml: ")
    for w in words:
        assert w in msg, msg


def test_missing_key_and_type_and_syntax():
    assert "bodies[1].inertia: missing key" in error_of(with_('inertia = "35 kg m^2"', ""))
    msg = error_of(with_('mass = "15 kg"', "mass = true"))
    assert "bodies[1].mass" in msg and "boolean" in msg
    msg = error_of(with_("n_save = 401", "n_save = 401 401"))
    line = TEXT[: TEXT.index("n_save = 401")].count("\n") + 1
    assert "invalid TOML" in msg and f"line {line}" in msg


def test_registry_is_extensible():
    """A new element type is usable from files once registered (clearance joints will be)."""
    FORCE_TYPES["test_spring"] = ElementType(
        fields={"name": schema.Text(name=True), "body": schema.BodyRef(ground=False),
                "stiffness": schema.Quantity(dimension="stiffness", low=0.0)},
        build=lambda v: LinearSpring(v["name"], v["body"], (0.0, 0.0), "ground", (0.0, 0.0),
                                     v["stiffness"], 0.0),
        doc="test only")
    try:
        extra = ('\n[[forces]]\ntype = "test_spring"\nname = "s"\nbody = "slider"\n'
                 'stiffness = "2 kN/m"\n')
        text = TEXT.replace("\n[initial]", extra + "\n[initial]")
        study = loads(text)
        assert study.mechanism.element("s").stiffness == 2000.0
        typo = text.replace('stiffness = "2', 'stifness = "2')
        assert "unknown key 'stifness' (did you mean 'stiffness'?)" in error_of(typo)
    finally:
        del FORCE_TYPES["test_spring"]
    assert "test_spring" not in FORCE_TYPES and "revolute" in JOINT_TYPES


# Any mutation of a valid description is either accepted or an InputError.
_toml_scalars = (st.text(max_size=12) | st.integers(-(2**63), 2**63 - 1) | st.floats()
                 | st.booleans() | st.dates()
                 | st.sampled_from(["1 m", "0 kg", "30 rpm", "crank", "ground", "revolute",
                                    "spring", "-1 kg m^2", "nan m", "1e9 s", "2 N/m"]))
_toml_values = st.recursive(
    _toml_scalars,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(
        st.sampled_from(["name", "type", "x", "mass", "on", "joint", "g", "bogus"]), inner,
        max_size=3),
    max_leaves=6)
_BASE = tomllib.loads(TEXT)


def _locations(node, path=()):
    yield path
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _locations(v, (*path, k))
    elif isinstance(node, list):
        for k, v in enumerate(node):
            yield from _locations(v, (*path, k))


_PATHS = [p for p in _locations(_BASE) if p]


def _mutate(data, path, action, value, new_key):
    import copy

    data = copy.deepcopy(data)
    parent = data
    for k in path[:-1]:
        parent = parent[k]
    last = path[-1]
    if action == "replace":
        parent[last] = value
    elif action == "delete":
        del parent[last]
    elif isinstance(parent[last], dict):
        parent[last][new_key] = value
    else:
        parent[last] = [parent[last], value]
    return data


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(path=st.sampled_from(_PATHS), action=st.sampled_from(["replace", "delete", "add"]),
       value=_toml_values, new_key=st.sampled_from(["bogus", "mass", "type", "point_i_m", "x"]))
def test_mutated_descriptions_give_input_error_or_a_study(path, action, value, new_key):
    data = _mutate(_BASE, path, action, value, new_key)
    try:
        study = load_dict(data, file="fuzz.toml")
    except InputError as err:
        assert str(err).startswith("fuzz.toml: ")
    else:
        assert study.mechanism.n_coords == 9


@settings(max_examples=150, deadline=None)
@given(data=st.binary(max_size=200) | st.text(max_size=200).map(str.encode))
def test_random_bytes_give_input_error(data):
    with pytest.raises(InputError):
        loads(data, file="junk.toml")


# ----------------------------------------------------------------------------- simulation
@pytest.fixture(scope="module")
def short_study():
    return loads(short_text(), file="short.toml")


def test_design_file_trajectory_equals_preset(short_study):
    mech, q_guess = slider_crank()
    ts = jnp.linspace(0.0, SHORT_T, SHORT_N)
    # The file's run (runner: its own integrator settings) against `simulate`
    # with its defaults.  Both are assembled by the runner's compiled
    # `consistent_state` (the eager one agrees to ~1e-16 but costs seconds).
    y0_file = motion.initial_state(short_study)
    y0_ref = motion._consistent_state(mech, q_guess)
    np.testing.assert_array_equal(y0_file, y0_ref)
    ref = jax.jit(lambda m, y: simulate(m, y, SHORT_T, ts=ts))(mech, y0_ref).raise_if_failed()
    traj = motion.integrate(short_study, y0_file)
    np.testing.assert_allclose(traj.ts, ref.ts, rtol=0, atol=1e-15)
    np.testing.assert_allclose(traj.ys, ref.ys, rtol=1e-12, atol=1e-12)
    assert float(jnp.max(jnp.abs(traj.ys[:, 2] - math.pi * ts))) < 1e-9  # driven crank angle


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory):
    base = tmp_path_factory.mktemp("cli")
    src = base / "short.toml"
    src.write_text(short_text())
    out = base / "out"
    code = cli.main(["run", str(src), "--out", str(out), "--quiet"])
    return code, src, out


def test_cli_run_writes_outputs(cli_run):
    code, src, out = cli_run
    assert code == 0
    names = {p.name for p in out.iterdir()}
    assert {"summary.json", "report.md", "trajectory.csv", "trajectory.png", "reactions.png",
            "input.toml", "reaction_crank_rod.csv", "reaction_ground_crank.csv",
            "reaction_driver.csv"} <= names
    assert (out / "input.toml").read_text() == src.read_text()
    with open(out / "trajectory.csv") as f:
        rows = list(csv.reader(f))
    assert rows[0][:4] == ["t_s", "crank_x_m", "crank_y_m", "crank_phi_rad"]
    assert "slider_omega_rad_s" in rows[0] and len(rows) == SHORT_N + 1
    data = np.loadtxt(out / "reaction_crank_rod.csv", delimiter=",", skiprows=1)
    with open(out / "reaction_crank_rod.csv") as f:
        assert f.readline().strip() == "t_s,fx_N,fy_N,m_Nm"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["max_constraint_violation"] < 1e-8
    assert summary["reactions"]["crank_rod"]["on_body"] == "rod"
    assert math.isclose(summary["reactions"]["crank_rod"]["max_force_N"],
                        np.hypot(data[:, 1], data[:, 2]).max(), rel_tol=1e-9)
    assert summary["wall_time_s"] > 0 and summary["integrator_steps"] > 0
    assert summary["compile_time_s"] > 0 and summary["run_time_s"] > 0
    assert math.isclose(summary["compile_time_s"] + summary["run_time_s"],
                        summary["wall_time_s"], rel_tol=1e-12)
    # an ideal mechanism started on its constraints has no start-up transient:
    # the settled maxima are the whole run's
    assert summary["start_up_transient"] == {"settled": True, "length_s": 0.0}
    assert summary["reactions"]["crank_rod"]["settled_max_force_N"] == \
        summary["reactions"]["crank_rod"]["max_force_N"]
    report = (out / "report.md").read_text()
    assert "| start-up transient | 0 s |" in report and "No transient" in report
    for link in re.findall(r"\]\(([^)]+)\)", report):
        assert (out / link).exists(), link


def test_cli_never_overwrites_without_flag(cli_run):
    code, src, out = cli_run
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert cli.main(["run", str(src), "--out", str(out), "--quiet"]) == 2
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_cli_solver_failure_exit_code_3(tmp_path, capsys):
    src = tmp_path / "m.toml"
    # 200 steps pass the up-front budget (0.25 revolutions x 500 per revolution)
    # but not the solver (~570 steps for a quarter revolution)
    src.write_text(short_text().replace("max_steps = 2_000_000", "max_steps = 200"))
    assert cli.main(["run", str(src), "--out", str(tmp_path / "out"), "--quiet"]) == 3
    assert "m.toml" in capsys.readouterr().err


def test_documented_units_table_matches_the_parser():
    readme = (ROOT / "docs" / "reference" / "mechanism-files.md").read_text()
    rows = dict(re.findall(r"^\| ([a-z ]+) \| ([^|]+) \|$", readme, flags=re.M))
    for name, dim in U.DIMENSIONS.items():
        assert rows[name].strip() == ", ".join(dim.units), name


def test_shipped_mechanisms_load_by_name_and_a_path_wins_over_a_name(tmp_path, monkeypatch):
    from diffwear.config.loader import resolve, shipped_mechanisms

    assert set(shipped_mechanisms()) == {"ideal_slider_crank", "clearance_slider_crank", "rig",
                                         "rig_lubricated", "four_bar_wear",
                                         "four_bar_lubricated"}
    assert load("rig").file == str(SHIPPED_MECHANISMS / "rig.toml")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "rig").write_text("not a mechanism")
    assert resolve("rig") == Path("rig")
    with pytest.raises(InputError, match="or a shipped mechanism: clearance_slider_crank, "
                                         "four_bar_lubricated, four_bar_wear, "
                                         "ideal_slider_crank, rig, rig_lubricated"):
        load("rigg")
