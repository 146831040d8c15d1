"""The wear engine: bushing profiles integrated in the crank-cycle count.

Every wear result of the package (an evolution over N cycles, a life to a
depth limit, a calibration's forward history) is one call of `integrate`:

    integrate(term, solver, WearState.initial(h0, memory), stop=..., slots=...)

in the shape of diffrax's ``diffeqsolve(terms, solver, ...)``:

* the **term** (`AbstractWearTerm`) is the cycle model: the wear of one crank
  cycle at a profile, w(h) (thesis Eq. 4-18 with A = 1), its response
  A = -dw/dh where the solver needs it, and what the next cycle starts from
  (the mechanism state of a dynamic cycle, the warm start of an equilibrium).
  The wear models supply it (`diffwear.wear.dynamic_term.DynamicWear`, the
  FEM route's `FemWear`, the quasi-static joint through
  `diffwear.wear.profile_ode`).
* the **solver** (`AbstractWearSolver`) advances the profile by one step:
  explicit extrapolation (`Constant`, `Adaptive`: thesis Eqs. 4-19, 4-20), an
  error-controlled pair (`ErrorControlled`), or the linearly implicit Euler
  step with its step-size rule (`LinearlyImplicitEuler`, `DepthGain`,
  `CycleGrid`: `diffwear.wear.implicit`).
* the **stop** (`Stop`) says where the integration ends: a cycle count, a
  depth limit (the life: the crossing is interpolated within its step), a
  wall (a step through it is cut back to it).

The engine owns the bookkeeping every route shares: the ``lax.scan`` over a
static number of slots (slots after the end are skipped with ``lax.cond``),
the status (a failed step keeps the last good state), the cut at the wall,
the crossing of the limit, and the per-slot history.  Profiles are a tuple
of arrays, one per wearing joint; joints are integrated together (one cycle
evaluates all of them) and a joint that reaches the limit is held there.
"""

from __future__ import annotations

import abc
import dataclasses
from typing import Any, Callable, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, Float

from .status import RESULTS, code, from_code


class CycleWear(eqx.Module):
    """The wear term at one profile.

    ``rate``: wear per cycle [m], one array per joint (tuple); ``ok``: the
    cycle model succeeded; ``memory``: what the next cycle starts from;
    ``load_sliding``: per joint, the cycle's integral of normal load x
    sliding [N m] (or ``None``); ``response``: per joint A = -d rate / dh
    (or ``None``); ``extra``: anything a solver or a record reads (saved
    states, force traces)."""

    rate: tuple
    ok: Array
    memory: Any
    load_sliding: Any = None
    response: Any = None
    extra: Any = None


class AbstractWearTerm(eqx.Module):
    """A cycle model: the wear of one crank cycle at profile ``h``."""

    @abc.abstractmethod
    def cycle(self, h: tuple, memory: Any) -> CycleWear:
        """The wear of one cycle at profiles ``h`` (one per joint), starting
        from ``memory`` (the previous cycle's)."""

    def modulate(self, cw: CycleWear, h: tuple, n, dn) -> CycleWear:
        """The rate over the real cycles [n, n + dn] from the cycle's rate
        (identity here; the calibration's effects scale it)."""
        return cw

    def advance(self, h: tuple, cw: CycleWear, dn):
        """The profiles after ``dn`` real cycles at the rate of one cycle, for
        the explicit solvers: (profiles, load x sliding per joint, memory, ok).
        Here the extrapolation h + dn w (thesis Eq. 4-19); the FEM route's
        term takes its linearly implicit step."""
        return (tuple(x + dn * w for x, w in zip(h, cw.rate)), dn * cw.load_sliding, cw.memory,
                cw.ok)


