"""`frame_check`: a profile recorded clockwise or from another zero is found,
with the manifest keys that declare its frame; a profile in the model's frame
with noise is left alone."""

import math

import numpy as np

from diffwear.calibrate.frame_check import frame_check

THETA = np.radians(np.arange(0.0, 360.0, 2.0))
SIGMA = 2e-6


def groove(theta):
    """A one-sided, skewed wear groove at 120 deg: its mirror image is not a
    rotation of it.  (A groove near 0 or 180 deg, like the Ch. 7 rig's at
    170 deg, mirrors onto itself: no check can tell the sense from it.)"""
    d = np.angle(np.exp(1j * (theta - math.radians(120.0))))
    return 60e-6 * np.exp(-(d / 0.5) ** 2) * (1.0 + 0.8 * np.tanh(d / 0.3))


def noisy(y, seed=0):
    return y + SIGMA * np.random.default_rng(seed).normal(size=y.shape)


def test_a_profile_in_the_model_frame_passes():
    assert frame_check(THETA, noisy(groove(THETA)), SIGMA, groove(THETA)) is None


def test_a_mirrored_profile_is_found_with_its_declaration():
    # recorded clockwise from the model's zero: the file's theta is -theta_model
    y = noisy(groove(-THETA))
    found = frame_check(THETA, y, SIGMA, groove(THETA))
    assert found is not None and found["sense"] == "clockwise" and found["zero_deg"] == 0.0
    assert found["chi2"] < 2 * THETA.size < found["chi2_as_given"]


def test_a_rotated_profile_is_found_with_its_zero():
    # the file's zero lies at 40 deg of the model frame: theta_file = theta_model - 40 deg
    y = noisy(groove(THETA + math.radians(40.0)))
    found = frame_check(THETA, y, SIGMA, groove(THETA))
    assert found is not None and found["sense"] == "counter-clockwise"
    assert found["zero_deg"] == 40.0


def test_a_symmetric_groove_mirrored_is_named_as_the_simpler_rotation():
    """Mirror and rotation fit a symmetric groove equally: the rotation is named."""
    def sym(theta):
        d = np.angle(np.exp(1j * (theta - math.radians(170.0))))
        return 60e-6 * np.exp(-(d / 0.5) ** 2)

    found = frame_check(THETA, noisy(sym(-THETA)), SIGMA, sym(THETA))
    assert found is not None and found["sense"] == "counter-clockwise"
    assert found["zero_deg"] == 340.0  # the groove at 190 deg read as one at 170 deg



def test_the_calibration_report_names_the_declaration():
    """`frame_warnings` on a calibration whose one profile was recorded clockwise."""
    from types import SimpleNamespace

    from diffwear.calibrate.dataset import Series
    from diffwear.calibrate.frame_check import frame_warnings

    profile = Series("bore", "profile", "bore.csv", 1000, THETA, noisy(groove(-THETA)), SIGMA)
    mass = Series("mass", "volume", "mass.csv", None, [1000.0, 2000.0], [1e-9, 2e-9], 1e-10,
                  basis="mass")
    which = np.concatenate([np.zeros(THETA.size, int), np.ones(2, int)])
    base = SimpleNamespace(prediction=np.concatenate([groove(THETA), [1e-9, 2e-9]]))
    c = SimpleNamespace(dataset=SimpleNamespace(series=(profile, mass)),
                        problem=SimpleNamespace(series_of_point=which),
                        base=base, final=None, chosen=base)
    base.residual = (base.prediction - np.concatenate([profile.y, mass.y])) / SIGMA
    (w,) = frame_warnings(c)
    assert w["series"] == "bore" and 'bushing_angle_sense = "clockwise"' in w["message"]
    assert "as given as well" not in w["message"]
    # a chosen model that fits the profile as given (a lobed k can mimic a
    # mirror) leaves both readings open, and the warning says so
    c.final = SimpleNamespace(residual=np.full(which.size, 0.5))
    (w,) = frame_warnings(c)
    assert f"fits it as given as well (chi2 {0.25 * THETA.size:.0f})" in w["message"]
