"""``[[joints]] type = "clearance"``: a revolute joint with radial clearance.

In the file it is a joint (same place, same points as an ideal revolute); in
the `Mechanism` it is a force element, a `ClearanceJoint` (the pin floats in
the bushing).  For the assembly at t = 0 it is replaced by the ideal
`RevoluteJoint` at the same points (pin centred, ideal velocities).

Only conversion and validation live here; the physics comes from the existing
builders: `LankaraniNikravesh.from_materials`, `KelvinVoigt.matched_to`,
`presets.efm_law`, `ClearanceJoint`.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..contact import (
    PTFE,
    STEEL,
    ClearanceJoint,
    CoulombFriction,
    FiniteBearingFilm,
    KelvinVoigt,
    LankaraniNikravesh,
    LongBearingFilm,
    Material,
    MixedLubrication,
    ShortBearingFilm,
    oils,
)
from ..contact.asperities import (
    DEFAULT_SLOPE_RATIO,
    DEFAULT_SUMMIT_PRODUCT,
    SLOPE_RATIO_RANGE,
    SUMMIT_PRODUCT_RANGE,
    GreenwoodTripp,
)
from ..contact.finite_bearing import (
    CAVITATION,
    MASS_CONSERVING,
    N_THETA,
    N_Z,
    REYNOLDS,
    film_law_for,
    nodes_for,
)
from ..contact.finite_table import SHIPPED_RATIOS, ShippedFiniteFilm
from ..contact.friction import DEFAULT_SLIP_WIDTH
from ..contact.mixed import ONSET_FILM_RATIO
from ..errors import InputError
from ..mechanism import RevoluteJoint
from ..wear import ArchardWear
from .elements import NAME, ElementType, FieldError
from .schema import (
    BodyRef,
    Field,
    Integer,
    Number,
    Quantity,
    Table,
    Tagged,
    Text,
    Vector,
    check_table,
    read_table,
    show,
    suggest,
    toml_type,
)

MATERIALS = {"steel": STEEL, "ptfe": PTFE}
"""Named materials (thesis Table 3-2): steel E = 206.8 GPa, nu = 0.29; PTFE 0.5 GPa, 0.38."""

MATERIAL_FIELDS = {
    "youngs_modulus": Quantity(dimension="pressure", low=0.0, low_open=True),
    "poisson_ratio": Number(low=-1.0, high=0.5, low_open=True, high_open=True),
}
MATERIAL_CHOICES = (" | ".join(repr(m) for m in MATERIALS)
                    + " | { youngs_modulus = \"206.8 GPa\", poisson_ratio = 0.29 }")


@dataclass(frozen=True)
class MaterialField(Field):
    """A named material (`MATERIALS`) or ``{ youngs_modulus, poisson_ratio }``."""

    def expects(self, key):
        return MATERIAL_CHOICES

    def read(self, ctx, path, key, spelling, raw):
        if isinstance(raw, str):
            if raw not in MATERIALS:
                raise ctx.error(path, f"unknown material {raw!r}{suggest(raw, list(MATERIALS))}",
                                MATERIAL_CHOICES)
            return MATERIALS[raw]
        if not isinstance(raw, dict):
            raise ctx.error(path, f"expected a material name or a table, got {toml_type(raw)} "
                            f"{show(raw)}", MATERIAL_CHOICES)
        v = read_table(ctx, path, check_table(ctx, path, raw, MATERIAL_CHOICES), MATERIAL_FIELDS)
        return Material(v["youngs_modulus"], v["poisson_ratio"], name=path)


RESTITUTION = Number(default=0.8, low=0.0, high=1.0, low_open=True,
                     doc="coefficient of restitution e_r (default 0.8, thesis Table 3-3)")
LN, KV, EFM = "lankarani-nikravesh", "kelvin-voigt", "elastic-foundation"
LAWS = {
    LN: {
        "restitution": RESTITUTION,
        "stiffness": Quantity(dimension="contact stiffness", default=None, low=0.0,
                              low_open=True, doc="default: Hertz, from the materials"),
    },
    KV: {
        "restitution": RESTITUTION,
        "stiffness": Quantity(dimension="stiffness", default=None, low=0.0, low_open=True),
        "matched_to_load": Quantity(dimension="force", default=None, low=0.0, low_open=True,
                                    doc="secant stiffness of the Hertz law at this load"),
    },
    EFM: {
        "layer_thickness": Quantity(dimension="length", low=0.0, low_open=True,
                                    doc="bushing wall: outer minus inner radius"),
        "depth": Quantity(dimension="length", low=0.0, low_open=True, doc="axial length"),
        "restitution": RESTITUTION,
        "damping_mass": Quantity(dimension="mass", default=None, low=0.0, low_open=True,
                                 doc="default: the bushing body's mass"),
    },
}

BEARINGS = {"short": ShortBearingFilm, "long": LongBearingFilm, "finite": FiniteBearingFilm}
"""Film models of ``lubricant.bearing``, by name: the short (Ocvirk) bearing
(`ShortBearingFilm`), the long (Sommerfeld) one (`LongBearingFilm`) and the
finite-length Reynolds film (`FiniteBearingFilm`, on the default grid read
from its shipped moving-journal tables, `ShippedFiniteFilm`).  By default the
one `film_law_for` finds for the joint (short where it holds, else finite); a
run warns where an explicit short film is out of its range."""
MAX_VISCOSITY = 10.0
"""Pa s: the most viscous lubricant a joint takes (honey is ~10 Pa s; above
that the fluid does not flow into the clearance as a lubricating film)."""
LUBRICANT = Table(fields={
    "viscosity": Quantity(dimension="viscosity", default=None, low=0.0, high=MAX_VISCOSITY,
                          low_open=True, doc="dynamic viscosity at the running temperature "
                          "(or grade and temperature)"),
    "grade": Text(default=None, doc="ISO 3448 viscosity grade, e.g. \"ISO VG 10\" (a VI ~ 100 "
                  "mineral oil; its viscosity at temperature by ASTM D341)"),
    "temperature": Text(default=None, doc="running temperature of the oil of grade, e.g. "
                        "\"25 degC\""),
    # its range, > 0 and < clearance / 3, is checked with the clearance (`_lubricated`)
    "roughness": Quantity(dimension="length",
                          doc="combined RMS roughness sigma of pin and bushing; > 0 and below "
                              "clearance / 3"),
    "summit_density": Quantity(dimension="areal density", default=None, low=0.0,
                               low_open=True,
                               doc="areal density eta of the asperity summits (Greenwood-"
                                   "Tripp); default: eta beta sigma = 0.04"),
    "summit_radius": Quantity(dimension="length", default=None, low=0.0, low_open=True,
                              doc="radius beta of the asperity summits; default: sigma / "
                                  "beta = 1e-3"),
    "bearing": Text(default=None, choices=tuple(BEARINGS),
                    doc="film model; default: the one that holds for the joint "
                        "(film_law_for): short where (L/D)^2 <= 0.05 (1 - eps_max), "
                        "eps_max = 1 - sigma / c, else finite (the shipped moving-journal "
                        "tables, L/D 0.05 to 4); a run warns where an explicit short film "
                        "is out of its range"),
    "film_n_theta": Integer(default=None, low=16, high=4096,
                            doc="bearing = \"finite\" only: grid nodes round the bushing "
                                "(even; default 96); they must resolve the minimum film at "
                                "eps_max = 1 - sigma / c"),
    "film_n_z": Integer(default=None, low=2, high=1024,
                        doc="bearing = \"finite\" only: grid nodes along the half length "
                            "(default 12)"),
    "cavitation": Text(default=None, choices=CAVITATION,
                       doc="bearing = \"finite\" only: the cavitation condition, "
                           "\"reynolds\" (Swift-Stieber, default) or \"mass-conserving\" "
                           "(Jakobsson-Floberg-Olsson: the film reforms only with the oil its "
                           "cavitated region carries)"),
    "length": Quantity(dimension="length", default=None, low=0.0, low_open=True,
                       doc="axial length of the film; default: law.depth"),
}, default=None)

FIELDS = {
    "name": NAME,
    "pin_body": BodyRef(), "pin_point": Vector(dimension="length"),
    "bushing_body": BodyRef(), "bushing_point": Vector(dimension="length"),
    "pin_radius": Quantity(dimension="length", low=0.0, low_open=True),
    "bushing_radius": Quantity(dimension="length", default=None, low=0.0, low_open=True),
    "clearance": Quantity(dimension="length", default=None, low=0.0,
                          doc="radial: bushing radius minus pin radius"),
    "law": Tagged(types=LAWS, what="law type"),
    "pin_material": MaterialField(default=None),
    "bushing_material": MaterialField(default=None),
    "friction": Table(fields={
        "coefficient": Number(low=0.0),
        "slip_width": Quantity(dimension="velocity", default=DEFAULT_SLIP_WIDTH, low=0.0,
                               low_open=True),
    }, default={"coefficient": 0.13, "slip_width": DEFAULT_SLIP_WIDTH}),
    "n_theta": Integer(default=360, low=8, high=100_000),
    "wear": Table(fields={"coefficient": Quantity(dimension="wear coefficient", low=0.0)},
                  default=None),
    "lubricant": LUBRICANT,
}


def _materials(v, *keys, why):
    for key in keys:
        if v[key] is None:
            raise FieldError(key, f"missing key: {why}", MATERIAL_CHOICES)
    return [v[key] for key in keys]


def _radii(v):
    rp = v["pin_radius"]
    rb, c = v["bushing_radius"], v["clearance"]
    both = "exactly one of bushing_radius and clearance"
    if rb is not None and c is not None:
        raise FieldError("clearance", "given together with bushing_radius", both)
    if rb is None and c is None:
        raise FieldError("bushing_radius", "missing key (or give clearance instead)", both)
    if rb is None:
        return rp, rp + c
    if rp > rb:
        raise FieldError("bushing_radius",
                         f"{rb:g} m is smaller than the pin radius {rp:g} m (negative clearance "
                         f"{rb - rp:g} m)", f">= pin_radius = {rp:g} m")
    return rp, rb


def _law(v, rp, rb, bodies):
    from ..presets import efm_law  # presets imports the mechanism package only lazily

    law = v["law"]
    kind = law["type"]
    why = f"the {kind} law computes its stiffness from the pin and bushing materials"
    if kind == LN:
        if law["stiffness"] is not None:
            return LankaraniNikravesh(law["stiffness"], law["restitution"])
        pin, bushing = _materials(v, "pin_material", "bushing_material",
                                  why=why + " (or give law.stiffness in N/m^1.5)")
        return LankaraniNikravesh.from_materials(pin, bushing, rp, rb, law["restitution"])
    if kind == KV:
        k, load = law["stiffness"], law["matched_to_load"]
        one = "exactly one of law.stiffness and law.matched_to_load"
        if k is None and load is None:
            raise FieldError("law.stiffness", "missing key (or give law.matched_to_load)", one)
        if k is not None and load is not None:
            raise FieldError("law.matched_to_load", "given together with law.stiffness", one)
        if k is not None:
            return KelvinVoigt(k, law["restitution"])
        pin, bushing = _materials(v, "pin_material", "bushing_material", why=why)
        ln = LankaraniNikravesh.from_materials(pin, bushing, rp, rb, law["restitution"])
        return KelvinVoigt.matched_to(ln, load)
    (bushing,) = _materials(v, "bushing_material", why=f"the {kind} law needs the bushing "
                            "material (its constrained modulus)")
    mass = law["damping_mass"]
    if mass is None:
        body = v["bushing_body"]
        if body not in bodies:
            raise FieldError("law.damping_mass", f"missing key: the bushing body {body!r} has "
                             "no mass to default to", "a mass, e.g. \"15 kg\"")
        mass = bodies[body].mass
    return efm_law(bushing, rb, law["layer_thickness"], law["depth"], law["restitution"], mass)


def oil_viscosity(lube) -> float:
    """The oil's dynamic viscosity [Pa s]: ``lubricant.viscosity``, or that of
    ``lubricant.grade`` at ``lubricant.temperature`` (`diffwear.contact.oils`)."""
    given = [k for k in ("viscosity", "grade") if lube[k] is not None]
    one = "exactly one of lubricant.viscosity and lubricant.grade (with lubricant.temperature)"
    if len(given) != 1:
        key = "lubricant.grade" if given else "lubricant.viscosity"
        what = "given together with lubricant.viscosity" if given else "missing key"
        raise FieldError(key, what + " (the oil needs one viscosity)", one)
    if lube["viscosity"] is not None:
        if lube["temperature"] is not None:
            raise FieldError("lubricant.temperature", "given with lubricant.viscosity, which is "
                             "already the viscosity at the running temperature", one)
        return lube["viscosity"]
    if lube["temperature"] is None:
        raise FieldError("lubricant.temperature", f"missing key: the viscosity of "
                         f"{lube['grade']!r} depends on the oil's temperature",
                         "a temperature, e.g. \"25 degC\"")
    try:
        oil = oils.grade(lube["grade"], key="lubricant.grade")
        temperature = oils.parse_temperature(lube["temperature"], key="lubricant.temperature")
        return oil.viscosity(temperature, key="lubricant.temperature")
    except InputError as err:
        key, _, rest = str(err).partition(": ")
        what, _, allowed = rest.partition("; allowed: ")
        raise FieldError(key, what, allowed or None) from None


def _lubricated(lube, law, rp, rb, pin, bushing):
    """The `MixedLubrication` of ``lube`` (the file's ``lubricant`` table) on the
    elastic-foundation ``law``: the film of ``lubricant.bearing`` and the
    Greenwood-Tripp asperities of the ``pin`` and ``bushing`` materials on the
    foundation (`diffwear.contact.mixed`)."""
    c, sigma = rb - rp, lube["roughness"]
    allowed = f"> 0 and < clearance / {ONSET_FILM_RATIO:g} = {c / ONSET_FILM_RATIO * 1e6:g} um"
    if not sigma > 0.0:
        raise FieldError("lubricant.roughness", f"{sigma * 1e6:g} um is out of range: an RMS "
                         "roughness is positive", allowed)
    if ONSET_FILM_RATIO * sigma >= c:
        raise FieldError("lubricant.roughness",
                         f"{sigma * 1e6:g} um: a full film (the onset of mixed lubrication, "
                         f"{ONSET_FILM_RATIO:g} sigma = {ONSET_FILM_RATIO * sigma * 1e6:g} um) "
                         f"does not fit in the radial clearance {c * 1e6:g} um", allowed)
    length = law.depth if lube["length"] is None else lube["length"]
    return MixedLubrication(_film(lube, oil_viscosity(lube), length, c, sigma, rp), law,
                            _summits(lube, pin, bushing))


def _film(lube, viscosity, length, c, sigma, radius):
    """The film law of ``lubricant.bearing``, by default the one `film_law_for`
    finds for the joint's L/D and eps_max = 1 - sigma / c (short where the
    short film holds, else finite; finite where a grid or a cavitation
    condition is given).  The finite film: on the default grid with the
    Reynolds condition the shipped moving-journal tables (`ShippedFiniteFilm`,
    squeeze and wedge); on the grid of ``lubricant.film_n_theta`` /
    ``film_n_z``, or with ``lubricant.cavitation = "mass-conserving"``, the
    Reynolds solve itself, whose grid must resolve the minimum film where the
    joint's film saturates (`FiniteBearingFilm.check_resolution`)."""
    grid = {k: lube[f"film_{k}"] for k in ("n_theta", "n_z") if lube[f"film_{k}"] is not None}
    eps_max = float(MixedLubrication.saturation(sigma, c))
    ratio = float(length) / (2.0 * float(radius))
    bearing = lube["bearing"]
    if bearing is None:
        chosen = grid or lube["cavitation"] is not None
        bearing = "finite" if chosen else film_law_for(ratio, eps_max)
    if bearing != "finite":
        if grid:
            key = f"lubricant.film_{next(iter(grid))}"
            raise FieldError(key, f"given for bearing = {bearing!r}, which has no "
                             "grid", "bearing = \"finite\", or no grid key")
        if lube["cavitation"] is not None:
            raise FieldError("lubricant.cavitation",
                             f"{lube['cavitation']!r} given for bearing = "
                             f"{bearing!r}, whose film has a fixed cavitation "
                             "condition (Gumbel's, half-Sommerfeld)",
                             "bearing = \"finite\", or no cavitation key")
        return BEARINGS[bearing](viscosity, length, c)
    n_theta = grid.get("n_theta", N_THETA)
    if n_theta % 2:
        raise FieldError("lubricant.film_n_theta", f"{n_theta} is odd: the grid needs a node "
                         "on the maximum film", "an even integer in [16, 4096]")
    if n_theta < nodes_for(eps_max):
        raise FieldError("lubricant.film_n_theta",
                         f"{n_theta} nodes round the bushing are too coarse to resolve the "
                         f"minimum film where the film saturates, at eps_max = 1 - sigma / c "
                         f"= {eps_max:.4g}",
                         f"an even integer >= {nodes_for(eps_max)} (or a larger roughness)")
    # evaluated up to its saturation (`MixedLubrication.saturated_film`)
    cavitation = lube["cavitation"] or REYNOLDS
    film = FiniteBearingFilm(viscosity, length, c, max_eccentricity_ratio=eps_max,
                             n_theta=n_theta, n_z=grid.get("n_z", N_Z), cavitation=cavitation)
    if grid or cavitation == MASS_CONSERVING:  # the shipped tables: Reynolds, default grid
        return film
    low, high = SHIPPED_RATIOS[0], SHIPPED_RATIOS[-1]
    if not low <= ratio <= high:
        chosen = ("" if lube["bearing"] else
                  " (the default film: the short film is out of its range, (L/D)^2 > "
                  "0.05 (1 - eps_max))")
        raise FieldError("lubricant.length",
                         f"{length * 1e3:g} mm: the finite film's L/D = length / (2 pin "
                         f"radius) = {ratio:.4g} is outside its shipped tables{chosen}",
                         f"L/D in [{low:g}, {high:g}], or bearing = \"short\" | \"long\", "
                         f"or a finite film grid (film_n_theta) solved directly")
    return ShippedFiniteFilm(film, radius)


