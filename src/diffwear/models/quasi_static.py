"""`QuasiStatic`: the quasi-static wear model as a strategy object.

One settled cycle of the ideal mechanism gives every wearing joint's loads
(`cycle_loads`); each joint's profile then evolves in the cycle count by
`diffwear.wear.profile_ode`, its wear per cycle from the pin's equilibrium on
the EFM springs (`QuasiStaticJoint`).  Without the pin offset fed back into
the kinematics (it changes the link lengths by at most the wear depth; the
measured effect on the Ch. 7 rig and the Ch. 8 lives is in the docs) the
joints do not interact, so they evolve side by side: stacked and vmapped when
their grids match (one loop in the compiled program), one after another
otherwise.

Every result carries a contact check, `QuasiStaticJoint.contact_margin`: a
margin below 1 anywhere in the cycle of the unworn joint sets the result
`RESULTS.contact_lost` (the pin flies across the clearance: the reduction does
not hold; use `Dynamic`).  Table 2-1 slider-crank: the 5 mm clearance is
flagged (margin 0.21; thesis Fig. 3-7: contact briefly lost), 0.5 mm is not
(2.1).  The margin at the final profile is reported beside it: a groove much
deeper than the clearance can let the pin lift off its flank where the load
turns fast (Ch. 8 joint 2 near its 2 mm limit: 0.25 over 1 % of the cycle,
carrying ~0.1 % of the wear), which the results report as a warning; the lives
there still agree with the dynamic model (docs: the agreement table).
"""

from __future__ import annotations

from typing import Any, ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_int_option, check_range, require_float64
from ..contact import ContactHistory
from ..errors import InputError
from ..mechanism import GROUND, Mechanism
from ..mechanism.geometry import safe_angle, safe_norm
from ..quasistatic.joint import EQUILIBRIUM
from ..quasistatic.loads import CycleLoads, JointLoads, clearance_joints, cycle_loads
from ..quasistatic.lubricated import joint_model
from ..wear._engine import AbstractWearTerm, CycleWear, Stop
from ..wear.implicit import CycleGrid, LinearlyImplicitEuler
from ..wear.modifier import AbstractWearModifier, JointGeometry, modulated
from ..wear.profile_ode import solve_profile
from ..wear.solution import WearSolution
from ..wear.status import RESULTS, not_an_answer, not_computed, stack, worst
from ._base import AbstractWearModel


def joint_mass(mech: Mechanism, joint) -> Float[Array, ""]:
    """Mass [kg] for the contact check: the heavier of the joint's two bodies
    (a conservative stand-in for the effective mass of the pin's relative
    motion; the ground counts as neither)."""
    masses = [b.mass for b in mech.bodies if b.name in (joint.pin_body, joint.bushing_body)
              and b.name != GROUND]
    return jnp.max(jnp.stack([jnp.asarray(m, dtype=float) for m in masses]))


def _stackable(trees) -> bool:
    first: Any = jax.tree.structure(trees[0])
    shapes = [jnp.shape(x) for x in jax.tree.leaves(trees[0])]
    return all(jax.tree.structure(t) == first
               and [jnp.shape(x) for x in jax.tree.leaves(t)] == shapes for t in trees[1:])


