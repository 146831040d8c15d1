"""The oil as users name it: an ISO viscosity grade at a running temperature.

ISO 3448 names an industrial oil by its kinematic viscosity at 40 degC (the
grade's midpoint, +-10 %).  The viscosity at another temperature follows the
Walther relation of ASTM D341 (Standard Practice for Viscosity-Temperature
Charts for Liquid Petroleum Products):

    log10 log10 (nu + 0.7) = A - B log10 T,      nu in mm^2/s, T in K,

a straight line through the grade's 40 degC and 100 degC viscosities.  The
plain form (the constant 0.7 alone) holds down to nu = 2 mm^2/s (below it
D341 adds correction terms); it is used between -20 degC (near the pour
point of the mineral oils of these grades) and the lower of 150 degC (a
mineral oil's upper service temperature, where it oxidises) and the
temperature where nu falls to 2 mm^2/s.

**The 100 degC viscosity.**  A grade fixes only the 40 degC value; the slope
depends on the oil's viscosity index (VI, ASTM D2270).  The table takes
paraffinic mineral oils of VI ~ 95-100, the usual industrial oils, with the
typical 100 degC viscosities of suppliers' ISO VG reference tables (e.g.
VG 10: 2.5 mm^2/s, VG 68: 8.5 mm^2/s, VG 1500: 74 mm^2/s; the last pair
gives VI 105 by ASTM D2270's formulas for nu_100 > 70 mm^2/s, L = 0.8353 Y^2 +
14.67 Y - 216, H = 0.1684 Y^2 + 11.85 Y - 97).  An oil of another VI (a
synthetic, a multigrade) should be given by its ``viscosity`` at the running
temperature instead.

**Density** (kinematic to dynamic viscosity, mu = rho nu): 870 kg/m^3 at
15 degC, the middle of the 850-890 kg/m^3 of paraffinic mineral oils of
these grades, with the thermal expansion 6.5e-4 /K of lubricating oils
(ASTM D1250 / API MPMS 11.1 tables at that density): rho(T) = rho_15 (1 -
6.5e-4 (T - 15 degC)).

Example: ISO VG 10 at 25 degC: nu = 17.4 mm^2/s, rho = 864 kg/m^3, mu = 15.0
mPa s (against 8.5 mPa s at 40 degC).
"""

from __future__ import annotations

import math
import re

from ..errors import InputError

__all__ = ["ISO_GRADES", "OilGrade", "grade", "parse_temperature"]

# ISO 3448 midpoints at 40 degC [mm^2/s] and the typical 100 degC viscosities of
# VI ~ 95-100 paraffinic mineral oils of each grade [mm^2/s] (module notes).
# Grades below VG 10 are not listed: their 100 degC viscosity is below the
# 2 mm^2/s where the plain Walther relation holds.
ISO_GRADES: dict[int, tuple[float, float]] = {
    10: (10.0, 2.5), 15: (15.0, 3.5), 22: (22.0, 4.5), 32: (32.0, 5.5),
    46: (46.0, 6.5), 68: (68.0, 8.5), 100: (100.0, 11.4), 150: (150.0, 14.5),
    220: (220.0, 19.0), 320: (320.0, 24.5), 460: (460.0, 32.0), 680: (680.0, 42.0),
    1000: (1000.0, 55.0), 1500: (1500.0, 74.0),
}
# Walther's constant of ASTM D341 [mm^2/s] and the least viscosity its plain form
# holds for [mm^2/s].
WALTHER_SHIFT, WALTHER_MIN_VISCOSITY = 0.7, 2.0
# Service range [K]: -20 degC (pour point of these mineral oils) to 150 degC
# (oxidation limit), further cut where nu falls to 2 mm^2/s.
LOWEST_TEMPERATURE, HIGHEST_TEMPERATURE = 253.15, 423.15
# Density at 15 degC [kg/m^3] and thermal expansion [1/K] (module notes).
DENSITY_15C, THERMAL_EXPANSION = 870.0, 6.5e-4
ZERO_CELSIUS = 273.15  # K


def _loglog(nu):
    return math.log10(math.log10(nu + WALTHER_SHIFT))


