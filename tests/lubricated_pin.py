"""The lubricated test pin shared by the lubricated-joint tests: a
connecting-rod-like pin (as tests/test_lubrication.py) in a PTFE-like
bushing.

Imported by the tests (pytest puts ``tests/`` on ``sys.path``); not collected.
"""

from __future__ import annotations

from diffwear.contact import (
    ArchardWear,
    ClearanceJoint,
    CoulombFriction,
    ElasticFoundation,
    MixedLubrication,
    ShortBearingFilm,
)

# R = 10 mm, L = 8 mm, c = 50 um, mu = 0.04 Pa s; a PTFE-like foundation
# (k_f = E_W / wall ~ 1e13 Pa/m for a 0.5 GPa layer 50 um thick: stiff enough
# to matter).
MU, R, L, C = 0.04, 0.010, 0.008, 50e-6
KF = 1e13


def pin_joint(mu=MU, sigma=0.1e-6, n=180, friction=0.1) -> ClearanceJoint:
    """The pin in its bushing on the short film of ``mu`` [Pa s], combined
    roughness ``sigma`` [m], ``n`` grid nodes, Coulomb ``friction``."""
    law = MixedLubrication(ShortBearingFilm(mu, L, C), ElasticFoundation(KF, L), sigma)
    return ClearanceJoint("j", "a", [0.0, 0.0], "b", [0.0, 0.0], R, R + C, law,
                          friction=CoulombFriction(friction), wear=ArchardWear(1e-14),
                          n_theta=n)
