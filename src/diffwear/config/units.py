"""Quantities with explicit units: ``"20 mm"``, ``"30 rpm"``, ``"45 kg m^2"``.

Every dimensioned value in a mechanism file carries its unit; nothing is
guessed.  `parse_quantity` turns a string into the SI value of one dimension;
`to_si` converts a plain number whose unit is named by its key (``mass_kg =
10``).  Both raise `InputError` with a message of the form ``"what is wrong;
allowed: ..."`` that the loader prefixes with the file and key path.

Conversion is exact where it can be: the number is read as a decimal fraction,
multiplied by the unit's rational scale and rounded once to a float
(``"1750 mm"`` gives exactly the float 1.75); units involving pi (deg, rpm,
rev) are then multiplied by ``math.pi`` once, so ``"30 rpm"`` is exactly
``math.pi`` and ``"90 deg"`` exactly ``math.pi / 2``.

Unit factors are the SI definitions (BIPM SI Brochure, 9th ed., 2019): prefixes
(Table 7), minute/hour/degree (Table 8), 1 rev = 2 pi rad, 1 rpm = 1 rev/min.
"""

from __future__ import annotations

import difflib
import math
import re
from fractions import Fraction
from typing import NamedTuple

from ..errors import InputError


class Unit(NamedTuple):
    """SI value of one unit = ``float(scale) * pi**pi_power``."""

    scale: Fraction
    pi_power: int = 0


class Dimension(NamedTuple):
    si: str                 # spelling of the SI unit (the key of scale 1)
    units: dict[str, Unit]  # allowed spellings -> factor
    example: str            # shown in error messages


