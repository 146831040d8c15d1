"""Kinematic analysis: positions, velocities, accelerations from the constraints.

Positions: Newton's method (optimistix) on the first-order conditions of

    min_q  1/2 |q - q_guess|_M^2   subject to  Phi(q, t) = 0,

i.e. the square root-finding problem  [M (q - q_guess) + Phi_q^T mu ; Phi] = 0.
For a fully driven mechanism (as many independent rows as coordinates) this is
plain Newton on Phi = 0; for a mechanism with free coordinates (e.g. one with
a clearance joint) it is the consistent configuration nearest the guess.  The
root find is differentiated implicitly, so `assemble` is differentiable with
respect to lengths and other parameters.

Velocities and accelerations are the M-weighted least-norm solutions of
Phi_q qd = -Phi_t (closest to a guess) and Phi_q qdd = gamma; for a fully
driven mechanism these are the unique solutions.
"""

from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from ..errors import InputError
from ..mechanism import Mechanism


def _projection(mech: Mechanism, q, t, v, target):
    """v + dv with Phi_q (v + dv) = target, |dv|_M minimal."""
    minv = 1.0 / mech.mass_diagonal()
    jac = mech.phi_q(q, t)
    jm = jac * minv
    mu = jnp.linalg.solve(jm @ jac.T, jac @ v - target)
    return v - jm.T @ mu


def _kkt(z, inputs):
    """The first-order conditions [M (q - q_guess) + Phi_q^T mu ; Phi] of
    `assemble` at z = [q, mu], ``inputs`` = (mech, q_guess, t)."""
    mech, q_guess, t = inputs
    mdiag = mech.mass_diagonal()
    q, mu = z[: mech.n_coords], z[mech.n_coords :]
    jac = mech.phi_q(q, t)
    return jnp.concatenate([(mdiag / jnp.mean(mdiag)) * (q - q_guess) + jac.T @ mu, mech.phi(q, t)])


@eqx.filter_custom_jvp
def _at_root(root, inputs):
    """``root``, a zero of `_kkt` at ``inputs``, differentiated implicitly
    (`assemble`)."""
    return root


@_at_root.def_jvp
def _at_root_jvp(primals, tangents):
    root, inputs = primals
    _, t_inputs = tangents
    dynamic, static = eqx.partition(inputs, eqx.is_inexact_array)
    t_dynamic = jax.tree_util.tree_map(
        lambda x, t: None if x is None else (jnp.zeros_like(x) if t is None else t),
        dynamic, t_inputs, is_leaf=lambda x: x is None)
    _, d_kkt = jax.jvp(lambda d: _kkt(root, eqx.combine(d, static)), (dynamic,), (t_dynamic,))
    # dz = -J^-1 dF: NaN, not an error, where J is singular or dF is NaN
    return root, -jnp.linalg.solve(jax.jacfwd(_kkt)(root, inputs), d_kkt)


def assemble(mech: Mechanism, q_guess, t=0.0, *, tol=1e-12, max_steps=64):
    """Configuration q with Phi(q, t) = 0 closest (M-norm) to ``q_guess``.

    Returns ``(q, converged)``; `check_assembly` raises a clear error for an
    unusable result.  Jit- and grad-safe: the root is found on the inputs with
    their derivatives stopped, and differentiated by the implicit function
    theorem (dz = -J^-1 dF, `_at_root`) with a plain linear solve.  A failed
    evaluation (a NaN flowing back from a model that could not be evaluated,
    a singular Jacobian) then gives a NaN derivative that the caller can see,
    where the root finder's own implicit derivative would stop the whole
    program in its linear solve.
    """
    q_guess = jnp.asarray(q_guess, dtype=float)
    t = jnp.asarray(t, dtype=q_guess.dtype)
    m = mech.n_constraints
    if m == 0:
        return q_guess, jnp.array(True)
    inputs = (mech, q_guess, t)
    dynamic, static = eqx.partition(inputs, eqx.is_inexact_array)
    frozen = eqx.combine(jax.lax.stop_gradient(dynamic), static)
    z0 = jnp.concatenate([jax.lax.stop_gradient(q_guess), jnp.zeros(m, dtype=q_guess.dtype)])
    sol: optx.Solution = optx.root_find(
        _kkt, optx.Newton(rtol=tol, atol=tol), z0, args=frozen, max_steps=max_steps, throw=False
    )
    q = _at_root(sol.value, inputs)[: mech.n_coords]
    ok = (sol.result == optx.RESULTS.successful) & jnp.all(jnp.isfinite(q))
    return q, ok


