"""A mechanism file's motion: the consistent initial state, the trajectory,
the joint reactions and contacts along it, and the checks that refuse a run up
front (a step budget too small for the drivers' revolutions, a linkage that
cannot move through its cycle) or flag results outside the clearance-joint
model's validity.

Stages with their own error classes, so that the command line's exit code says
which one failed: `initial_state` (assembly; `InputError`), `integrate`
(`SolverError`).
"""

from __future__ import annotations

import functools
import time
from typing import Any, NamedTuple, cast

import diffrax
import equinox as eqx
import jax
import numpy as np

from ..config import MechanismFile
from ..config.mechanism_file import Simulation
from ..contact import MixedLubrication, centred_state, contact_history
from ..dynamics import (
    Rodas4,
    along_trajectory,
    check_assembly,
    consistent_state,
    reaction_wrench,
    simulate,
)
from ..dynamics.kinematics import check_cycle_motion
from ..dynamics.simulate import Trajectory
from ..errors import InputError, SolverError
from ..mechanism import Mechanism
from ..mechanism.constraints import Driver
from ..quasistatic.loads import fully_driven, ideal_parent
from .transient import Settling, run_settling

_consistent_state = eqx.filter_jit(functools.partial(consistent_state, check=False))


def initial_state(mfile: MechanismFile):
    """Consistent y0 = [q, qd, aux] at t = 0 from the file's ``[initial]`` guess;
    `InputError` if the mechanism does not assemble near it.

    Same result as ``consistent_state(mech, q_guess)`` but compiled (the eager
    Newton iteration costs seconds); the check then runs on concrete values.
    With clearance joints the assembly is that of ``mfile.assembly`` (each one
    an ideal revolute at the same points): the pins start centred with the
    ideal joints' velocities, and the contact states at their initial values.
    """
    mech = mfile.mechanism if mfile.assembly is None else mfile.assembly
    y0 = _consistent_state(mech, mfile.q_guess)
    finite = bool(np.all(np.isfinite(np.asarray(y0))))
    try:
        check_assembly(mech, y0[: mech.n_coords], finite, q_guess=mfile.q_guess)
    except InputError as err:
        raise InputError(f"{mfile.file}: initial: {err}") from None
    if mfile.assembly is None:
        return y0
    return centred_state(mech, y0, mfile.mechanism)


def lubricated(mech: Mechanism) -> bool:
    """Whether ``mech`` has a lubricated clearance joint (`MixedLubrication`)."""
    return any(isinstance(getattr(f, "law", None), MixedLubrication) for f in mech.forces)


def motion_integrator(mech: Mechanism) -> str:
    """The integrator of a file's motion: ``"Rodas4"`` for a mechanism with a
    lubricated joint, else ``"Tsit5"``.

    An oil film's squeeze term damps the pin's motion in the clearance with a
    time constant (pin mass / film damping) of ~0.1 us, so an explicit
    integrator is held at steps of that size (1e5-1e6 per simulated second); the
    L-stable, linearly implicit Rodas4 is not, and takes its steps for
    accuracy (docs/notes/lubricated-motion.md has the measurements).  The dry
    mechanisms keep Tsit5, faster on their contacts at the files' tolerance.
    """
    return "Rodas4" if lubricated(mech) else "Tsit5"


@eqx.filter_jit
def _integrate(mech: Mechanism, y0, sim: Simulation, t0) -> Trajectory:
    ts = t0 + sim.ts()
    if motion_integrator(mech) == "Tsit5":
        return simulate(mech, y0, t0 + sim.duration, t0=t0, ts=ts,
                        baumgarte=sim.baumgarte(), stepsize_controller=sim.controller(),
                        max_steps=sim.max_steps)
    # every saved state the end of a step: Rodas4's cubic interpolant between
    # steps would blur the film's fast squeeze transients in the saved forces
    controller = diffrax.ClipStepSizeController(sim.controller(), step_ts=ts)
    return simulate(mech, y0, t0 + sim.duration, t0=t0, ts=ts, solver=Rodas4(),
                    baumgarte=sim.baumgarte(), stepsize_controller=controller,
                    max_steps=sim.max_steps)


def integrate(mfile: MechanismFile, y0, t0: float = 0.0) -> Trajectory:
    """The file's trajectory from ``y0`` at ``t0`` [s] over the file's
    duration; `SolverError` (naming the file) if the solve failed.  A start
    other than 0 continues a run from one of its states (the drivers' angles
    are functions of the time)."""
    return integrate_timed(mfile, y0, t0).trajectory


class Timed(NamedTuple):
    trajectory: Trajectory
    compile_time_s: float   # compiling the integrator's program
    run_time_s: float       # running the compiled program
    failure: str | None = None  # why the integrator stopped early (``partial=True``);
                                # ``trajectory`` then holds the states it reached


