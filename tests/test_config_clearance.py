"""Clearance joints in mechanism files: the design files against the presets
(`clearance_slider_crank("efm", 0.5e-3)`, the Ch. 7 rig with `RIG_JOINT`), the
field rules, and ``contact_<joint>.csv`` from ``diffwear run``."""

import csv
import json
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from diffwear import cli
from diffwear.choices import SHIPPED_MECHANISMS
from diffwear.config import load, loads
from diffwear.contact import (
    PTFE,
    STEEL,
    ClearanceJoint,
    ElasticFoundation,
    KelvinVoigt,
    LankaraniNikravesh,
)
from diffwear.dynamics import simulate
from diffwear.errors import InputError
from diffwear.mechanism_file import motion
from diffwear.presets import (
    RIG_JOINT,
    clearance_slider_crank,
    rig_slider_crank,
    slider_crank,
    with_wear_joint,
)

ROOT = Path(__file__).resolve().parents[1]
DESIGN = SHIPPED_MECHANISMS / "clearance_slider_crank.toml"
RIG = SHIPPED_MECHANISMS / "rig.toml"
TEXT = DESIGN.read_text()
SHORT_T = 0.3  # s
SHORT_N = 31


def short_text(text: str = TEXT) -> str:
    text = text.replace('duration = "2 s"', f'duration = "{SHORT_T} s"')
    return text.replace("n_save = 401", f"n_save = {SHORT_N}")


def with_(old: str, new: str, text: str = TEXT) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def error_of(text: str) -> str:
    with pytest.raises(InputError) as info:
        loads(text, file="m.toml")
    return str(info.value)


def assert_same_leaves(a, b, rtol=1e-12):
    assert jax.tree_util.tree_structure(a) == jax.tree_util.tree_structure(b)
    for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b), strict=True):
        np.testing.assert_allclose(np.asarray(x), np.asarray(y), rtol=rtol, atol=0)


# ----------------------------------------------------------------------------- round trip
@pytest.fixture(scope="module")
def preset():
    return clearance_slider_crank("efm", 0.5e-3)


def test_design_file_matches_preset(preset):
    mech, _ = preset
    study = load(DESIGN)
    assert_same_leaves(study.mechanism, mech)
    joint = study.mechanism.element("crank_rod")
    assert isinstance(joint, ClearanceJoint) and isinstance(joint.law, ElasticFoundation)
    assert [c.name for c in study.mechanism.constraints] == [
        "ground_crank", "rod_slider", "slider_guide", "driver"]
    assert [c.name for c in study.assembly.constraints] == [
        "ground_crank", "crank_rod", "rod_slider", "slider_guide", "driver"]
    assert [o.joint for o in study.contacts] == ["crank_rod"]


@pytest.fixture(scope="module")
def short_study():
    return loads(short_text(), file="short.toml")


def test_design_file_trajectory_equals_preset(preset, short_study):
    """The file's run against `simulate` on the preset.  Both start from the
    runner's compiled assembly of the ideal slider-crank (the preset's eager
    `consistent_state` agrees to 1 ulp, 4e-16; the contact transient amplifies
    such a difference to ~4e-5 in 0.3 s, so the reference must use the same
    assembly to be comparable at 1e-10)."""
    mech, y_preset = preset
    ideal, q_guess = slider_crank()
    q, qd, _ = ideal.split(motion._consistent_state(ideal, q_guess))
    y_ref = mech.join(q, qd, mech.initial_aux(q, qd))
    y0 = motion.initial_state(short_study)
    np.testing.assert_array_equal(y0, y_ref)
    np.testing.assert_allclose(y0, y_preset, rtol=0, atol=1e-14)
    ts = jnp.linspace(0.0, SHORT_T, SHORT_N)
    ref = jax.jit(lambda m, y: simulate(m, y, SHORT_T, ts=ts))(mech, y_ref).raise_if_failed()
    traj = motion.integrate(short_study, y0)
    np.testing.assert_allclose(traj.ts, ref.ts, rtol=0, atol=1e-15)
    np.testing.assert_allclose(traj.ys, ref.ys, rtol=1e-10, atol=1e-10)


def test_rig_file_matches_preset():
    study = load(RIG)
    ideal, _ = rig_slider_crank()
    assert_same_leaves(study.mechanism, with_wear_joint(ideal, RIG_JOINT))
    assert study.mechanism.element("crank_rod").wear is not None


# ----------------------------------------------------------------------------- laws
def _law(spec: str, extra: str = "") -> str:
    text = with_('law = { type = "elastic-foundation", layer_thickness = "13.308686667365992 mm", '
                 'depth = "12.8 mm", restitution = 0.8, damping_mass = "15 kg" }', f"law = {spec}")
    return with_('n_theta = 180', f"n_theta = 180\n{extra}", text) if extra else text


def test_point_laws_use_the_existing_builders():
    rp, rb = 0.02, 0.02 + 0.5e-3
    ln = loads(_law('{ type = "lankarani-nikravesh", restitution = 0.8 }')).mechanism
    want = LankaraniNikravesh.from_materials(STEEL, PTFE, rp, rb, 0.8)
    assert_same_leaves(ln.element("crank_rod").law, want)
    kv = loads(_law('{ type = "kelvin-voigt", matched_to_load = "1 kN" }')).mechanism
    assert_same_leaves(kv.element("crank_rod").law, KelvinVoigt.matched_to(want))
    kv2 = loads(_law('{ type = "kelvin-voigt", stiffness = "2e8 N/m", restitution = 0.5 }'))
    law = kv2.mechanism.element("crank_rod").law
    assert float(law.stiffness) == 2e8 and float(law.restitution) == 0.5
    ln2 = loads(_law('{ type = "lankarani-nikravesh", stiffness = "7e10 N/m^1.5" }'))
    assert float(ln2.mechanism.element("crank_rod").law.stiffness) == 7e10


