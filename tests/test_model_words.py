"""What the reports say of a wear model (`diffwear.studies.model_words`): the
settings and route numbers of the stored study runs, the labels the
validation pages print, and the plain words of a model of another class."""

import json
from pathlib import Path
from types import SimpleNamespace
from typing import ClassVar

import numpy as np
import pytest

from diffwear.models import AbstractWearModel, Dynamic, FemRoute, QuasiStatic
from diffwear.presets import RIG_JOINT
from diffwear.studies import model_words
from diffwear.studies._wear_common import dynamic_model
from diffwear.wear import Constant
from diffwear.wear.fem_route import default_model

ROOT = Path(__file__).resolve().parents[1]
STORED = ROOT / "design_studies" / "results" / "studies"
SETTINGS = ("model", "method", "extrapolation", "contact", "integrator")


def _stored(study: str) -> dict:
    return json.loads((STORED / study / "summary.json").read_text())


@pytest.mark.parametrize("study, cycles, integrator", [("wear-5000", 5000, "tsit5"),
                                                       ("rig-21400", 21400, "rodas4")])
def test_the_dynamic_settings_are_those_of_the_stored_runs(study, cycles, integrator):
    """The studies' dynamic model (50 dynamic cycles on the study's
    integrator) reports the settings its stored summary.json holds."""
    stored = _stored(study)
    got = model_words.describe(dynamic_model(cycles, 50, integrator), cycles)
    assert got == {k: stored[k] for k in SETTINGS}


def test_the_fem_route_settings_and_numbers_are_those_of_the_stored_run():
    """rig-21400 on the FEM route (Constant A = 428, Rodas4): the settings of
    its summary.json, and the ring's numbers of its ``fem_route`` entry."""
    stored = _stored("rig-21400-fem")
    model = FemRoute(fem=default_model(RIG_JOINT), extrapolation=Constant(428.0),
                     cycle=dynamic_model(21400, 50, "rodas4").cycle)
    settings = model_words.describe(model, 21400)
    fem_keys = ("fem_refresh_interval", "fem_samples", "fem_layers", "fem_force")
    assert settings == {k: stored[k] for k in (*SETTINGS, *fem_keys)}
    # the reference route it is compared with reports the EFM contact
    assert model_words.describe(model.reference(), 21400)["contact"] == "efm"
    run = SimpleNamespace(state=SimpleNamespace(memory={"fem_explicit": np.asarray(0)}))
    route = model_words.route_summary(model, run)
    assert route == {k: stored["fem_route"][k] for k in route}
    assert set(route) == {"explicit_fallback_cycles", "refresh_interval", "samples_per_cycle",
                          "layers", "force", "youngs_modulus_Pa", "poisson_ratio",
                          "outer_radius_m"}
    assert model_words.route_summary(model.reference(), run) == {}


def test_labels_and_step_words_follow_the_class_and_its_bases():
    """The labels of the reports' tables (docs/validation/ch7-rig.md prints
    them) and the history figure's step words; the FEM route has a label of
    its own and the dynamic model's step words."""
    fem = FemRoute(fem=default_model(RIG_JOINT))
    assert [model_words.label(m) for m in (Dynamic(), QuasiStatic(), fem)] == [
        "diffwear (EFM)", "diffwear (quasi-static)", "diffwear (FEM route)"]
    assert [model_words.step_words(m) for m in (Dynamic(), QuasiStatic(), fem)] == [
        "simulated dynamic cycles", "wear ODE steps", "simulated dynamic cycles"]
    assert model_words.describe(QuasiStatic(samples=90), 100) == {
        "model": "quasi-static", "load_samples_per_cycle": 90}
    page = (ROOT / "docs" / "validation" / "ch7-rig.md").read_text()
    assert "diffwear (EFM)" in page


class _Other(AbstractWearModel):
    name: ClassVar[str] = "other"
    exact_gradients: ClassVar[bool] = True

    def solve(self, mech, joints, y0, *, period, cycles=None, limit=None,
              wall_thickness=None):
        raise NotImplementedError

    def joint_force(self, mech, joint, y0, *, period, evolution, samples=180):
        raise NotImplementedError

    def cycle_histories(self, mech, joint, y0, *, period, evolution):
        raise NotImplementedError


def test_a_model_of_another_class_gets_the_plain_words():
    other = _Other()
    assert model_words.label(other) == "diffwear"
    assert model_words.step_words(other) == "steps"
    assert model_words.describe(other, 10) == {"model": "other"}
    assert model_words.route_summary(other, None) == {}


def test_the_model_classes_hold_no_report_words_and_no_run():
    for cls in (AbstractWearModel, Dynamic, QuasiStatic, FemRoute):
        for attr in ("label", "step_words", "describe", "route_summary", "run"):
            assert not hasattr(cls, attr), (cls.__name__, attr)