class WearState(eqx.Module):
    """Where an integration stands after some slots: the carry of the scan and
    what a checkpoint holds.

    ``h``: profiles [m] (one per joint); ``memory``: the term's carried state;
    ``n``: real cycles; ``status``: a `diffwear.wear.RESULTS` member; ``evaluations``:
    cycles of the model run (dynamic cycles, warm-up included); ``steps``:
    slots that ran; ``load_sliding``: per joint, the extrapolated sum of
    int N ds [N m]; ``life``: per joint, the cycles at the limit (NaN before);
    ``done``: per joint, at the limit; ``fail_n``/``fail_h``: cycles and peak
    depth where the run stopped early (0 while running); ``solver``: the
    solver's memory by name."""

    h: tuple
    memory: Any
    n: Float[Array, ""]
    status: RESULTS
    evaluations: Array
    steps: Array
    load_sliding: Float[Array, " J"]
    life: Float[Array, " J"]
    done: Array
    fail_n: Float[Array, ""]
    fail_h: Float[Array, ""]
    solver: dict

    @classmethod
    def initial(cls, h0: tuple, memory, *, evaluations=0, ok=True) -> "WearState":
        """The state before the first step: profiles ``h0``, the term's
        ``memory`` (e.g. after warm-up cycles, ``evaluations`` of them, ``ok``
        if they succeeded)."""
        j = len(h0)
        return cls(
            h=tuple(h0), memory=memory, n=jnp.zeros(()),
            status=RESULTS.where(jnp.asarray(ok, dtype=bool), RESULTS.ok,
                                 RESULTS.cycle_model_failed),
            evaluations=jnp.asarray(evaluations), steps=jnp.zeros((), int),
            load_sliding=jnp.zeros(j), life=jnp.full((j,), jnp.nan),
            done=jnp.zeros((j,), bool), fail_n=jnp.zeros(()), fail_h=jnp.zeros(()), solver={})

    def replace(self, **changes) -> "WearState":
        """A copy with the named fields changed; solver memory by its names."""
        solver = {k: changes.pop(k) for k in list(changes) if k not in _FIELDS}
        if solver:
            changes["solver"] = {**self.solver, **solver}
        return dataclasses.replace(self, **changes)

    def as_dict(self) -> dict:
        """Flat name -> array: a checkpoint's layout (the status as its code)."""
        return _flatten({f: code(self.status) if f == "status" else getattr(self, f)
                         for f in _FIELDS})

    @classmethod
    def from_dict(cls, d: dict) -> "WearState":
        from ..errors import InputError

        tree = _unflatten(d)
        missing = [f for f in _FIELDS if f not in tree]
        if missing:
            raise InputError(f"wear state without {missing}")
        try:
            status = from_code(tree["status"])
        except ValueError as err:
            raise InputError(f"wear state: {err}") from err
        fields: dict[str, Any] = {f: tree[f] for f in _FIELDS}
        return cls(**{**fields, "status": status})


_FIELDS = ("h", "memory", "n", "status", "evaluations", "steps", "load_sliding", "life",
           "done", "fail_n", "fail_h", "solver")


def _flatten(tree, prefix="") -> dict:
    """Nested dicts and tuples of arrays as one flat dict: keys "a.b", "h.#0"."""
    if isinstance(tree, dict):
        out = {}
        for k, v in tree.items():
            out.update(_flatten(v, f"{prefix}{k}."))
        return out or {f"{prefix}{{}}": jnp.zeros(0)}
    if isinstance(tree, tuple):
        out = {}
        for i, v in enumerate(tree):
            out.update(_flatten(v, f"{prefix}#{i}."))
        return out or {f"{prefix}()": jnp.zeros(0)}
    if tree is None:
        return {f"{prefix}None": jnp.zeros(0)}
    return {prefix[:-1]: tree}


def _unflatten(flat: dict):
    root: dict = {}
    for key, value in flat.items():
        node = root
        parts = key.split(".")
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = value

    def build(node):
        if not isinstance(node, dict):
            return node
        if list(node) == ["{}"]:
            return {}
        if list(node) == ["()"]:
            return ()
        if list(node) == ["None"]:
            return None
        if node and all(k.startswith("#") for k in node):
            return tuple(build(node[f"#{i}"]) for i in range(len(node)))
        return {k: build(v) for k, v in node.items()}

    return build(root)


MAX_CYCLES = 1e12
"""A life's last cycle count when none is given (`Stop`)."""