_F = Fraction
DIMENSIONS: dict[str, Dimension] = {
    "length": Dimension("m", {
        "m": Unit(_F(1)), "cm": Unit(_F(1, 100)), "mm": Unit(_F(1, 1000)),
        "um": Unit(_F(1, 10**6)),
    }, "20 mm"),
    "angle": Dimension("rad", {
        "rad": Unit(_F(1)), "deg": Unit(_F(1, 180), 1), "rev": Unit(_F(2), 1),
    }, "90 deg"),
    "angular speed": Dimension("rad/s", {
        "rad/s": Unit(_F(1)), "deg/s": Unit(_F(1, 180), 1), "rev/s": Unit(_F(2), 1),
        "rpm": Unit(_F(1, 30), 1),
    }, "30 rpm"),
    "mass": Dimension("kg", {
        "kg": Unit(_F(1)), "g": Unit(_F(1, 1000)), "mg": Unit(_F(1, 10**6)),
    }, "10 kg"),
    "inertia": Dimension("kg m^2", {
        "kg m^2": Unit(_F(1)), "kg cm^2": Unit(_F(1, 10**4)), "kg mm^2": Unit(_F(1, 10**6)),
        "g cm^2": Unit(_F(1, 10**7)), "g mm^2": Unit(_F(1, 10**9)),
    }, "45 kg m^2"),
    "time": Dimension("s", {
        "s": Unit(_F(1)), "ms": Unit(_F(1, 1000)), "us": Unit(_F(1, 10**6)),
        "min": Unit(_F(60)), "h": Unit(_F(3600)),
    }, "2 s"),
    "rate": Dimension("1/s", {"1/s": Unit(_F(1))}, "250 1/s"),
    "velocity": Dimension("m/s", {"m/s": Unit(_F(1)), "mm/s": Unit(_F(1, 1000))}, "0.5 m/s"),
    "acceleration": Dimension("m/s^2", {
        "m/s^2": Unit(_F(1)), "mm/s^2": Unit(_F(1, 1000)),
    }, "-9.80665 m/s^2"),
    "force": Dimension("N", {"N": Unit(_F(1)), "kN": Unit(_F(1000))}, "150 N"),
    "torque": Dimension("N m", {
        "N m": Unit(_F(1)), "N mm": Unit(_F(1, 1000)), "kN m": Unit(_F(1000)),
    }, "12 N m"),
    "stiffness": Dimension("N/m", {
        "N/m": Unit(_F(1)), "N/mm": Unit(_F(1000)), "kN/m": Unit(_F(1000)),
        "kN/mm": Unit(_F(10**6)),
    }, "525.4 N/m"),
    "damping": Dimension("N s/m", {"N s/m": Unit(_F(1)), "N s/mm": Unit(_F(1000))}, "20 N s/m"),
    "pressure": Dimension("Pa", {
        "Pa": Unit(_F(1)), "kPa": Unit(_F(1000)), "MPa": Unit(_F(10**6)),
        "GPa": Unit(_F(10**9)),
    }, "207 GPa"),
    # worn volume (calibration data); mass / density gives it from a weighing
    "volume": Dimension("m^3", {
        "m^3": Unit(_F(1)), "cm^3": Unit(_F(1, 10**6)), "mm^3": Unit(_F(1, 10**9)),
    }, "116 mm^3"),
    "density": Dimension("kg/m^3", {
        "kg/m^3": Unit(_F(1)), "g/cm^3": Unit(_F(1000)), "kg/dm^3": Unit(_F(1000)),
    }, "2.25 g/cm^3"),
    # dynamic viscosity of a lubricant; 1 cP (centipoise) = 1 mPa s, 1 P (poise) =
    # 0.1 Pa s (CGS unit, 1 g/(cm s))
    "viscosity": Dimension("Pa s", {
        "Pa s": Unit(_F(1)), "mPa s": Unit(_F(1, 1000)), "cP": Unit(_F(1, 1000)),
        "P": Unit(_F(1, 10)),
    }, "0.05 Pa s"),
    # areal density of asperity summits (Greenwood-Tripp eta)
    "areal density": Dimension("1/m^2", {
        "1/m^2": Unit(_F(1)), "1/mm^2": Unit(_F(10**6)), "1/um^2": Unit(_F(10**12)),
    }, "1e10 1/m^2"),
    # Hertz contact stiffness K of F = K delta^1.5 (Lankarani-Nikravesh law)
    "contact stiffness": Dimension("N/m^1.5", {"N/m^1.5": Unit(_F(1))}, "7e10 N/m^1.5"),
    # Archard k: worn volume per (normal load x sliding distance); 1/Pa = m^3/(N m)
    "wear coefficient": Dimension("1/Pa", {
        "1/Pa": Unit(_F(1)), "m^3/(N m)": Unit(_F(1)), "mm^3/(N m)": Unit(_F(1, 10**9)),
    }, "5.05e-4 mm^3/(N m)"),
}
"""Allowed units per dimension.  Other modules may add dimensions or units
(e.g. a wear coefficient in m^2/N) before loading a file."""

_NUMBER = r"[+-]?(?:infinity|inf|nan|\d+\.?\d*(?:[eE][+-]?\d+)?|\.\d+(?:[eE][+-]?\d+)?)"
_QUANTITY = re.compile(rf"\s*(?P<num>{_NUMBER})\s*(?P<unit>.*?)\s*",
                       re.IGNORECASE | re.DOTALL | re.ASCII)
_MAX_EXPONENT = 400  # |exponent| beyond float64's range: no exact (and huge) Fraction


def allowed_units(dimension: str) -> str:
    return ", ".join(DIMENSIONS[dimension].units)


def key_suffix(unit: str) -> str:
    """Key suffix naming ``unit`` for a plain number: ``mass_kg``, ``inertia_kg_m2``,
    ``omega_rad_per_s``, ``stiffness_N_per_m``, ``baumgarte_alpha_per_s``,
    ``coefficient_mm3_per_N_m``, ``stiffness_N_per_m1_5``."""
    s = unit.replace("^", "").replace("(", "").replace(")", "").replace(".", "_")
    s = s.replace(" ", "_")
    if s.startswith("1/"):
        s = "per_" + s[2:]
    return s.replace("/", "_per_")


def normalise_unit(unit: str) -> str:
    """Spelling variants accepted for the same unit: ``kg*m^2``, ``kg·m²``, ``µm``."""
    u = unit.replace("*", " ").replace("·", " ").replace("⋅", " ").replace("²", "^2")
    u = u.replace("µ", "u").replace("μ", "u")
    return " ".join(u.split())


