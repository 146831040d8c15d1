"""Where a rig wear cycle's time goes: steps, time per step and per
right-hand-side call, the XLA program of one call, the contact's explicit
stability floor; the per-call timers are shared with the peer cases."""

from __future__ import annotations

import math

from harness import time_jitted

# Stability boundary of Tsit5 / Dormand-Prince 5(4) along the negative real axis
# (Hairer & Wanner, Solving ODEs II, Fig. IV.2.1: ~3.3; the imaginary-axis
# extent is similar): an explicit step needs dt <= 3.3 / |lambda|.
EXPLICIT_STABILITY_RADIUS = 3.3


def rig_profile(repeats: int) -> dict:
    """Where a rig wear cycle's time goes (one cycle after the warm-up, the
    wear-cycle settings: Tsit5, PID 0.3/0.4, rtol = atol = 1e-6): accepted and
    rejected steps, time per step and per `vector_field` call, the share of the
    time spent in the RHS (6 calls per Tsit5 step), the EFM contact frequency
    sqrt(k_contact / m) / 2 pi (k_contact: half-circle EFM stiffness; m: the
    rod mass, diffwear's damping mass), and the explicit-stability floor on the
    steps: the largest |eigenvalue| of d(vector_field)/dy at 73 states over the
    cycle, integrated as sum |lambda_max| dt / 3.3."""
    import diffrax
    import jax
    import numpy as np

    from diffwear.dynamics import simulate
    from diffwear.dynamics.equations import Baumgarte, vector_field
    from diffwear.studies import _wear_common as common
    from diffwear.studies.rig_21400 import PERIOD, _setup
    from diffwear.wear.cycle import CYCLE_ATOL, CYCLE_RTOL

    mech0, mech, y0 = _setup()
    ctrl = diffrax.PIDController(rtol=CYCLE_RTOL, atol=CYCLE_ATOL, pcoeff=0.3, icoeff=0.4)
    n_save = 73
    fn = jax.jit(lambda m, y, t0: simulate(
        m, y, t0 + PERIOD, t0=t0, ts=t0 + PERIOD * jax.numpy.linspace(0.0, 1.0, n_save),
        stepsize_controller=ctrl))
    warm = fn(mech, y0, 0.0)
    traj, m = time_jitted(fn, (mech, warm.y_final, PERIOD), repeats)
    traj.raise_if_failed("benchmark rig profile", mech)
    steps = int(traj.num_steps)
    acc, rej = int(traj.num_accepted_steps), int(traj.num_rejected_steps)
    us_rhs = rhs_us(mech, traj.y_final)

    jac = jax.jit(jax.vmap(jax.jacfwd(lambda t, y: vector_field(t, y, (mech, Baumgarte())),
                                      argnums=1)))(traj.ts, traj.ys)
    lam_max = np.array([np.abs(np.linalg.eigvals(j)).max() for j in np.asarray(jac)])
    dt = PERIOD / (n_save - 1)
    floor_steps = float(np.sum(0.5 * (lam_max[1:] + lam_max[:-1])) * dt
                        / EXPLICIT_STABILITY_RADIUS)
    el = mech.element(common.JOINT)
    k_c = float(el.law.contact_stiffness(el.bushing_radius))
    m_rod = float(next(b.mass for b in mech.bodies if b.name == "rod"))
    q, qd, _ = mech.split(traj.y_final)
    y_ideal = mech0.join(q, qd)  # the same motion without the clearance joint
    us_rhs_ideal = rhs_us(mech0, y_ideal)
    us_loop = loop_us_per_step(traj.y_final.size, steps)
    return {
        "simulated_s": PERIOD, **m, "integrator_steps": steps, "accepted_steps": acc,
        "rejected_steps": rej, "us_per_step": m["run_s"] / steps * 1e6,
        "us_per_rhs": us_rhs, "rhs_share": 6 * steps * us_rhs * 1e-6 / m["run_s"],
        "us_per_rhs_ideal_mechanism": us_rhs_ideal,
        "us_per_rhs_contact_and_wear": us_rhs - us_rhs_ideal,
        "us_per_step_loop_only": us_loop,
        "xla_rhs": hlo_kernels(mech, traj.y_final),
        "xla_rhs_ideal_mechanism": hlo_kernels(mech0, y_ideal),
        "contact_stiffness_N_per_m": k_c,
        "contact_frequency_Hz": math.sqrt(k_c / m_rod) / (2 * math.pi),
        "dt_stable_contact_s": EXPLICIT_STABILITY_RADIUS / math.sqrt(k_c / m_rod),
        "steps_floor_contact_formula": PERIOD * math.sqrt(k_c / m_rod) / EXPLICIT_STABILITY_RADIUS,
        "lambda_max_over_cycle": [float(lam_max.min()), float(np.median(lam_max)),
                                  float(lam_max.max())],
        "steps_floor_eigenvalues": floor_steps,
        "accepted_over_floor": acc / floor_steps,
        "repeats": repeats,
    }