class QuasiStatic(AbstractWearModel):
    """The quasi-static wear model (module notes; `QuasiStaticJoint` for the
    physics and where it holds).

    ``samples``: equally spaced samples of the load cycle (quadrature of the
    wear; 180 changes the Ch. 8 lives by < 1e-4 against 360); ``steps``: the
    accuracy knob of the wear ODE in the cycle count
    (`diffwear.wear.profile_ode`; 40 puts the Ch. 8 lives within ~0.2 % of
    their converged values, the Ch. 7 rig's depth within 1e-6); ``warmup_cycles``:
    settling cycles of a mechanism that is not fully driven; ``load_rtol``:
    tolerance of the ideal mechanism's solve; ``contact_mass`` [kg]: mass for
    the contact check (default `joint_mass`); ``max_steps``: scan slots of the
    wear ODE (default ``steps + 3``, counted tight for vmapped design sweeps; a
    groove whose peak grows slower than the step rule expects needs more: a
    single run can afford ``4 steps + 8``); ``grid``: real cycle counts 0 =
    N_0 < N_1 < ... to step on instead (one linearly implicit step per
    interval, the profile kept at each: `diffwear.wear.implicit.CycleGrid`),
    which a ``modifier`` (`AbstractWearModifier`: the calibration's effects)
    needs.
    """

    name: ClassVar[str] = "quasi-static"
    exact_gradients: ClassVar[bool] = True
    samples: int = eqx.field(static=True, default=180)
    steps: int = eqx.field(static=True, default=40)
    warmup_cycles: int = eqx.field(static=True, default=0)
    load_rtol: float = eqx.field(static=True, default=1e-8)
    contact_mass: Float[Array, ""] | None = None
    fixed_loads: CycleLoads | None = None
    max_steps: int | None = eqx.field(static=True, default=None)
    grid: Float[Array, " K"] | None = None
    modifier: AbstractWearModifier | None = None

    def __check_init__(self):
        if self.modifier is not None and self.grid is None:
            raise InputError("QuasiStatic: a modifier's rate is held over each step, so its "
                             "steps must be given in advance; allowed: grid= (real cycle "
                             "counts) with modifier=")
        # counts of the quadrature and of the wear ODE: a zero or negative one
        # has no cycle to integrate (an `InputError` here, not a shape error
        # or a division by zero in the traced program)
        check_int_option("QuasiStatic: samples", self.samples, 1)
        check_int_option("QuasiStatic: steps", self.steps, 1)
        check_int_option("QuasiStatic: warmup_cycles", self.warmup_cycles, 0)
        if self.max_steps is not None:
            check_int_option("QuasiStatic: max_steps", self.max_steps, 1)
        check_range("QuasiStatic: load_rtol", self.load_rtol, 0.0, 1.0, low_open=True,
                    high_open=True)

    @property
    def precomputes(self) -> bool:  # type: ignore[override]
        """The joint loads are computed once unless they are given."""
        return self.fixed_loads is None

    def prepared(self, mech: Mechanism, joints, y0, period) -> "QuasiStatic":
        """This model with the joint loads of ``mech`` computed once
        (`with_loads`), unless they are given already."""
        if self.fixed_loads is not None:
            return self
        return self.with_loads(self.loads(mech, joints, y0, period))

    def with_loads(self, loads: CycleLoads) -> "QuasiStatic":
        """This model with the joint loads given (`loads`): for studies whose
        parameters leave the ideal mechanism unchanged (bushing dimensions,
        clearance, wear coefficient, friction), which then skip its solve."""
        return eqx.tree_at(lambda m: m.fixed_loads, self, loads,
                           is_leaf=lambda x: x is None)

    # --------------------------------------------------------------- pieces
    def loads(self, mech: Mechanism, joints, y0, period) -> CycleLoads:
        """Loads of ``joints`` over one settled cycle of the ideal mechanism
        (``fixed_loads`` if given)."""
        if self.fixed_loads is not None:
            return self.fixed_loads
        return cycle_loads(mech, tuple(joints), y0, period, samples=self.samples,
                           warmup_cycles=self.warmup_cycles, rtol=self.load_rtol,
                           atol=self.load_rtol)

    def joints(self, mech: Mechanism, joints) -> tuple:
        return tuple(joint_model(j) for j in clearance_joints(mech, joints))

    def masses(self, mech: Mechanism, joints) -> tuple:
        if self.contact_mass is not None:
            m = jnp.asarray(self.contact_mass, dtype=float)
            return tuple(m for _ in joints)
        return tuple(joint_mass(mech, j) for j in clearance_joints(mech, joints))

    def _each(self, mech, joints, y0, period, walls=None, **target):
        """Per joint: (its `WearSolution`, (unworn, worn) contact margins); and
        the loads' success.  ``walls``: per joint wall thickness [m] (none:
        no wall)."""
        require_float64("QuasiStatic")
        loads = self.loads(mech, joints, y0, period)
        models = self.joints(mech, joints)
        masses = self.masses(mech, joints)
        # slots needed: steps + 1 for a life (each step gains up to limit / steps
        # of peak depth; measured steps + 1 on the Ch. 8 designs), at most
        # steps + 1 for a run of fixed length (the first step is the longest).
        # Under vmap every slot runs, so they are counted tight; a life that
        # needs more is reported (`RESULTS.run_ended_early`), not cut.
        slots = self.steps + 3 if self.max_steps is None else int(self.max_steps)

        walls = (jnp.full(len(models), jnp.inf) if walls is None
                 else jnp.broadcast_to(jnp.asarray(walls, dtype=float), (len(models),)))

        # what a modifier reads of each joint (a grid run only)
        geometries = (tuple(JointGeometry.of(el) for el in clearance_joints(mech, joints))
                      if self.grid is not None else (None,) * len(models))

        def one(j, lo: JointLoads, mass, wall, geometry):
            term = _JointWear(j, lo, self.modifier, geometry)
            # warm start: the pin offsets of the previous step's profile
            memory = jnp.full_like(lo.force, jnp.nan)
            solver, stop = self._stepping(wall, **target)
            sol = solve_profile(term, solver, jnp.zeros(j.n), memory, stop,
                                solver.slots(stop, slots))
            margins = jnp.stack([jnp.min(j.contact_margin(jnp.zeros(j.n), lo, mass)),
                                 jnp.min(j.contact_margin(sol.depth[0], lo, mass))])
            return sol, margins

        parts = (models, loads.joints, masses, tuple(walls), geometries)
        if len(models) > 1 and all(_stackable(p) for p in parts):
            # one vmapped loop, not two side by side in one program (XLA's CPU
            # runtime: docs/notes/quasi-static-model.md, "Joints side by side")
            stacked = [jax.tree.map(lambda *a: jnp.stack(a), *p) for p in parts]
            sols, margins = jax.vmap(one)(*stacked)
            per_joint = [(jax.tree.map(lambda a: a[i], sols), margins[i])
                         for i in range(len(models))]
        else:
            per_joint = [one(*args) for args in zip(*parts)]
        return per_joint, loads.ok

    def _stepping(self, wall, cycles=None, limit=None):
        """The step rule and the stop of one joint's integration: the
        linearly implicit rule in `steps` steps, or the given cycle `grid`
        (to its last count unless ``cycles`` says otherwise)."""
        if self.grid is None:
            return (LinearlyImplicitEuler(int(self.steps)),
                    Stop(cycles=cycles, limit=limit, wall=wall))
        solver = CycleGrid(jnp.asarray(self.grid, dtype=float))
        return solver, Stop(cycles=solver.grid[-1] if cycles is None else cycles, limit=limit,
                            wall=wall)

    @staticmethod
    def _result(per_joint, loads_ok):
        status = stack([
            RESULTS.where(~loads_ok, RESULTS.cycle_model_failed,
                          RESULTS.where((sol.result == RESULTS.ok) & (margins[0] < 1.0),
                                        RESULTS.contact_lost, sol.result))
            for sol, margins in per_joint])
        return status, worst(status)

    # -------------------------------------------------------------- results
    def solve(self, mech, joints, y0, *, period, cycles=None, limit=None,
              wall_thickness=None) -> WearSolution:
        """One integration of the wear of ``joints`` from unworn bushings, to
        ``cycles`` real cycles, to ``limit`` [m] of peak depth, or to whichever
        comes first (the engine's `Stop`), stopping a joint at its
        ``wall_thickness`` [m]: one `WearSolution` (the profiles reached and,
        with a limit, the lives).  Given as traced values (``limit`` +inf:
        none; ``cycles`` `MAX_CYCLES`: none), a run and a life are one
        program: jitted once, it serves both (a lubricated joint's orbit takes
        tens of seconds to compile)."""
        per_joint, ok = self._each(mech, joints, y0, period, walls=wall_thickness,
                                   cycles=cycles, limit=limit)
        joint_result, result = self._result(per_joint, ok)
        sols: list[WearSolution] = [s for s, _ in per_joint]
        inputs = (self, mech, y0, period, cycles, limit, wall_thickness)
        failed = not_computed(joint_result)
        # a joint whose cycle model failed (a joint that carries no load: its
        # equilibrium has no solution) or whose slots ran out has no life and,
        # short of ``cycles``, no final profile: NaN, with NaN derivatives by
        # every input (never a silent 0; the profiles it reached stay in the
        # history)
        return WearSolution(
            depth=tuple(not_an_answer(s.depth[0], failed[k], inputs) for k, s in enumerate(sols)),
            joint_cycles=jnp.concatenate([s.joint_cycles for s in sols]),
            life=not_an_answer(jnp.concatenate([s.life for s in sols]), failed, inputs),
            result=result, joint_result=joint_result,
            contact_margin=jnp.stack([m[0] for _, m in per_joint]),
            contact_margin_worn=jnp.stack([m[1] for _, m in per_joint]),
            stats={"steps": jnp.concatenate([s.stats["steps"] for s in sols]),
                   "evaluations": jnp.stack([s.stats["evaluations"] for s in sols])},
            history=tuple(s.history[0] for s in sols))

    def joint_force(self, mech, joint, y0, *, period, evolution: WearSolution,
                    samples: int = 180):
        """The ideal mechanism's joint load over the cycle (`samples` of this
        model's): wear does not change it in this model."""
        return safe_norm(self.loads(mech, (joint,), y0, period).joints[0].force)

    def contact_history(self, mech, joint: str, y0, period, depth) -> ContactHistory:
        """``joint`` over one cycle at wear ``depth``: the loads of the ideal
        mechanism, the pin at equilibrium."""
        loads = self.loads(mech, (joint,), y0, period).joints[0]
        model = self.joints(mech, (joint,))[0]
        eq = model.equilibrium(depth, loads)
        gap = eq.offset @ model.directions.T - (model.clearance + depth)
        angle = jnp.mod(safe_angle(eq.offset), 2 * jnp.pi)
        return ContactHistory(force=loads.force, normal_load=eq.normal_load, offset=eq.offset,
                              penetration=gap.max(axis=1), contact_angle=angle,
                              pressure=eq.pressure)

    def cycle_histories(self, mech, joint, y0, *, period, evolution: WearSolution) -> tuple:
        """The unworn and the final profile's equilibria over the cycle (the
        same joint load: wear does not change it in this model)."""
        history = eqx.filter_jit(self.contact_history)
        depth = evolution.depth[0]
        crank = 2 * jnp.pi * jnp.arange(self.samples) / self.samples
        return (history(mech, joint, y0, period, jnp.zeros_like(depth)),
                history(mech, joint, y0, period, depth), crank)

    def film_cycle(self, mech, joints, y0, period, depths) -> tuple[list, Any]:
        """The lubricated ``joints``' film and asperities over one cycle at the
        pin's quasi-static equilibrium (`LubricatedQuasiStaticJoint.equilibrium`),
        on the unworn bushing and on the worn one (``depths``: per joint, the
        wear depth [m] on the bushing grid), under this model's loads.  Per
        joint, (unworn, worn) dicts of arrays over the cycle's samples; and
        whether the loads converged."""
        loads = self.loads(mech, joints, y0, period)
        out = []
        for j, lo, h in zip(self.joints(mech, joints), loads.joints, depths):
            # the unworn bushing, then the worn one from the unworn offsets:
            # one scan, so that the equilibrium (the orbit's solves) is
            # compiled once
            def one(guess, depth, j=j, lo=lo):
                eq = j.equilibrium(depth, lo, guess)
                return eq.offset, _film_numbers(j, lo, eq)

            _, both = jax.lax.scan(one, jnp.full_like(lo.force, jnp.nan),
                                   jnp.stack([jnp.zeros(j.n), h]))
            out.append(tuple(jax.tree.map(lambda a, k=k: a[k], both) for k in (0, 1)))
        return out, loads.ok