def test_bushing_radius_equals_clearance_and_damping_mass_defaults_to_bushing_body():
    a = load(DESIGN).mechanism
    text = with_('clearance = "0.5 mm"', 'bushing_radius = "20.5 mm"')
    text = text.replace(', damping_mass = "15 kg" }', " }")
    assert_same_leaves(loads(text).mechanism, a)


def test_wear_coefficient_units():
    text = _law('{ type = "elastic-foundation", layer_thickness = "13.31 mm", depth = "12.8 mm" }',
                'wear = { coefficient = "5.05e-4 mm^3/(N m)" }')
    k = loads(text).mechanism.element("crank_rod").wear.coefficient
    assert float(k) == 5.05e-13
    text2 = text.replace('coefficient = "5.05e-4 mm^3/(N m)"', "coefficient_mm3_per_N_m = 5.05e-4")
    assert float(loads(text2).mechanism.element("crank_rod").wear.coefficient) == 5.05e-13


@pytest.mark.parametrize("old, new, words", [
    ('clearance = "0.5 mm"', 'clearance = "-0.5 mm"',
     ["joints[1].clearance", "out of range", ">= 0 m"]),
    ('clearance = "0.5 mm"', 'bushing_radius = "19 mm"',
     ["joints[1].bushing_radius", "smaller than the pin radius", "negative clearance"]),
    ('clearance = "0.5 mm"', 'clearance = "0.5 mm"\nbushing_radius = "20.5 mm"',
     ["joints[1].clearance", "together with bushing_radius", "exactly one"]),
    ('clearance = "0.5 mm"', "", ["joints[1].bushing_radius", "missing key", "exactly one"]),
    ('youngs_modulus = "0.5 GPa"', 'youngs_modulus = "0 GPa"',
     ["joints[1].bushing_material.youngs_modulus", "out of range", "> 0 Pa"]),
    ("poisson_ratio = 0.38", "poisson_ratio = 0.5",
     ["joints[1].bushing_material.poisson_ratio", "out of range", "(-1, 0.5)"]),
    ('pin_material = "steel"', 'pin_material = "steal"',
     ["joints[1].pin_material", "unknown material 'steal'", "did you mean 'steel'"]),
    ("coefficient = 0.13", "coefficient = -0.1",
     ["joints[1].friction.coefficient", "out of range", ">= 0"]),
    ("restitution = 0.8", "restitution = 1.2",
     ["joints[1].law.restitution", "out of range", "(0, 1]"]),
    ("restitution = 0.8", "restitution = 0",
     ["joints[1].law.restitution", "out of range", "(0, 1]"]),
    ("n_theta = 180", "n_theta = 4", ["joints[1].n_theta", "out of range", "[8, 100000]"]),
    ('type = "elastic-foundation"', 'type = "elastic-fondation"',
     ["joints[1].law.type", "unknown law type", "did you mean 'elastic-foundation'"]),
    ('depth = "12.8 mm"', 'dept = "12.8 mm"',
     ["joints[1].law.dept", "unknown key", "did you mean 'depth'"]),
    ('bushing_material = { youngs_modulus = "0.5 GPa", poisson_ratio = 0.38 }  # PTFE, Table 3-2',
     "", ["joints[1].bushing_material", "missing key", "'ptfe'"]),
])
def test_clearance_validation(old, new, words):
    msg = error_of(with_(old, new))
    assert msg.startswith("m.toml: ")
    for w in words:
        assert w in msg, msg


def test_wear_needs_the_elastic_foundation():
    msg = error_of(_law('{ type = "kelvin-voigt", stiffness = "2e8 N/m" }',
                        'wear = { coefficient = "5.05e-4 mm^3/(N m)" }'))
    assert "joints[1].wear" in msg and "elastic-foundation" in msg and "point law" in msg
    msg = error_of(_law('{ type = "kelvin-voigt", restitution = 0.8 }'))
    assert "joints[1].law.stiffness" in msg and "matched_to_load" in msg


def test_outputs_name_clearance_joints():
    msg = error_of(with_('reactions = ["ground_crank", "driver"]',
                         'reactions = ["crank_rod"]'))
    assert "outputs.reactions[0]" in msg and "contact = ['crank_rod']" in msg
    msg = error_of(with_('contact = ["crank_rod"]', 'contact = ["driver"]'))
    assert "outputs.contact[0]" in msg and "not a clearance joint" in msg
    msg = error_of(with_('contact = ["crank_rod"]', 'contact = ["crank_rd"]'))
    assert "did you mean 'crank_rod'" in msg


# ----------------------------------------------------------------------------- CLI
def test_cli_writes_contact_csv(tmp_path):
    src = tmp_path / "short.toml"
    src.write_text(short_text())
    out = tmp_path / "out"
    assert cli.main(["run", str(src), "--out", str(out), "--quiet"]) == 0
    with open(out / "contact_crank_rod.csv") as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["t_s", "force_N", "normal_load_N", "theta_rad", "penetration_m"]
    assert len(rows) == SHORT_N + 1
    data = np.asarray(rows[1:], dtype=float)
    assert data[-1, 1] > 50.0 and np.all(data[:, 3] >= 0) and np.all(data[:, 3] < 2 * np.pi)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["contacts"]["crank_rod"]["file"] == "contact_crank_rod.csv"
    assert "contact_crank_rod.csv" in (out / "report.md").read_text()