class Stop(eqx.Module):
    """Where an integration ends: after ``cycles`` real cycles; when the peak
    depth of every joint has reached ``limit`` [m] (a life: each joint's
    crossing is recorded); at whichever comes first when both are given; and
    early when a joint's peak depth reaches its ``wall`` [m] (one per joint or
    one for all; none: no wall).  Without ``cycles`` a life ends at
    ``max_cycles`` at the latest, and one that ends there unreached ran out
    (`RESULTS.run_ended_early`), as one that reaches ``cycles`` >= ``max_cycles``.

    A ``limit`` of +inf is no limit and ``cycles = max_cycles`` none: a run
    and a life of the same model are then one program (traced values, one
    compile), ``Stop(cycles=N, limit=jnp.inf)`` and ``Stop(cycles=max_cycles,
    limit=L)``, with the numbers of ``Stop(cycles=N)`` and ``Stop(limit=L)``."""

    cycles: Any = None
    limit: Any = None
    wall: Any = None
    max_cycles: Any = MAX_CYCLES

    def __check_init__(self):
        if self.cycles is None and self.limit is None:
            raise ValueError("give cycles=, limit= or both")

    @property
    def has_limit(self):
        """Whether a limit ends the integration (a traced bool: +inf is none)."""
        if self.limit is None:
            return jnp.asarray(False)
        return jnp.isfinite(jnp.asarray(self.limit, dtype=float))

    @property
    def end(self):
        """The last cycle count: ``cycles``, or ``max_cycles`` without them."""
        return self.max_cycles if self.cycles is None else self.cycles

    @property
    def capped(self):
        """Whether the end is ``max_cycles`` (a traced bool)."""
        return (jnp.asarray(self.end, dtype=float)
                >= jnp.asarray(self.max_cycles, dtype=float))


class Proposal(NamedTuple):
    """One step as a solver proposes it; the engine accepts, cuts or rejects it.

    ``h``: the profiles after the step; ``dn``: its real cycles (0: a rejected
    try, the profile unchanged); ``ok``: every cycle it ran succeeded;
    ``memory``: the term's state after its cycles; ``load_sliding``: per
    joint, the step's int N ds [N m]; ``evaluations``: cycles run;
    ``solver``: its memory after the step; ``peak_rates``: per joint,
    d(peak)/dN at both ends of the step (a Hermite crossing; ``None``: the
    crossing is interpolated linearly)."""

    h: tuple
    dn: Any
    ok: Any
    memory: Any
    load_sliding: Any
    evaluations: Any
    solver: dict
    peak_rates: Any = None


class AbstractWearSolver(eqx.Module):
    """A rule that advances the profiles by one step (one slot of the scan)."""

    def peak(self, h) -> Float[Array, ""]:
        """The depth its steps, lives and walls are measured in: here the
        deepest grid value."""
        return jnp.max(h)

    @abc.abstractmethod
    def init(self, term: AbstractWearTerm, state: WearState, stop: Stop) -> WearState:
        """The solver's memory added to the initial state (it may run cycles)."""

    @abc.abstractmethod
    def step(self, term: AbstractWearTerm, state: WearState, stop: Stop) -> Proposal:
        """One step from ``state``."""

    def cut(self, term, state: WearState, proposal: Proposal, stop: Stop, peak):
        """The fraction of the step at which the first joint's peak depth meets
        its wall, and the profiles there.  Here the step is linear in its
        length (explicit steps): the exact fraction, min over rising nodes."""
        walls = per_joint(stop.wall, len(state.h))
        fractions = []
        for h0, h1, wall in zip(state.h, proposal.h, walls):
            dh = h1 - h0
            # double where: no infinite wall in the division (its gradient is NaN)
            room = jnp.where(jnp.isfinite(wall), wall - h0, 0.0)
            rising = dh > 0.0
            fractions.append(jnp.min(jnp.where(rising, room / jnp.where(rising, dh, 1.0),
                                               jnp.inf)))
        f = jnp.clip(jnp.min(jnp.stack(fractions)), 0.0, 1.0)
        return f, tuple(h0 + f * (h1 - h0) for h0, h1 in zip(state.h, proposal.h))

    def slots(self, stop: Stop, max_slots: int | None) -> int:
        """Scan slots the integration needs (static)."""
        from ..errors import InputError

        if max_slots is None:
            raise InputError(f"{type(self).__name__} needs a number of scan slots")
        if int(max_slots) < 1:
            raise InputError(f"scan slots must be >= 1, got {max_slots}")
        return int(max_slots)


def per_joint(value, joints: int) -> tuple:
    """``value`` (none: infinite; one for all; one per joint) as one scalar per joint."""
    if value is None:
        return (jnp.asarray(jnp.inf),) * joints
    v = jnp.broadcast_to(jnp.asarray(value, dtype=float), (joints,))
    return tuple(v[j] for j in range(joints))