def _film_numbers(joint, loads: JointLoads, eq) -> dict:
    """A lubricated joint's film numbers at its equilibrium ``eq`` over the
    cycle; the bore's deflection under the film's peak pressure is p / k_f
    (the foundation's stiffness: a soft bore's test)."""
    film = joint.law.saturated_film()
    eps = safe_norm(eq.offset) / film.clearance
    peak = jax.vmap(lambda e, om: film.steady_peak_pressure(e, om, joint.dry.pin_radius))(
        eps, loads.omega)
    return {"min_film_thickness": eq.min_film_thickness, "film_ratio": eq.film_ratio,
            "interference": eq.interference, "film_peak_pressure": peak,
            "bore_deflection": peak / joint.law.asperity.stiffness,
            "asperity_share": eq.asperity_share, "film_load": eq.film_load,
            "asperity_load": eq.normal_load, "ok": eq.ok}


_KEEP_EQUILIBRIUM = jax.checkpoint_policies.save_only_these_names(EQUILIBRIUM)


class _JointWear(AbstractWearTerm):
    """One quasi-static joint's wear per cycle at the clearance profile
    c0 + g h (g the modifier's growth), its rate and response modulated by
    the modifier over each step (`diffwear.wear.modifier`)."""

    joint: Any
    loads: JointLoads
    modifier: AbstractWearModifier | None
    geometry: JointGeometry

    def _growth(self):
        return 1.0 if self.modifier is None else self.modifier.growth()

    def cycle(self, h, memory) -> CycleWear:
        # a reverse pass keeps of each cycle only its pin offsets and
        # recomputes the rest: a gradient that stored the cycle's (samples x
        # nodes) arrays for every step cost 2.4-2.6x as much
        # (benchmarks/experiments/reverse_pass.py)
        return jax.checkpoint(_JointWear._cycle, policy=_KEEP_EQUILIBRIUM)(self, h, memory)

    def _cycle(self, h, memory) -> CycleWear:
        seen = self._growth() * h[0]
        dw, _, eq = self.joint.cycle_wear(seen, self.loads, memory)
        a = self.joint.wear_response(seen, self.loads, eq)
        return CycleWear(rate=(dw,), ok=eq.ok, memory=eq.offset, response=(a,))

    def modulate(self, cw: CycleWear, h, n, dn) -> CycleWear:
        if self.modifier is None:
            return cw
        return modulated(cw, h, n, dn, self.modifier, self.geometry)


__all__ = ["QuasiStatic", "joint_mass"]