def _dimension_of(unit: str) -> str | None:
    for name, dim in DIMENSIONS.items():
        if unit in dim.units:
            return name
    return None


def _unit(unit: str, dimension: str) -> Unit:
    dim = DIMENSIONS[dimension]
    u = normalise_unit(unit)
    if u in dim.units:
        return dim.units[u]
    other = _dimension_of(u)
    if other is not None:
        article = "an" if other[0] in "aeiou" else "a"
        what = f"unit {unit!r} is {article} {other} unit, not {dimension}"
    else:
        what = f"unknown unit {unit!r} for {dimension}"
        close = difflib.get_close_matches(u, list(dim.units), n=1, cutoff=0.5)
        if not close:
            close = [k for k in dim.units if k.lower() == u.lower()]
        if close:
            what += f" (did you mean {close[0]!r}?)"
    raise InputError(f"{what}; allowed: {allowed_units(dimension)}")


def _exact(number: str, unit: Unit) -> float:
    """float(number * scale) rounded once, then times pi**pi_power."""
    mantissa, _, exponent = number.lower().partition("e")
    if exponent and abs(int(exponent)) > _MAX_EXPONENT:
        value = float(number) * float(unit.scale)
    else:
        try:
            value = float(Fraction(number) * unit.scale)
        except OverflowError:
            value = math.inf
    return value * math.pi**unit.pi_power


def unit_of(text: str, dimension: str) -> str | None:
    """The allowed spelling of the unit in quantity ``text`` ("5e-4 mm^3/(N m)"
    -> "mm^3/(N m)"), None when it has none or names no unit of ``dimension``."""
    m = _QUANTITY.fullmatch(text)
    if m is None:
        return None
    u = normalise_unit(m.group("unit"))
    return u if u in DIMENSIONS[dimension].units else None


def in_unit(value: float, unit: str, dimension: str) -> float:
    """SI ``value`` expressed in ``unit`` of ``dimension``."""
    scale = DIMENSIONS[dimension].units[unit]
    return value / (float(scale.scale) * math.pi ** scale.pi_power)


def parse_quantity(text: str, dimension: str) -> float:
    """SI value of ``"<number> <unit>"`` in ``dimension`` (see `DIMENSIONS`)."""
    dim = DIMENSIONS[dimension]
    allowed = (f"a number and a {dimension} unit, e.g. {dim.example!r}; "
               f"units: {allowed_units(dimension)}")
    if not isinstance(text, str):
        raise InputError(f"expected a string such as {dim.example!r}, got {text!r}; "
                         f"allowed: {allowed}")
    m = _QUANTITY.fullmatch(text)
    if m is None:
        raise InputError(f"{text!r} does not start with a number; allowed: {allowed}")
    number, unit = m["num"], m["unit"]
    if not unit:
        raise InputError(
            f"{text!r} has no unit (a bare number is never given a unit silently); "
            f"allowed: {allowed}"
        )
    u = _unit(unit, dimension)
    if number.lower().lstrip("+-") in {"inf", "infinity", "nan"}:
        raise InputError(f"{text!r} is not finite; allowed: a finite number with a unit")
    value = _exact(number, u)
    if not math.isfinite(value):
        raise InputError(f"{text!r} is out of the float64 range in SI units; allowed: "
                         f"|value| < 1.8e308 {dim.si}")
    return value


def to_si(value, unit: str, dimension: str) -> float:
    """SI value of a plain number ``value`` given in ``unit`` (named by its key)."""
    u = _unit(unit, dimension)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"expected a plain number (the key names the unit {unit!r}), got "
                         f"{value!r}; allowed: an integer or float")
    if not math.isfinite(value):
        raise InputError(f"{value!r} is not finite; allowed: a finite number")
    si = _exact(repr(value) if isinstance(value, float) else str(value), u)
    if not math.isfinite(si):
        raise InputError(f"{value!r} {unit} is out of the float64 range in SI units; allowed: "
                         f"|value| < 1.8e308 {DIMENSIONS[dimension].si}")
    return si