class OilGrade:
    """An ISO VG mineral oil: its Walther line through (40 degC, nu_40) and
    (100 degC, nu_100) and its density."""

    def __init__(self, number: int):
        self.number = number
        nu40, nu100 = ISO_GRADES[number]
        t40, t100 = math.log10(ZERO_CELSIUS + 40.0), math.log10(ZERO_CELSIUS + 100.0)
        self.slope = (_loglog(nu40) - _loglog(nu100)) / (t100 - t40)  # B
        self.intercept = _loglog(nu40) + self.slope * t40  # A
        # temperature where nu = 2 mm^2/s, the end of the plain relation
        t_min_nu = 10.0 ** ((self.intercept - _loglog(WALTHER_MIN_VISCOSITY)) / self.slope)
        self.temperature_range = (LOWEST_TEMPERATURE, min(HIGHEST_TEMPERATURE, t_min_nu))

    @property
    def name(self) -> str:
        return f"ISO VG {self.number}"

    def kinematic_viscosity(self, temperature: float) -> float:
        """nu [m^2/s] at ``temperature`` [K] (ASTM D341)."""
        loglog = self.intercept - self.slope * math.log10(temperature)
        return (10.0 ** (10.0 ** loglog) - WALTHER_SHIFT) * 1e-6

    @staticmethod
    def density(temperature: float) -> float:
        """rho [kg/m^3] at ``temperature`` [K]."""
        return DENSITY_15C * (1.0 - THERMAL_EXPANSION * (temperature - ZERO_CELSIUS - 15.0))

    def viscosity(self, temperature: float, key: str = "temperature") -> float:
        """Dynamic viscosity mu = rho nu [Pa s] at ``temperature`` [K];
        `InputError` naming ``key`` outside the relation's range."""
        low, high = self.temperature_range
        if not low <= temperature <= high:
            raise InputError(
                f"{key}: {temperature - ZERO_CELSIUS:g} degC is outside the range where the "
                f"viscosity of {self.name} follows ASTM D341 (Walther); allowed: "
                f"{low - ZERO_CELSIUS:g} degC to {high - ZERO_CELSIUS:.4g} degC")
        return self.density(temperature) * self.kinematic_viscosity(temperature)


_GRADE = re.compile(r"\s*(?:ISO\s*)?(?:VG\s*)?(\d+)\s*", re.IGNORECASE)


def grade(text: str, key: str = "grade") -> OilGrade:
    """The `OilGrade` named ``text`` ("ISO VG 10", "VG 68"); `InputError`
    naming ``key`` for an unknown grade."""
    allowed = ", ".join(f"ISO VG {g}" for g in ISO_GRADES)
    match = _GRADE.fullmatch(text) if isinstance(text, str) else None
    if match is None or int(match.group(1)) not in ISO_GRADES:
        raise InputError(f"{key}: {text!r} is not an ISO 3448 grade this viscosity table "
                         f"covers; allowed: {allowed}")
    return OilGrade(int(match.group(1)))


_TEMPERATURE = re.compile(r"\s*([+-]?\d+\.?\d*(?:[eE][+-]?\d+)?)\s*(degC|°C|C|K|degF|°F)\s*")


def parse_temperature(text: str, key: str = "temperature") -> float:
    """``"25 degC"``, ``"298.15 K"``, ``"77 degF"`` -> K; `InputError` naming
    ``key`` otherwise."""
    match = _TEMPERATURE.fullmatch(text) if isinstance(text, str) else None
    if match is None:
        raise InputError(f"{key}: {text!r} is not a temperature; allowed: a number and "
                         "degC, K or degF, e.g. \"25 degC\"")
    value, unit = float(match.group(1)), match.group(2)
    if unit in ("degC", "°C", "C"):
        kelvin = value + ZERO_CELSIUS
    elif unit in ("degF", "°F"):
        kelvin = (value - 32.0) * 5.0 / 9.0 + ZERO_CELSIUS
    else:
        kelvin = value
    if not kelvin > 0.0:
        raise InputError(f"{key}: {text!r} is below absolute zero; allowed: > 0 K")
    return kelvin