def peaks(h: tuple, peak: Callable) -> Float[Array, " J"]:
    return jnp.stack([peak(x) for x in h])


# ----------------------------------------------------------------- the driver
class Integration(NamedTuple):
    """The end of an integration: its final `WearState` and per-slot history
    (``cycles``, ``max_depth`` per joint, ``step`` dN, ``valid``,
    ``evaluations``; ``depth`` and ``memory`` where kept)."""

    state: WearState
    history: dict


class Engine(eqx.Module):
    """One integration set up: ``term``, ``solver``, ``stop`` and ``slots``
    (``keep_profiles``, ``keep_memory``: the history holds every slot's
    profiles, the term's memory).
    `integrate` runs it in one scan; `init`, `run` and `finish` run it in
    pieces (chunks with checkpoints) with the same result.
    Build it inside a jitted function from traced leaves."""

    term: AbstractWearTerm
    solver: AbstractWearSolver
    stop: Stop
    slots: int = eqx.field(static=True, default=1)
    keep_profiles: bool = eqx.field(static=True, default=False)
    keep_memory: bool = eqx.field(static=True, default=False)

    @property
    def peak(self) -> Callable:
        return self.solver.peak

    def init(self, state: WearState) -> WearState:
        return self.solver.init(self.term, state, self.stop)

    def active(self, s: WearState):
        return ((s.status == RESULTS.ok) & ~jnp.all(s.done)
                & (s.n < jnp.asarray(self.stop.end, dtype=float) - 1e-9))

    def record(self, s: WearState, dn, valid) -> dict:
        """One history entry (one per slot)."""
        entry = dict(cycles=s.n, max_depth=peaks(s.h, self.peak), step=dn, valid=valid,
                     evaluations=s.evaluations)
        if self.keep_profiles:
            entry["depth"] = s.h
        if self.keep_memory:
            entry["memory"] = s.memory
        return entry

    def idle_record(self, s: WearState) -> dict:
        """The history entry of a slot after the end (what `run` records there)."""
        return self.record(s, jnp.zeros(()), jnp.array(False))

    def settle(self, s: WearState, p: Proposal) -> WearState:
        """Accept the proposal, cut it at a wall, or keep the old state."""
        joints = len(s.h)
        ok = p.ok & jnp.all(jnp.stack([jnp.all(jnp.isfinite(x)) for x in p.h]))
        h_new = tuple(jnp.where(d, h0, h1) for d, h0, h1 in zip(s.done, s.h, p.h))
        p = p._replace(h=h_new)
        m_old, m_new = peaks(s.h, self.peak), peaks(h_new, self.peak)
        walls = jnp.stack(per_joint(self.stop.wall, joints))
        pierced = ok & jnp.any(m_new >= walls)
        f, h_cut = lax.cond(
            pierced, lambda: self.solver.cut(self.term, s, p, self.stop, self.peak),
            lambda: (jnp.ones(()), h_new))
        h = tuple(jnp.where(ok, hc, h0) for hc, h0 in zip(h_cut, s.h))
        n = jnp.where(ok, s.n + f * p.dn, s.n)
        life, done = s.life, s.done
        if self.stop.limit is not None:
            # a limit of +inf (none: `Stop`) never crosses; double where, so
            # that the crossing's derivatives stay finite there
            given = self.stop.has_limit
            limit = jnp.where(given, jnp.asarray(self.stop.limit, dtype=float), 0.0)
            cross = given & ok & ~s.done & (m_new >= limit)
            if p.peak_rates is None:  # the peak depth linear over the step
                gain = jnp.where(cross, m_new - m_old, 1.0)
                n_cross = s.n + p.dn * (limit - m_old) / gain
            else:
                s0, s1 = p.peak_rates
                tau = jax.vmap(hermite_root, (0, 0, 0, 0, None, None))(
                    m_old, m_new, s0, s1, p.dn, limit)
                n_cross = s.n + tau * p.dn
            life = jnp.where(cross, n_cross, s.life)
            done = s.done | cross
        status = RESULTS.where(~ok, RESULTS.cycle_model_failed,
                               RESULTS.where(pierced, RESULTS.wall_reached, RESULTS.ok))

        def kept(new, old):  # a failed step keeps the last good state
            return jax.tree.map(lambda a, b: jnp.where(ok, a, b), new, old)

        return s.replace(
            h=h, memory=kept(p.memory, s.memory), n=n, status=status,
            evaluations=s.evaluations + p.evaluations, steps=s.steps + 1,
            load_sliding=kept(s.load_sliding + f * p.load_sliding, s.load_sliding),
            life=life, done=done,
            fail_n=jnp.where(~ok, s.n + p.dn, jnp.where(pierced, n, 0.0)),
            fail_h=jnp.where(~ok, jnp.max(m_new),
                             jnp.where(pierced, jnp.max(peaks(h, self.peak)), 0.0)),
            solver=kept(p.solver, s.solver))

    def slot(self, s: WearState, _):
        def do(s):
            p = self.solver.step(self.term, s, self.stop)
            return self.settle(s, p), jnp.asarray(p.dn, dtype=float)

        go = self.active(s)
        s2, dn = lax.cond(go, do, lambda s: (s, jnp.zeros(())), s)
        return s2, self.record(s2, dn, go & (dn > 0))

    def run(self, state: WearState, length: int):
        """``length`` slots from ``state``: (new state, history of these slots)."""
        # a closure: a Module holding traced leaves cannot be hashed as a bound method
        return lax.scan(lambda s, x: self.slot(s, x), state, None, length=int(length))

    def finish(self, final: WearState) -> WearState:
        """The final state, with `RESULTS.run_ended_early` where the slots ran
        out before the stop."""
        # ended short: neither every joint's limit nor the end reached, or
        # the end reached unlimited at max_cycles, a life's cap
        ended = final.n >= jnp.asarray(self.stop.end, dtype=float) - 1e-6
        short = ((final.status == RESULTS.ok) & ~jnp.all(final.done)
                 & (~ended | (self.stop.has_limit & self.stop.capped)))
        return final.replace(status=RESULTS.where(short, RESULTS.run_ended_early, final.status),
                             fail_n=jnp.where(short, final.n, final.fail_n),
                             fail_h=jnp.where(short, jnp.max(peaks(final.h, self.peak)),
                                              final.fail_h))