def velocities(mech: Mechanism, q, t=0.0, qd_guess=None):
    """qd with Phi_q qd + Phi_t = 0 closest (M-norm) to ``qd_guess`` (default 0)."""
    t = jnp.asarray(t, dtype=q.dtype)
    v = jnp.zeros_like(q) if qd_guess is None else qd_guess
    if mech.n_constraints == 0:
        return v
    return _projection(mech, q, t, v, -mech.phi_t(q, t))


def kinematic_accelerations(mech: Mechanism, q, qd, t=0.0):
    """qdd with Phi_q qdd = gamma (least M-norm: unique when fully driven)."""
    t = jnp.asarray(t, dtype=q.dtype)
    return _projection(mech, q, t, jnp.zeros_like(q), mech.gamma(q, qd, t))


def check_assembly(mech: Mechanism, q, ok, t=0.0, *, q_guess=None, rank_tol=1e-9) -> None:
    """Raise `InputError` if the configuration does not assemble or the
    constraint Jacobian is rank deficient (redundant or inconsistent rows).
    Call with concrete values, outside ``jit``.

    When Newton's method failed, ``q`` may be NaN (redundant rows make its
    matrix singular) or far off; ``q_guess`` then tells the two causes apart:
    a Jacobian that is singular at a generic configuration (a random
    perturbation of the guess) means redundant constraints, anything else means
    the geometry does not close.
    """
    if mech.n_constraints == 0:
        return
    q = np.asarray(q, dtype=float)
    t = jnp.asarray(t, dtype=float)
    finite = bool(np.all(np.isfinite(q)))
    resid = float(np.max(np.abs(np.asarray(mech.phi(jnp.asarray(q), t))))) if finite else np.nan
    assembled = bool(ok) and finite and resid <= 1e-8
    if assembled:
        _raise_if_singular(mech, q, t, rank_tol)
        return
    if q_guess is not None:
        q_guess = np.asarray(q_guess, dtype=float)
        generic = q_guess + 0.1 * np.random.default_rng(0).standard_normal(q_guess.shape)
        _raise_if_singular(mech, generic, t, rank_tol)
    found = f"with max |Phi| = {resid:.3g}" if finite else "at a non-finite configuration"
    raise InputError(
        f"the mechanism cannot be assembled at t = {float(t)} s: Newton's method ended "
        f"{found} (check lengths, joint points and the initial guess)"
    )


def _raise_if_singular(mech: Mechanism, q, t, rank_tol) -> None:
    jac = np.asarray(mech.phi_q(jnp.asarray(q, dtype=float), t))
    u, s, _ = np.linalg.svd(jac)
    m = jac.shape[0]
    rank = int(np.sum(s > rank_tol * max(s.max(), 1.0)))
    if rank < m:
        null = u[:, rank:]  # row combinations w with w^T Phi_q = 0
        weights = np.abs(null).max(axis=1)
        rows = [i for i in range(m) if weights[i] > 1e-6]
        owners = _row_owners(mech)
        involved = sorted({owners[i] for i in rows})
        raise InputError(
            f"constraint Jacobian is singular: {m} rows but rank {rank} "
            f"(redundant or inconsistent constraints among {involved})"
        )


def _row_owners(mech: Mechanism) -> list[str]:
    return [c.name for c in mech.constraints for _ in range(c.n_rows)]


