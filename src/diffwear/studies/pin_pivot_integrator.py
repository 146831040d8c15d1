"""The pin-pivot study's own wear integrator: quasi-static wear of an
oscillating steel pin in a steel pivot (thesis Ch. 4).

Why it is not on the wear engine (`diffwear.wear._engine`).  The engine
integrates bushing profiles of a mechanism's clearance joints in the crank-cycle
count: a term gives the wear of one cycle at A = 1 and a solver multiplies it
by the extrapolation factor.  The thesis's Ch. 4 procedure, which this study
reproduces, is another integrator: each step of a sweep adds k A p ds to both
bodies *before* the next step's contact solve (Fig. 4-3, Eq. 4-18 applied per
step), so a computed sweep is not A x (the wear of one sweep); the sweeps
alternate in direction; the two worn bodies live in frames that turn against
each other; and the count of computed sweeps is rounded to whole test cycles.
Put on the engine's term/solver split, its numbers would change.  It has no
mechanism and no dynamics, and no other part of the package uses it: it is
the study's (`diffwear.studies.pin_pivot`).

The thesis's wear test (Tables 4-1..4-3): a steel pin in a steel pivot, dry,
oscillating +-30 deg under a constant load of 60 MPa projected pressure
(F = p D L), 408,000 test cycles; its FEM simulation wears both bodies with
Archard's law (Eq. 4-7: h += k p ds at every contact node and step), 10 steps
per simulated cycle, extrapolation factor A (Eq. 4-18).  No dynamics: the load
is constant and the motion prescribed.

Frames and signs.  All contact quantities live in the *load frame*, in which
the load F (force of the pin on the pivot) points along theta = 0 and one body
is at rest: the pivot (``load_frame="pivot"``: the load is fixed to the pivot,
the pin turns by phi(t)) or the pin (``load_frame="pin"``: the pivot turns by
-phi(t)); phi(t) is the pin's rotation relative to the pivot, +-amplitude.
Each wear profile h >= 0 [m] is stored on its own body's nodes psi_j = 2 pi j / n
(psi measured from the load direction at phi = 0).  The surfaces are the
pivot bore r = a + h_pivot(theta) and the pin r = R - h_pin(psi) about the pin
centre (a = R + c, c the radial clearance), so along the ray theta of the load
frame the undeformed gap is

    g0(theta) = a + h_rest(theta) + h_turn(theta - phi_turn) - ray_R(e, theta),

ray_R the distance to the round pin of radius R centred at e (exact ray form,
`diffwear.fem.contact`): both bodies' wear opens the gap.  The pin's wear is
read at the ray angle, not at the pin's own polar angle of that point: they
differ by |e| / R rad, and with the profile's slope the error is of order
|e| / R x h'(theta), small while the wear is small against R.

Elasticity.  Both bodies are plane-strain steel.  Under the frictionless
contact's equal and opposite nodal forces f_j (pin on pivot outward, pivot on
pin inward), the pivot's bore moves outward by C_pivot f (outer surface held,
`diffwear.fem.condense`) and the pin's surface inward by C_pin f (held bore,
`diffwear.fem.pin`); the gap closes by the sum, g = g0 + (C_pivot + C_pin) f,
which is the existing rigid-pin contact (`RingContact`) with the summed
compliance.  Both matrices are computed once on the *unworn* meshes: both
bodies are round, so their compliance is the same in every rotation and the
rotating body's compliance needs no rotation (exactly so for a rotation by an
even number of nodes, which maps the Q9 mesh onto itself; an odd number swaps
corner and mid-side nodes, whose compliances differ by the discretisation
error: the study's n_theta = 120 row, where the steps are 2 nodes, measures it).
Wear changes them only through the geometry (order h / wall); the study
measures the answer's sensitivity to the compliance (x 0.5, x 2).

Wear.  Step i of a sweep puts the turning body at its step angle, solves the
contact for F and adds, on each body's nodes, dh = k A p ds with
p = f / w (w the node's tributary length on that body's surface), ds = R |dphi|
(the pin's surface speed: R dphi; the pivot bore's is a dphi, 0.2 % more at
c / R = 2e-3) and A the extrapolation factor.  The rotating body's pressure is
mapped back onto its own nodes by the same periodic interpolation (exact when
the step is a whole number of nodes: 6 deg = 1 node at n = 60).  Worn volume
per unit depth: L sum_j h_j w_j on each body, equal for the two bodies (same k,
same f, same ds) and equal to k A sum_steps (L sum_j f_j) ds: the Archard
bookkeeping with the total normal load (thesis Eq. 4-1 with the pressure integrated), tested.

Cycles.  A *sweep* is one stroke between the extremes (the thesis's simulated
cycle, -30 -> 30); a *test cycle* is two sweeps (-30 -> 30 -> -30).  Sweeps
alternate in direction; the thesis's flow chart (Fig. 4-3) solves at the pin's
current angle and then rotates, so step i of a forward sweep is at
phi = -amplitude + i dphi, i = 0 .. steps - 1 (left end), and the backward sweep
mirrors it; a forward-backward pair visits each angle symmetrically.  One
computed sweep stands for A sweeps (Eq. 4-18, constant A; the thesis's adaptive
A settled near 6000): the number of computed sweeps is rounded to an even number
so that the run ends on a whole test cycle.

Everything is jit-compiled once (`wear_history`: a ``lax.scan`` over sweeps of
a ``lax.scan`` over steps); a failed contact solve sets a flag that
`run_wear` turns into `SolverError`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array, Bool, Float

from .._checks import check_int_option, check_range, require_float64
from ..errors import InputError, SolverError
from ..fem.condense import tributary_lengths
from ..fem.contact import TOL, RingContact
from ..fem.mesh import check_theta_nodes, ring_mesh
from ..fem.pin import pin_compliance, pin_mesh

MM3_PER_NM = 1e-9  # 1 mm^3/(N m) = 1e-9 1/Pa

# ---- the thesis's test and simulation (Tables 4-1, 4-2) ----
THESIS_PRESSURE = 60e6  # Pa, "load (cross-sectional pressure)", Tables 4-1 and 4-2
THESIS_AMPLITUDE_DEG = 30.0  # deg, oscillation amplitude, Tables 4-1 and 4-2
THESIS_K = 1.0e-5 * MM3_PER_NM  # 1/Pa, Table 4-2 (pin-on-disk value of Kim et al. [50])
THESIS_K_HIGH = 1.2e-5 * MM3_PER_NM  # 1/Pa, Ch. 4 summary: "within the range of scatter"
THESIS_STEPS_PER_SWEEP = 10  # Table 4-2, "steps per cycle" (a simulated cycle = one sweep)
THESIS_SIM_SWEEPS = 100_000  # Table 4-2, "total cycles" simulated (with extrapolation)
THESIS_TEST_CYCLES = 408_000  # Table 4-1, test cycles (-30 -> 30 -> -30 = 2 sweeps)
SWEEPS_PER_TEST_CYCLE = 2  # Ch. 4, "Experimental validation": definitions of the two cycles
STEEL_E = 206.8e9  # Pa, steel, Table 3-2
STEEL_NU = 0.29  # steel, Table 3-2

LOAD_FRAMES = ("pivot", "pin")


@dataclass(frozen=True)
class PinPivotSetup:
    """Inputs of the pin-pivot wear model (SI units).  Thesis values where the
    thesis gives them (see the constants above); the dimensions are ours: the
    thesis shows them only in Fig. 4-1 (see ``diffwear study pin-pivot``'s
    report for the justification and the scaling of the answer with them)."""

    pin_radius: float = 5.0e-3  # R [m]: a 10 mm pin (our choice)
    # c = a - R [m]: radial, a close running fit of a 10 mm pin (our choice)
    clearance: float = 10e-6
    pivot_outer_radius: float = 15e-3  # b [m]: held outer surface of the pivot, 3 R (our choice)
    length: float = 10e-3  # L [m]: contact length (cancels at fixed projected pressure)
    bore_fraction: float = 0.05  # r0 / R: the pin's held bore (`diffwear.fem.pin`)
    projected_pressure: float = THESIS_PRESSURE  # F / (2 R L) [Pa]
    amplitude_deg: float = THESIS_AMPLITUDE_DEG  # phi in [-amplitude, amplitude]
    wear_coefficient: float = THESIS_K  # k [1/Pa], the same for both bodies
    youngs_modulus: float = STEEL_E  # both bodies steel
    poisson_ratio: float = STEEL_NU
    load_frame: str = "pivot"  # body the load is fixed to ("pivot" or "pin")
    steps_per_sweep: int = THESIS_STEPS_PER_SWEEP
    n_theta: int = 60  # nodes around both surfaces (6 deg = one step of 10 per 60 deg sweep)
    n_r_pivot: int = 8  # element layers through the pivot wall
    n_r_pin: int = 16  # element layers from the pin surface to its bore

    def __post_init__(self):
        for name, low, what in [
            ("pin_radius", 0.0, "pin radius R [m]"),
            ("length", 0.0, "contact length L [m]"),
            ("projected_pressure", 0.0, "projected pressure F / (D L) [Pa]"),
            ("youngs_modulus", 0.0, "Young's modulus E [Pa]"),
        ]:
            _check_number(name, what, getattr(self, name), low, math.inf, low_open=True)
        _check_number("clearance", "radial clearance c [m]", self.clearance, 0.0, self.pin_radius,
                      high_open=True)
        _check_number("pivot_outer_radius", "pivot outer radius b [m]", self.pivot_outer_radius,
                      self.pin_radius + self.clearance, math.inf, low_open=True)
        _check_number("bore_fraction", "pin bore fraction r0 / R", self.bore_fraction, 0.0, 1.0,
                      low_open=True, high_open=True)
        _check_number("amplitude_deg", "oscillation amplitude [deg]", self.amplitude_deg, 0.0,
                      180.0, low_open=True, high_open=True)
        _check_number("wear_coefficient", "wear coefficient k [1/Pa]", self.wear_coefficient,
                      0.0, math.inf)
        _check_number("poisson_ratio", "Poisson ratio nu", self.poisson_ratio, -1.0, 0.5,
                      low_open=True, high_open=True)
        if self.load_frame not in LOAD_FRAMES:
            raise InputError(f"pin-pivot: load_frame must be one of {LOAD_FRAMES}, got "
                             f"{self.load_frame!r}")
        for name in ("steps_per_sweep", "n_r_pivot", "n_r_pin"):
            check_int_option(f"pin-pivot: {name}", getattr(self, name), 1)
        check_theta_nodes("pin-pivot: n_theta", self.n_theta)

    @property
    def force(self) -> float:
        """F = p D L [N]: the projected pressure on the pin's diameter x length."""
        return self.projected_pressure * 2.0 * self.pin_radius * self.length

    def replace(self, **changes) -> "PinPivotSetup":
        known = {f.name for f in fields(self)}
        bad = sorted(set(changes) - known)
        if bad:
            raise InputError(f"pin-pivot: unknown setup field(s) {bad}; known: {sorted(known)}")
        return PinPivotSetup(**{**{f.name: getattr(self, f.name) for f in fields(self)}, **changes})