def integrate(term: AbstractWearTerm, solver: AbstractWearSolver, state: WearState, *,
              stop: Stop, slots: int, keep_profiles: bool = False,
              keep_memory: bool = False) -> Integration:
    """Integrate the profiles of ``state`` (`WearState.initial`) with ``term`` and
    ``solver`` until ``stop``, in ``slots`` scan slots.  Pure, jit-able and
    differentiable."""
    engine = Engine(term, solver, stop, slots=int(slots), keep_profiles=keep_profiles,
                    keep_memory=keep_memory)
    final, history = engine.run(engine.init(state), engine.slots)
    return Integration(engine.finish(final), history)


# ---------------------------------------------------------------- step pieces
def linearly_implicit_step(h, rate, response, dn):
    """The linearly implicit (Rosenbrock) Euler step of dh/dN = w(h):
    h + dN (I + dN A)^-1 w, with A = -dw/dh (``None``: the explicit step
    h + dN w)."""
    if response is None:
        return h + dn * rate
    eye = jnp.eye(h.shape[0], dtype=h.dtype)
    return h + dn * jnp.linalg.solve(eye + dn * response, rate)


_HERMITE_NEWTON = 8


def hermite_root(m0, m1, s0, s1, dn, target):
    """tau in [0, 1] where the cubic Hermite peak history on one step (values
    ``m0``, ``m1``, slopes ``s0``, ``s1`` per cycle, length ``dn``) equals
    ``target`` (m0 < target <= m1), by Newton from the linear interpolation."""
    gain = jnp.where(m1 > m0, m1 - m0, 1.0)
    tau0 = jnp.clip((target - m0) / gain, 0.0, 1.0)

    def value(tau):
        t2, t3 = tau * tau, tau * tau * tau
        return ((2 * t3 - 3 * t2 + 1) * m0 + (t3 - 2 * t2 + tau) * dn * s0
                + (-2 * t3 + 3 * t2) * m1 + (t3 - t2) * dn * s1)

    def newton(_, tau):
        f, df = jax.jvp(value, (tau,), (jnp.ones_like(tau),))
        ok = df > 0.0
        return jnp.clip(tau - jnp.where(ok, f - target, 0.0) / jnp.where(ok, df, 1.0), 0.0, 1.0)

    return lax.fori_loop(0, _HERMITE_NEWTON, newton, tau0)