def integrate_timed(mfile: MechanismFile, y0, t0: float = 0.0, *,
                    partial: bool = False) -> Timed:
    """`integrate`, compiled ahead of the run so that the report can give the
    compile time and the run time apart.  A failed integration raises
    `SolverError`; with ``partial=True`` it returns the states reached and the
    failure's message instead, when at least two saved states were reached."""
    args = (mfile.mechanism, y0, mfile.simulation, jax.numpy.asarray(float(t0)))
    start = time.perf_counter()
    # equinox's jit wrapper lowers ahead of time; its type is hidden by the decorator
    compiled = cast(Any, _integrate).lower(*args).compile()
    compiled_at = time.perf_counter()
    traj = jax.block_until_ready(compiled(*args))
    done = time.perf_counter()
    try:
        return Timed(traj.raise_if_failed(mfile.file, mfile.mechanism,
                                          advice=_advice(mfile, traj, float(t0))),
                     compiled_at - start, done - compiled_at)
    except SolverError as err:
        reached = traj.reached()
        if not partial or reached.ts.shape[0] < 2:
            raise
        return Timed(reached, compiled_at - start, done - compiled_at, failure=str(err))


def _advice(mfile: MechanismFile, traj: Trajectory, t0: float) -> str | None:
    """What to change in the file when its motion ran out of steps (None:
    the generic advice of any other failure).  The budget at the pace so far;
    on Rodas4 (a lubricated joint) a looser tolerance also takes fewer steps,
    on Tsit5 hardly where a contact's stiffness holds its steps
    (docs/notes/rosenbrock-rig-cycle.md)."""
    if not traj.out_of_steps:
        return None
    sim = mfile.simulation
    reached = float(traj.t_final) - t0
    budget = (f"raise [simulation] max_steps (now {sim.max_steps:,}) to about "
              f"{1.2 * sim.max_steps * sim.duration / reached:,.0f}, the pace so far over the "
              f"{sim.duration:g} s" if reached > 0 else "raise [simulation] max_steps")
    if motion_integrator(mfile.mechanism) == "Rodas4":
        return (f"The step budget ran out: {budget}, or loosen [simulation] rtol and atol "
                f"(now {sim.rtol:g}, {sim.atol:g}): the lubricated joint's motion is integrated "
                "on Rodas4, whose steps are set by the tolerance (1e-6 takes about a quarter "
                "of the steps of 1e-8), or shorten [simulation] duration.")
    return (f"The step budget ran out: {budget}, or shorten [simulation] duration (a looser "
            "tolerance helps little where a clearance joint's contact stiffness holds "
            "Tsit5's steps).")


class Results(NamedTuple):
    ts: np.ndarray          # (T,) s
    q: np.ndarray           # (T, n) m / rad
    qd: np.ndarray          # (T, n) m/s / rad/s
    violation: np.ndarray   # (T, m) constraint residuals (m or rad per row)
    reactions: dict         # joint -> (T, 3): fx [N], fy [N], moment about COM [N m]
    contacts: dict = {}     # clearance joint -> (T, 4): |F| [N], normal load [N],
                            #   contact angle [rad], penetration [m]


@eqx.filter_jit
def _contacts(mech: Mechanism, ys, joints):
    out = {}
    for joint in joints:
        h = contact_history(mech, joint, ys)
        out[joint] = jax.numpy.stack([h.force_magnitude, h.normal_load, h.contact_angle,
                                      h.penetration], axis=-1)
    return out


@eqx.filter_jit
def _post(mech: Mechanism, ts, ys, sim: Simulation, outputs):
    _, lam, _ = along_trajectory(mech, ts, ys, sim.baumgarte())
    q, qd, _ = jax.vmap(mech.split)(ys)
    phi = jax.vmap(mech.phi)(q, ts)
    wrenches = {
        o.joint: jax.vmap(lambda qq, ll, t, o=o: reaction_wrench(mech, qq, ll, t, o.joint, o.on))(
            q, lam, ts)
        for o in outputs
    }
    return q, qd, phi, wrenches


def postprocess(mfile: MechanismFile, traj: Trajectory) -> Results:
    q, qd, phi, wrenches = _post(mfile.mechanism, traj.ts, traj.ys, mfile.simulation,
                                 mfile.reactions)
    contacts = _contacts(mfile.mechanism, traj.ys, tuple(o.joint for o in mfile.contacts))
    return Results(np.asarray(traj.ts), np.asarray(q), np.asarray(qd), np.asarray(phi),
                   {k: np.asarray(v) for k, v in wrenches.items()},
                   {k: np.asarray(v) for k, v in contacts.items()})


def force_signals(mfile: MechanismFile, r: Results) -> dict[str, np.ndarray]:
    """The forces whose maxima a run reports, by name: each requested
    reaction's |F| and |M|, each clearance joint's contact force."""
    out: dict[str, np.ndarray] = {}
    for o in mfile.reactions:
        w = r.reactions[o.joint]
        out |= {f"reaction {o.joint!r} |F|": np.hypot(w[:, 0], w[:, 1]),
                f"reaction {o.joint!r} |M|": np.abs(w[:, 2])}
    for co in mfile.contacts:
        out[f"contact force of {co.joint!r}"] = r.contacts[co.joint][:, 0]
    return out