def _check_number(name, what, value, low, high, *, low_open=False, high_open=False):
    check_range(f"pin-pivot: {name} ({what})", value, low, high, low_open=low_open,
                high_open=high_open)


def periodic_sample(values: Float[Array, " n"], shift) -> Float[Array, " n"]:
    """v(j + s) at every node j of a periodic uniform grid (linear
    interpolation; exact for a whole-number shift s, in nodes)."""
    n = values.shape[0]
    x = jnp.arange(n) + shift
    m = jnp.floor(x)
    alpha = x - m
    m = m.astype(int)
    return (1.0 - alpha) * values[m % n] + alpha * values[(m + 1) % n]


class PinPivot(eqx.Module):
    """The condensed two-body contact and the wear law; build with `build`."""

    contact: RingContact  # pivot geometry, compliance C_pivot + C_pin
    pivot_tributary: Float[Array, " n"]  # w_j on the pivot bore [m]
    pin_tributary: Float[Array, " n"]  # w_j on the pin surface [m]
    force: Float[Array, "2"]  # F [N], pin on pivot, along theta = 0 of the load frame
    wear_coefficient: Float[Array, ""]  # k [1/Pa]
    amplitude: Float[Array, ""]  # [rad]
    slide_radius: Float[Array, ""]  # R [m]: ds = R |dphi|
    steps: int = eqx.field(static=True)
    load_frame: str = eqx.field(static=True)

    @classmethod
    def build(cls, setup: PinPivotSetup) -> "PinPivot":
        s = setup
        a = s.pin_radius + s.clearance
        pivot = ring_mesh(a, s.pivot_outer_radius, s.n_theta, s.n_r_pivot)
        pin = pin_mesh(s.pin_radius, s.bore_fraction * s.pin_radius, s.n_theta, s.n_r_pin)
        contact = RingContact.build(pivot, s.youngs_modulus, s.poisson_ratio, s.clearance, s.length)
        c_pin, w_pin = _pin_parts(pin, s.youngs_modulus, s.poisson_ratio)
        contact = eqx.tree_at(lambda c: c.compliance, contact, contact.compliance + c_pin)
        return cls(contact=contact, pivot_tributary=contact.tributary, pin_tributary=w_pin,
                   force=jnp.array([s.force, 0.0]),
                   wear_coefficient=jnp.asarray(s.wear_coefficient, dtype=float),
                   amplitude=jnp.asarray(math.radians(s.amplitude_deg)),
                   slide_radius=jnp.asarray(s.pin_radius, dtype=float),
                   steps=int(s.steps_per_sweep), load_frame=s.load_frame)

    @property
    def n_theta(self) -> int:
        return self.contact.theta.shape[0]

    @property
    def theta(self) -> Float[Array, " n"]:
        return self.contact.theta

    @property
    def step_angle(self) -> Float[Array, ""]:
        return 2.0 * self.amplitude / self.steps

    def sweep_angles(self, forward) -> Float[Array, " steps"]:
        """Pin angles phi_i of the steps of one sweep: -A + i dphi (forward) or
        A - i dphi (backward), i = 0 .. steps - 1 (solve, then rotate: Fig. 4-3)."""
        i = jnp.arange(self.steps)
        sign = jnp.where(forward, 1.0, -1.0)
        return sign * (-self.amplitude + i * self.step_angle)

    def _turn_shift(self, phi):
        """Rotation of the turning body in the load frame, in nodes (snapped to
        the nearest whole node when within 1e-9 of it)."""
        turn = phi if self.load_frame == "pivot" else -phi
        s = turn * self.n_theta / (2.0 * jnp.pi)
        return jnp.where(jnp.abs(s - jnp.round(s)) < 1e-9, jnp.round(s), s)

    def solve(self, h_pivot, h_pin, phi, offset_guess=None):
        """Contact at pin angle ``phi`` with the profiles h_pivot, h_pin (each on
        its own body's nodes): (solution, pressure on the pivot's nodes,
        pressure on the pin's nodes) [Pa].  ``offset_guess``: Newton start of the
        pin offset (default: the pin on the bore along F, offset c + wear there)."""
        shift = self._turn_shift(phi)
        if self.load_frame == "pivot":
            gap_wear = h_pivot + periodic_sample(h_pin, -shift)
        else:
            gap_wear = h_pin + periodic_sample(h_pivot, -shift)
        prob = eqx.tree_at(lambda c: c.boundary_radius, self.contact,
                           self.contact.boundary_radius + gap_wear)
        if offset_guess is None:  # the pin touching the (worn) bore along F: theta = 0
            offset_guess = prob.wall_offset(self.force)
        sol = prob.solve_force(self.force, tol=TOL, offset_guess=offset_guess)
        # the FB solution leaves |f| ~ 1e-16 max f off contact, either sign: no node gains material
        sol = eqx.tree_at(lambda c: c.nodal_force, sol, jnp.maximum(sol.nodal_force, 0.0))
        f = sol.nodal_force
        if self.load_frame == "pivot":
            p_pivot = f / self.pivot_tributary
            p_pin = periodic_sample(f / self.pin_tributary, shift)
        else:
            p_pin = f / self.pin_tributary
            p_pivot = periodic_sample(f / self.pivot_tributary, shift)
        return sol, p_pivot, p_pin

    def sweep(self, state, forward, scale):
        """One computed sweep standing for ``scale`` = A sweeps: the new
        (h_pivot, h_pin, sum of normal load x sliding [N m], ok, max residual,
        pin offset e [m] of the last step) and the peak nodal pressure of each step [Pa]."""
        ds = self.slide_radius * self.step_angle

        def step(carry, phi):
            h_pv, h_pn, work, ok, res, e = carry
            sol, p_pv, p_pn = self.solve(h_pv, h_pn, phi, e)  # warm start: previous offset
            inc = self.wear_coefficient * scale * ds
            load = self.contact.length * jnp.sum(sol.nodal_force)  # total normal load [N]
            good = sol.info.converged & jnp.all(jnp.isfinite(sol.nodal_force))
            return (h_pv + inc * p_pv, h_pn + inc * p_pn, work + scale * load * ds, ok & good,
                    jnp.maximum(res, sol.info.residual), sol.offset), jnp.max(p_pv)

        return lax.scan(step, state, self.sweep_angles(forward))