def _summits(lube, pin, bushing) -> GreenwoodTripp:
    """The `GreenwoodTripp` asperities of ``lube`` on the pin's and bushing's
    materials (the pin steel when not given); the summit parameters'
    defaults and ranges: `diffwear.contact.asperities`."""
    sigma, eta, beta = lube["roughness"], lube["summit_density"], lube["summit_radius"]
    beta_ = sigma / DEFAULT_SLOPE_RATIO if beta is None else beta
    eta_ = DEFAULT_SUMMIT_PRODUCT / (beta_ * sigma) if eta is None else eta
    low, high = SLOPE_RATIO_RANGE
    if not low <= sigma / beta_ <= high:
        raise FieldError("lubricant.summit_radius",
                         f"{beta_ * 1e6:g} um: roughness / summit radius sigma / beta = "
                         f"{sigma / beta_:.3g} with sigma = {sigma * 1e6:g} um",
                         f"sigma / beta in [{low:g}, {high:g}]: {sigma / high * 1e6:g} um to "
                         f"{sigma / low * 1e6:g} um")
    low, high = SUMMIT_PRODUCT_RANGE
    product = eta_ * beta_ * sigma
    if not low <= product <= high:
        # (only a given density can leave the range: the default's product is 0.04)
        raise FieldError("lubricant.summit_density",
                         f"{eta_:.4g} 1/m^2 with summit radius {beta_ * 1e6:g} um and "
                         f"roughness {sigma * 1e6:g} um: eta beta sigma = {product:.3g}",
                         f"eta beta sigma in [{low:g}, {high:g}] (measured surfaces: "
                         f"0.03-0.05): eta from {low / (beta_ * sigma):.3g} to "
                         f"{high / (beta_ * sigma):.3g} 1/m^2")
    return GreenwoodTripp.from_materials(STEEL if pin is None else pin, bushing, sigma, eta_,
                                         beta_)


