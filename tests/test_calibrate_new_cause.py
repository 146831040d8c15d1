"""A cause the library does not have, written in this one file: a new
multiplicative effect and a new variable of the learned discrepancy, added
to the calibration's library and found in synthetic campaigns made with them.

Nothing else in the package knows them: the forward models read their hooks
(`Effect.rate`, `Variable.basis` and `Variable.read`), the loop scores, refits and
names them by the library it is given (`ModelSettings.library`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
import pytest

jax.config.update("jax_enable_x64", True)

from diffwear.calibrate import load_dataset  # noqa: E402
from diffwear.calibrate.discrepancy import Variable  # noqa: E402
from diffwear.calibrate.effects import (  # noqa: E402
    LIBRARY,
    Effect,
    EffectValues,
    Shape,
    rate_factor,
)
from diffwear.calibrate.fit import Fitter, ModelSettings, Problem  # noqa: E402
from diffwear.calibrate.identify import calibrate  # noqa: E402
from diffwear.calibrate.synthetic import Plan, synthesize  # noqa: E402


@dataclass(frozen=True)
class GreaseDepletion(Effect):
    """A grease charge used up after about N_d cycles: the rate rises by a
    factor (1 + s) as it runs out, k (1 + s / (1 + exp(-(N - N_d) / (N_d /
    10)))), at the middle of each step (N_d: the shape)."""

    def rate(self, strength, shape, point):
        return 1.0 + strength * jax.nn.sigmoid((point.middle - shape) / (0.1 * shape))


@dataclass(frozen=True)
class WornVolume(Variable):
    """The worn volume V: powers 1..3 of tanh(V / 5 mm^3), zero on the unworn
    bushing (the rig wears a few mm^3 in a thousand cycles)."""

    name: str = "volume"
    words: str = "the worn volume"
    unit: str = "mm^3"
    scale: float = 1e9
    reference: float = 5e-9   # m^3

    def prior_std(self) -> np.ndarray:
        """A wide prior (3 per coefficient): the truth below (0.8) sits well inside
        it, so the fit is the data's, not the prior's."""
        return np.full(3, 3.0)

    def basis(self, x, window: float = 1.0):
        xi = jnp.tanh(jnp.asarray(x, dtype=float) / self.reference)
        return jnp.stack([xi, xi ** 2, xi ** 3], axis=-1)

    def read(self, point):
        return point.volume

    def span(self, data) -> tuple:
        weighed = [float(np.max(s.y)) for s in data.series if s.kind == "volume"]
        return (0.0, max(weighed, default=self.reference))


GREASE = GreaseDepletion("grease_depletion", "k (1 + s sigmoid((N - N_d) / (N_d / 10)))", 0.3,
                         0.0, Shape("depletion_cycles", 500.0, "cycles", math.log(3.0)))
LIBRARY_PLUS = LIBRARY.extended(effects=(GREASE,), variables=(WornVolume(),))
SETTINGS = ModelSettings(n_theta=40, force_samples=41, steps=20, library=LIBRARY_PLUS)
PLAN = Plan(cycles=1000.0, profile_cycles=(250.0, 500.0, 750.0, 1000.0),
            volume_cycles=tuple(50.0 * i for i in range(1, 21)), force_cycles=(0.0,),
            profile_angles=48, force_angles=48, holdout_from_cycles=750.0)


def test_the_new_cause_is_zero_at_zero_and_its_closed_form_otherwise():
    theta = jnp.linspace(0.0, 2 * jnp.pi, 7)
    h = jnp.zeros(7)
    zero = EffectValues.zero(LIBRARY_PLUS)
    np.testing.assert_array_equal(rate_factor(zero, h, 0.0, 0.0, 10.0, theta, 1000.0),
                                  np.ones(7))
    e = EffectValues.of(LIBRARY_PLUS, grease_depletion=0.4, depletion_cycles=600.0)
    # the step [550, 650]: its middle is N_d, where the sigmoid is 1/2
    np.testing.assert_allclose(rate_factor(e, h, 0.0, 550.0, 100.0, theta, 1000.0),
                               np.full(7, 1.2), rtol=1e-14)
    # the new variable's factor on a step's rate: 1 + c1 tanh(V / 5 mm^3)
    d = zero.with_discrepancy("volume", [0.5, 0.0, 0.0])
    g = rate_factor(d, h, 5e-9, 0.0, 10.0, theta, 1000.0)
    np.testing.assert_allclose(g, np.full(7, 1.0 + 0.5 * math.tanh(1.0)), rtol=1e-14)


@pytest.fixture(scope="module")
def grease_campaign(tmp_path_factory):
    folder = tmp_path_factory.mktemp("new_cause") / "grease"
    synthesize(folder, name="grease", seed=5, plan=PLAN, settings=SETTINGS,
               effects=EffectValues.of(LIBRARY_PLUS, grease_depletion=1.0,
                                       depletion_cycles=400.0))
    return load_dataset(folder)


@pytest.mark.extended  # a whole calibration loop: about a minute
def test_the_loop_names_a_new_effect_added_in_one_file(grease_campaign):
    c = calibrate(grease_campaign, SETTINGS, check=False, discrepancy=(), outlook=None,
                  log=lambda *_: None)
    s = c.summary()
    assert s["effect_identified"] == "grease_depletion"
    (e,) = s["effects_identified"]
    assert abs(e["strength"] - 1.0) <= 3 * e["strength_std"]
    assert s["heldout_rmse_after"] < min(s["heldout_rmse_before"], 1.5)
    # the report's library lists it
    assert any(cand["name"] == "grease_depletion" for cand in s["candidates"])


@pytest.mark.extended  # two fits on the quasi-static model: half a minute
def test_a_new_discrepancy_variable_is_fitted_and_described(grease_campaign):
    """Data made with a discrepancy over the worn volume (the new variable):
    the fit over it recovers the truth's k (1 + delta) over the volumes the
    campaign reaches, and the loop's words name it."""
    import dataclasses

    from diffwear.calibrate import learned

    p = Problem.from_dataset(grease_campaign, SETTINGS)
    coef = np.array([0.8, 0.0, 0.0])
    truth = EffectValues.zero(LIBRARY_PLUS).with_discrepancy("volume", coef)
    y = np.asarray(jax.jit(p.predict)(np.zeros(p.n_base), truth))
    f = Fitter(dataclasses.replace(p, y=y))
    before = f.fit(None)
    res = f.fit(None, discrepancy="volume")
    assert res.discrepancy == "volume"
    # noise-free data: the base model misses them by 0.7 sigma RMS.  A trend
    # in the worn volume acts unlike k over the data, so no direction of its
    # coefficients is taken out to keep k identified (`Fitter.k_direction`):
    # the discrepancy reaches the truth and takes the misfit away
    assert f.k_direction("volume") is None
    assert res.chi2_fit < 1e-3 * before.chi2_fit
    # and predicts the held-out inspections as well
    assert res.chi2_holdout < 1e-3 * before.chi2_holdout
    # k (1 + delta) rises with the worn volume as the truth's does, within
    # 1 % of it over the volumes the fit window reaches
    (weighed,) = [s for s in grease_campaign.series if s.kind == "volume"]
    v = np.linspace(0.1, 1.0, 10) * float(np.max(weighed.y[~weighed.holdout]))
    phi = np.asarray(WornVolume().basis(jnp.asarray(v)))
    k0 = float(p.base0["k"])
    k = float(p.base(jnp.asarray(res.notes["x"]))["k"])   # the model's k
    c = np.asarray(res.discrepancy_coefficients)
    rate = k * (1 + phi @ c)
    assert rate[-1] > 1.3 * rate[0]
    np.testing.assert_allclose(rate, k0 * (1 + phi @ coef), rtol=0.01)
    b = np.asarray(res.notes["log_k_per_coefficient"])
    words = learned.describe("volume", c, res.discrepancy_cov, grease_campaign, b,
                             LIBRARY_PLUS)
    assert words["variable"] == "volume" and "mm^3" in words["shape"]
    assert learned.label(learned.candidate("volume"), LIBRARY_PLUS) == \
        "discrepancy in the worn volume"