class PinPivotWear(eqx.Module):
    """Result of `run_wear`: final profiles (each on its own body's nodes,
    psi_j from the load direction at phi = 0) and the history per computed sweep."""

    theta: Float[Array, " n"]
    h_pivot: Float[Array, " n"]  # [m]
    h_pin: Float[Array, " n"]  # [m]
    sweeps: Float[Array, " m"]  # real sweeps done after each computed sweep
    max_pivot: Float[Array, " m"]  # [m]
    max_pin: Float[Array, " m"]  # [m]
    peak_pressure: Float[Array, " m"]  # largest nodal pressure of the sweep [Pa]
    load_sliding: Float[Array, ""]  # A sum over steps of (total normal load) ds [N m]
    converged: Bool[Array, ""]
    residual: Float[Array, ""]
    extrapolation: float = eqx.field(static=True)  # A actually used (sweeps / computed sweeps)

    def volume(self, model: PinPivot, body: str) -> Float[Array, ""]:
        """Worn volume [m^3] of ``body``: L sum_j h_j w_j."""
        h, w = ((self.h_pin, model.pin_tributary) if body == "pin"
                else (self.h_pivot, model.pivot_tributary))
        return model.contact.length * jnp.sum(h * w)


@eqx.filter_jit
def wear_history(model: PinPivot, n_computed: int, scale):
    """Run ``n_computed`` computed sweeps (alternating, forward first), each
    standing for ``scale`` real sweeps; jitted once per (mesh, n_computed)."""
    n = model.n_theta
    zero = jnp.zeros(n)
    e0 = model.contact.wall_offset(model.force)
    state0 = (zero, zero, jnp.asarray(0.0), jnp.asarray(True), jnp.asarray(0.0), e0)

    def one(state, c):
        state, peaks = model.sweep(state, c % 2 == 0, scale)
        return state, (jnp.max(state[0]), jnp.max(state[1]), jnp.max(peaks))

    state, (mx_pv, mx_pn, peak) = lax.scan(one, state0, jnp.arange(n_computed))
    return state, mx_pv, mx_pn, peak