def build(v, bodies) -> ClearanceJoint:
    rp, rb = _radii(v)
    if v["wear"] is not None and v["law"]["type"] != EFM:
        raise FieldError("wear", f"wear needs the pressure distribution of the {EFM!r} law, "
                         f"not the {v['law']['type']!r} point law",
                         f"law.type = {EFM!r}, or no wear key")
    if v["lubricant"] is not None and v["law"]["type"] != EFM:
        raise FieldError("lubricant", f"a lubricated joint's asperity contact is the {EFM!r} "
                         f"law, not the {v['law']['type']!r} law",
                         f"law.type = {EFM!r}, or no lubricant key")
    law = _law(v, rp, rb, bodies)
    if v["lubricant"] is not None:
        law = _lubricated(v["lubricant"], law, rp, rb, v["pin_material"],
                          v["bushing_material"])
    friction = CoulombFriction(v["friction"]["coefficient"], v["friction"]["slip_width"])
    wear = None if v["wear"] is None else ArchardWear(v["wear"]["coefficient"])
    return ClearanceJoint(v["name"], v["pin_body"], v["pin_point"], v["bushing_body"],
                          v["bushing_point"], rp, rb, law, friction=friction, wear=wear,
                          n_theta=v["n_theta"])


def ideal(joint: ClearanceJoint) -> RevoluteJoint:
    """The ideal revolute at the same points (assembly at t = 0: pin centred)."""
    return joint.ideal()


CLEARANCE = ElementType(
    fields=FIELDS, build=build, bodies=True, assembly=ideal,
    doc="revolute joint with radial clearance: the pin (pin_point of pin_body) floats in the "
        "bushing (bushing_point of bushing_body) under a contact law",
)