def consistent_state(mech: Mechanism, q_guess, qd_guess=None, t0=0.0, *, check=True):
    """y0 = [q, qd, aux0] satisfying Phi = 0 and Phidot = 0 at ``t0``.

    ``check=True`` validates the assembly (concrete inputs only); pass
    ``check=False`` inside a traced function.
    """
    q, ok = assemble(mech, q_guess, t0)
    if check:
        check_assembly(mech, q, ok, t0, q_guess=q_guess)
    qd = velocities(mech, q, t0, qd_guess)
    return mech.join(q, qd, mech.initial_aux(q, qd))


def kinematic_analysis(mech: Mechanism, ts, q_guess):
    """(q, qd, qdd) at each time of ``ts`` for a fully driven mechanism.

    A ``lax.scan`` over ``ts``; each position solve starts from the previous one.
    """
    ts = jnp.asarray(ts, dtype=float)

    def step(q_prev, t):
        q, _ = assemble(mech, q_prev, t)
        qd = velocities(mech, q, t)
        return q, (q, qd, kinematic_accelerations(mech, q, qd, t))

    _, (q, qd, qdd) = jax.lax.scan(step, jnp.asarray(q_guess, dtype=float), ts)
    return q, qd, qdd


# A sample of the cycle is "closed" when every constraint holds to this [m or
# rad] (Newton converges quadratically to ~1e-15 where a solution exists), and
# a dead point when the constraint Jacobian's smallest singular value falls
# below this fraction of its largest (the driver cannot carry the linkage
# through it).
_CLOSED = 1e-8
_DEAD_POINT = 1e-7
_phi = eqx.filter_jit(lambda mech, q, t: mech.phi(q, t))
_phi_q = eqx.filter_jit(lambda mech, q, t: mech.phi_q(q, t))


def check_cycle_motion(mech: Mechanism, q0, ts, *, what: str = "the mechanism",
                       driver: str = "the driver") -> None:
    """Raise `InputError` if the fully driven ``mech`` cannot move through the
    times ``ts`` from the assembled ``q0``: a sample where its joints cannot
    all be closed (a link too short to reach, a crank that cannot turn fully)
    or where the constraint Jacobian is singular (a dead point).  Each sample's
    Newton starts from the previous one; concrete values, outside ``jit``."""
    phi = functools.partial(_phi, mech)
    phi_q = functools.partial(_phi_q, mech)
    q = np.asarray(q0, dtype=float)
    ts = np.asarray(ts, dtype=float)
    period = ts[-1] - ts[0]
    for t in ts:
        for _ in range(30):
            r = np.asarray(phi(q, t))
            if not np.all(np.isfinite(r)) or np.max(np.abs(r)) <= _CLOSED:
                break
            step = np.linalg.lstsq(np.asarray(phi_q(q, t)), r, rcond=None)[0]
            q = q - step
        r = np.asarray(phi(q, t))
        where = (f"at t = {t:.4g} s ({driver} at {360.0 * (t - ts[0]) / period:.0f} deg "
                 "of its cycle)")
        worst = float(np.max(np.abs(r))) if np.all(np.isfinite(r)) else np.inf
        if worst > _CLOSED:
            raise InputError(
                f"{what} cannot move through its cycle: {where} its joints cannot all be "
                f"closed (max |Phi| = {worst:.3g}): a link too short to reach (e.g. a rod "
                "shorter than the crank) or a crank that cannot turn fully; clearance joints "
                "count as ideal revolute joints in this check")
        sv = np.linalg.svd(np.asarray(phi_q(q, t)), compute_uv=False)
        if sv[-1] < _DEAD_POINT * sv[0]:
            raise InputError(
                f"{what} locks: {where} the constraint Jacobian is singular (a dead point "
                "the driver cannot carry the linkage through, e.g. links that fold onto "
                "one line); clearance joints count as ideal revolute joints in this check")