def _cycle_period(mechanism: Mechanism) -> float | None:
    """One revolution of the first driver [s], or None without a turning driver."""
    driver = first_driver(mechanism)
    return None if driver is None else driver.period


def start_up_transient(mfile: MechanismFile, r: Results) -> Settling:
    """How long the reported forces take to settle onto the forced motion
    (`diffwear.mechanism_file.transient`); a run that reports no force has
    nothing to settle (0 s)."""
    return run_settling(r.ts, force_signals(mfile, r), _cycle_period(mfile.mechanism))


def first_driver(mechanism: Mechanism) -> Driver | None:
    """The first driver with a non-zero speed (its revolution is the mechanism's
    cycle), or None."""
    return next((c for c in mechanism.constraints
                 if isinstance(c, Driver) and float(c.omega) != 0.0), None)


# A penalty contact holds for elastic penetrations of microns: one of 10 % of
# the pin radius means the pin is through the bushing (e.g. a rod shorter than
# the crank forcing an assembly the clearance cannot take).
MAX_PENETRATION_OF_PIN_RADIUS = 0.1


def contact_warnings(joint, contact: dict) -> list[tuple[str, bool]]:
    """(message, fatal) for results outside the clearance joint model's
    validity: no contact at all (a warning; not for a lubricated joint, whose
    film holds the pin off the bore), or a penetration beyond
    `MAX_PENETRATION_OF_PIN_RADIUS` of the pin radius (fatal)."""
    out = []
    # a lubricated pin that never reaches the bore rides on its oil film (the
    # film's force acts throughout): not a pin moving freely
    lubricated = isinstance(joint.law, MixedLubrication)
    if contact["fraction_in_contact"] == 0.0 and not lubricated:
        out.append((f"clearance joint {joint.name!r} never made contact: the pin moved freely "
                    "inside the bushing for the whole run (a clearance larger than the "
                    "motion?)", False))
    radius = float(joint.pin_radius)
    if contact["max_penetration_m"] > MAX_PENETRATION_OF_PIN_RADIUS * radius:
        out.append((f"clearance joint {joint.name!r}: penetration "
                    f"{contact['max_penetration_m'] * 1e3:.3g} mm is "
                    f"{contact['max_penetration_m'] / radius:.0%} of the pin radius "
                    f"{radius * 1e3:g} mm: the pin is through the bushing and the contact model "
                    "does not hold (geometry that cannot assemble with this clearance, e.g. a "
                    "rod shorter than the crank?)", True))
    return out


# Integrator steps per crank revolution, a lower bound: the ideal slider-crank
# takes 2,276 steps per revolution at the default tolerances (performance docs).
MIN_STEPS_PER_REVOLUTION = 500


def check_step_budget(mfile: MechanismFile) -> None:
    """Refuse up front a run whose drivers turn more revolutions than the step
    budget (``max_steps``) can take at `MIN_STEPS_PER_REVOLUTION`."""
    sim = mfile.simulation
    for c in mfile.mechanism.constraints:
        omega = getattr(c, "omega", None)
        if omega is None:
            continue
        turns = sim.duration * abs(float(omega)) / (2 * np.pi)
        need = turns * MIN_STEPS_PER_REVOLUTION
        if need > sim.max_steps:
            raise InputError(
                f"{mfile.file}: driver {c.name!r} turns {turns:.3g} revolutions in "
                f"{sim.duration:g} s: at least {need:.2g} integrator steps, beyond the budget "
                f"max_steps = {sim.max_steps:,}; allowed: a speed or duration within it, "
                "or a larger [simulation] max_steps")


# Samples of the cycle in the motion check (5 degrees of the driver apart).
MOTION_SAMPLES = 73


def check_motion(mfile: MechanismFile, y0) -> None:
    """Refuse up front a linkage that cannot move through its cycle (links too
    short to reach, a crank that cannot turn fully, a dead point): the ideal
    mechanism (clearance joints taken as revolute joints) is closed at
    `MOTION_SAMPLES` instants over one revolution of its first driver (or the
    run's duration, if shorter).  Mechanisms the drivers do not fully
    determine are not checked (their motion is not kinematic)."""
    ideal = ideal_parent(mfile.mechanism)
    driver = first_driver(ideal)
    if driver is None or not fully_driven(ideal):
        return
    sim = mfile.simulation
    span = min(sim.duration, driver.period)
    q0, _, _ = ideal.split(y0)
    ts = np.linspace(0.0, span, MOTION_SAMPLES)
    check_cycle_motion(ideal, q0, ts, what=str(mfile.file), driver=f"driver {driver.name!r}")


__all__ = ["Results", "Timed", "check_motion", "check_step_budget", "contact_warnings",
           "first_driver", "force_signals", "initial_state", "integrate",
           "integrate_timed", "lubricated", "motion_integrator", "postprocess",
           "start_up_transient"]