def computed_sweeps(sweeps: float, extrapolation: float) -> int:
    """Computed sweeps for ``sweeps`` real ones at A ~ ``extrapolation``:
    sweeps / A rounded to an even number >= 2 (whole test cycles)."""
    return max(2, 2 * int(round(sweeps / (2.0 * extrapolation))))


def run_wear(model: PinPivot, sweeps: float, extrapolation: float = 1.0) -> PinPivotWear:
    """Wear after ``sweeps`` real sweeps (one sweep = one stroke, half a test
    cycle), each computed sweep standing for A ~ ``extrapolation`` sweeps.
    `SolverError` if any contact solve failed."""
    require_float64("run_wear")
    _check_number("sweeps", "number of sweeps", sweeps, 0.0, 1e12, low_open=True)
    _check_number("extrapolation", "extrapolation factor A", extrapolation, 1.0, float(sweeps))
    m = computed_sweeps(sweeps, extrapolation)
    scale = float(sweeps) / m
    (h_pv, h_pn, work, ok, res, _), mx_pv, mx_pn, peak = wear_history(model, m, jnp.asarray(scale))
    finite = (bool(np.all(np.isfinite(np.asarray(h_pv))))
              and bool(np.all(np.isfinite(np.asarray(h_pn)))))
    ok = bool(ok) and finite
    if not ok:
        radius = float(model.slide_radius)
        worn = float(np.nanmax(np.asarray(mx_pv)) + np.nanmax(np.asarray(mx_pn)))
        hint = (f"the wear (pin + pivot up to {worn * 1e3:.3g} mm) approaches the pin radius "
                f"{radius * 1e3:.3g} mm, beyond this small-wear model: simulate fewer sweeps"
                if not (worn < 0.5 * radius) else "try a smaller extrapolation factor")
        raise SolverError(f"pin-pivot wear: a contact solve did not converge (max residual "
                          f"{float(res):.3g}, tolerance {TOL:g}) in {m} computed sweeps of "
                          f"A = {scale:g}: {hint}")
    return PinPivotWear(theta=model.theta, h_pivot=h_pv, h_pin=h_pn,
                        sweeps=scale * jnp.arange(1, m + 1), max_pivot=mx_pv, max_pin=mx_pn,
                        peak_pressure=peak,
                        load_sliding=work, converged=jnp.asarray(ok), residual=res,
                        extrapolation=scale)


def linear_extrapolation(sweeps, depth, target: float,
                         fit_from: float = 0.5) -> tuple[float, float]:
    """The thesis's last step (Ch. 4, Fig. 4-9): the depth history is
    ~linear once the wear is steady, so fit a line to the part after
    ``fit_from`` x the last simulated sweep count and read it at ``target``.
    Returns (depth at target [m], slope [m per sweep])."""
    slope, icpt = steady_line(sweeps, depth, fit_from)
    return icpt + slope * target, slope


def steady_line(sweeps, depth, fit_from: float = 0.5) -> tuple[float, float]:
    """(slope [m per sweep], intercept [m]) of the line through the depth
    history after ``fit_from`` x the last sweep count (at least its last two
    points): the line `linear_extrapolation` reads off."""
    s, d = np.asarray(sweeps, dtype=float), np.asarray(depth, dtype=float)
    sel = s >= fit_from * s[-1]
    if sel.sum() < 2:
        sel = np.zeros_like(sel)
        sel[-2:] = True
    slope, icpt = np.polyfit(s[sel], d[sel], 1)
    return float(slope), float(icpt)


@eqx.filter_jit
def _pin_parts(pin, e, nu):
    return pin_compliance(pin, e, nu), tributary_lengths(pin)