def rhs_us(mech, y, t=0.3, n: int = 2000, reps: int = 5) -> float:
    """Microseconds per `vector_field` evaluation of ``mech`` at ``y``: ``n``
    calls chained inside one jitted fori_loop (no dispatch cost), median of
    ``reps`` timed calls."""
    import jax
    import jax.numpy as jnp

    from diffwear.dynamics.equations import Baumgarte, vector_field

    args = (mech, Baumgarte())

    @jax.jit
    def loop(y):  # each call depends on the last, so none is hoisted or skipped
        return jax.lax.fori_loop(0, n, lambda i, acc: acc + 1e-300 * vector_field(t, acc, args), y)

    _, m = time_jitted(loop, (jnp.asarray(y),), reps)
    return m["run_s"] / n * 1e6


def loop_us_per_step(size: int, steps: int, reps: int = 5) -> float:
    """Microseconds per step of diffrax's loop alone: Tsit5 with the wear
    cycles' PID controller (rtol = atol = 1e-6) on a trivial right-hand side
    (-y) of ``size`` states, run for ``steps`` steps (the rest of a real step
    is its six right-hand-side calls)."""
    import diffrax
    import jax
    import jax.numpy as jnp

    term = diffrax.ODETerm(lambda t, y, args: -y)
    ctrl = diffrax.PIDController(rtol=1e-6, atol=1e-6, pcoeff=0.3, icoeff=0.4,
                                 dtmin=1e-12, dtmax=1e-3)
    # -y is smooth: the controller's step grows to dtmax and stays there, so
    # the run takes ``steps`` steps of 1e-3 s
    fn = jax.jit(lambda y: diffrax.diffeqsolve(term, diffrax.Tsit5(), 0.0, steps * 1e-3, 1e-3,
                                               y, stepsize_controller=ctrl,
                                               max_steps=steps + 16))
    sol, m = time_jitted(fn, (jnp.ones(size),), reps)
    return m["run_s"] / int(sol.stats["num_steps"]) * 1e6


def hlo_kernels(mech, y, t: float = 0.3) -> dict:
    """The optimised XLA program of one `vector_field` call: its kernels (the
    entry computation's fusions, dots and library calls, each one dispatch
    of the CPU runtime) and all its instructions (fused ones included)."""
    import re

    import jax
    import jax.numpy as jnp

    from diffwear.dynamics.equations import Baumgarte, vector_field

    text = jax.jit(vector_field).lower(jnp.asarray(t), jnp.asarray(y),
                                       (mech, Baumgarte())).compile().as_text()
    entry = next(c for c in re.split(r"\n(?=\S)", text) if c.startswith("ENTRY"))
    ops = re.findall(r"= \S+ ([a-z][\w-]*)\(", entry)
    free = {"parameter", "constant", "get-tuple-element", "tuple", "bitcast"}
    return {"kernels": sum(op not in free for op in ops),
            "library_calls": ops.count("custom-call"),
            "instructions": sum(" = " in line for line in text.splitlines())}
