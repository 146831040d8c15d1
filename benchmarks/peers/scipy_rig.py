#!/usr/bin/env python3
"""A side-by-side peer: the Chapter 7 wear rig written plainly in NumPy/SciPy.

Not part of the package and imports nothing from it: a straightforward
engineer's implementation of the same model, so that diffwear's speed can be
compared at equal accuracy.  The model, term by term as diffwear
builds it (sources in the comments):

* slider-crank, thesis Table 7-1, lengths are half-lengths (thesis Eq. 2-9):
  crank pivot at the origin, crank COM at l1 (cos phi1, sin phi1), rod COM l2
  from either end, slider on the x axis; gravity -y (standard g); crank driven
  at pi rad/s (30 rpm); slider inertia 1 kg m^2 (not in the thesis; it cannot
  rotate, so its value changes nothing);
* slider spring 525.4 N/m (Table 7-3), free length 0.5479 m (calibrated by
  diffwear, presets.RIG_SPRING_FREE_LENGTH), ground anchor at x = 1 m;
* crank-rod joint: pin (crank) in a PTFE bushing (rod), Table 7-2: pin radius
  9.500 mm, bore 9.533 mm, outer radius 15.875 mm, depth 13.1 mm, mu 0.13,
  k = 5.05e-4 mm^3/(N m); elastic foundation model (thesis Ch. 6) on a 180-point
  grid with foundation stiffness E_W / wall, E_W the constrained modulus of
  PTFE (E 0.5 GPa, nu 0.38, Table 3-2); Kelvin-Voigt damping time from the
  restitution 0.8 (Table 3-3) with the half-circle contact stiffness and the rod
  mass; contact onset and no-tension clamps smoothed by a cubic ramp of width
  10 nm; friction mu F_N v / sqrt(v^2 + (1 mm/s)^2) per grid spring; Archard
  wear dh/dt = k p R_b |omega_rel| (|.| smoothed by 1e-3 rad/s) integrated as
  ODE states with the normal load x sliding distance;
* Baumgarte-stabilised index-1 DAE (alpha = beta = 250 1/s), solved through the
  Schur complement of the diagonal mass matrix;
* integrator: ``scipy.integrate.solve_ivp`` RK45 (Dormand-Prince 5(4), the same
  class of explicit embedded pair as diffwear's Tsit5) at rtol = atol = 1e-6 on
  the whole state (both use the RMS norm of error / (atol + rtol |y|));
* wear evolution: one warm-up cycle (wear discarded), then constant-A
  extrapolation h += A dh per dynamic cycle, the state carried over.

Run ``python benchmarks/peers/scipy_rig.py [--cycles N --dynamic D]`` for a
stand-alone timing; `benchmarks/run.py` (case ``scipy-peer``) cross-checks it
against diffwear.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from scipy.integrate import solve_ivp

# ---------------------------------------------------------------- data
G = 9.80665                                # m/s^2, standard gravity
OMEGA = math.pi                            # rad/s, 30 rpm (thesis)
PERIOD = 2 * math.pi / OMEGA               # s
L1, L2 = 0.0381, 0.1016                    # m, Table 7-1 half-lengths
M1, I1 = 0.4045, 204.0e-6                  # kg, kg m^2, crank (Table 7-1)
M2, I2 = 0.8175, 5500.0e-6                 # rod (Table 7-1)
M3, I3 = 8.5, 1.0                          # slider (Table 7-1; I3 arbitrary)
K_SPRING = 525.4                           # N/m, Table 7-3
L0_SPRING = 0.5479                         # m, diffwear's calibrated free length
ANCHOR_X = 1.0                             # m, spring anchor (diffwear's choice)
R_PIN = 9.500e-3                           # m, Table 7-2
R_BORE = 9.533e-3                          # m, Table 7-2
WALL = 15.875e-3 - R_BORE                  # m, outer minus inner bushing radius
DEPTH = 13.1e-3                            # m, bushing depth, Table 7-2
MU = 0.13                                  # Table 7-2
K_WEAR = 5.05e-4 * 1e-9                    # 1/Pa, Table 7-2 (mm^3/(N m) -> m^3/(N m))
E_PTFE, NU_PTFE = 0.5e9, 0.38              # Pa, Table 3-2
RESTITUTION = 0.8                          # Table 3-3
N_THETA = 180                              # bushing grid
W_PEN = 1e-8                               # m, contact-onset smoothing width
W_SLIP = 1e-3                              # m/s, friction sign smoothing
W_OMEGA = 1e-3                             # rad/s, |omega_rel| smoothing
ALPHA = BETA = 250.0                       # 1/s, Baumgarte (thesis Ch. 2-3)
RTOL = ATOL = 1e-6                         # diffwear's wear-cycle tolerances
RIG_CYCLES = 21_400                        # Table 7-3

E_W = (1 - NU_PTFE) * E_PTFE / ((1 + NU_PTFE) * (1 - 2 * NU_PTFE))  # constrained modulus
K_F = E_W / WALL                           # Pa/m, foundation stiffness
_k_contact = K_F * R_BORE * DEPTH * math.pi / 2   # N/m, half-circle contact
_zeta = -math.log(RESTITUTION) / math.sqrt(math.pi ** 2 + math.log(RESTITUTION) ** 2)
TAU = 2 * _zeta / math.sqrt(_k_contact / M2)     # s, Kelvin-Voigt damping time

MASS = np.array([M1, M1, I1, M2, M2, I2, M3, M3, I3])
MINV = 1.0 / MASS
THETA = 2 * np.pi * np.arange(N_THETA) / N_THETA
COS, SIN = np.cos(THETA), np.sin(THETA)
DTHETA = 2 * np.pi / N_THETA
AREA = R_BORE * DEPTH * DTHETA             # m^2 per grid spring
N_Q = 9
N_STATE = 2 * N_Q + N_THETA + 1            # q, qd, wear depth, int N ds


def ramp(x, w):
    """max(x, 0), C1 cubic blend over [0, w]."""
    return np.where(x <= 0.0, 0.0, np.where(x >= w, x, x * x * (2 * w - x) / (w * w)))


def step(x, w):
    """Heaviside(x), the derivative of `ramp`."""
    return np.where(x <= 0.0, 0.0, np.where(x >= w, 1.0, x * (4 * w - 3 * x) / (w * w)))


def rot(phi):
    c, s = math.cos(phi), math.sin(phi)
    return np.array([[c, -s], [s, c]])


# ---------------------------------------------------------------- model
class Rig:
    """The rig with a bushing clearance profile ``clearance`` (180 values, m)."""

    def __init__(self, clearance=None):
        self.clearance = (np.full(N_THETA, R_BORE - R_PIN) if clearance is None
                          else np.asarray(clearance, dtype=float))
        self.nfev = 0

    # constraints: ground-crank revolute (2), rod-slider revolute (2), slider
    # on the x axis (y3 = 0, phi3 = 0), driver phi1 = omega t  -> 7 rows
    @staticmethod
    def constraints(q, qd, t):
        """(Phi, Phi_q, Phi_t, gamma) of the 7 rows."""
        x1, y1, p1, x2, y2, p2, x3, y3, p3 = q
        c1, s1, c2, s2 = math.cos(p1), math.sin(p1), math.cos(p2), math.sin(p2)
        w1, w2 = qd[2], qd[5]
        phi = np.array([
            x1 - L1 * c1, y1 - L1 * s1,                  # crank point (-l1, 0) at the origin
            x2 + L2 * c2 - x3, y2 + L2 * s2 - y3,        # rod point (+l2, 0) at the slider
            y3, p3,                                      # slider guide
            p1 - OMEGA * t,                              # driver
        ])
        jac = np.zeros((7, 9))
        jac[0, 0] = jac[1, 1] = 1.0
        jac[0, 2], jac[1, 2] = L1 * s1, -L1 * c1
        jac[2, 3] = jac[3, 4] = 1.0
        jac[2, 5], jac[3, 5] = -L2 * s2, L2 * c2
        jac[2, 6] = jac[3, 7] = -1.0
        jac[4, 7] = jac[5, 8] = jac[6, 2] = 1.0
        phi_t = np.array([0, 0, 0, 0, 0, 0, -OMEGA])
        # gamma = -(Phi_q qd)_q qd (the rows are linear in t): A s phi_dot^2 per body point
        gamma = np.array([-L1 * c1 * w1 * w1, -L1 * s1 * w1 * w1,
                          L2 * c2 * w2 * w2, L2 * s2 * w2 * w2, 0, 0, 0])
        return phi, jac, phi_t, gamma

    def joint(self, q, qd):
        """EFM contact of the crank-rod joint: (force on the pin, global; moment
        on the pin; pin point; pressure p_k; normal load; sliding rate)."""
        a1, a2 = rot(q[2]), rot(q[5])
        s_pin, s_bush = np.array([L1, 0.0]), np.array([-L2, 0.0])
        arm1, arm2 = a1 @ s_pin, a2 @ s_bush
        pin, bush = q[0:2] + arm1, q[3:5] + arm2
        v_pin = qd[0:2] + qd[2] * np.array([-arm1[1], arm1[0]])
        v_bush = qd[3:5] + qd[5] * np.array([-arm2[1], arm2[0]])
        e, e_dot = pin - bush, v_pin - v_bush
        off = a2.T @ e                                     # in the bushing (rod) frame
        off_rate = a2.T @ (e_dot - qd[5] * np.array([-e[1], e[0]]))
        omega = qd[2] - qd[5]
        delta = COS * off[0] + SIN * off[1] - self.clearance
        rate = COS * off_rate[0] + SIN * off_rate[1]
        p = K_F * (ramp(delta, W_PEN) + TAU * rate * step(delta, W_PEN))
        p = ramp(p, K_F * W_PEN)                           # no tension
        load = p * AREA
        slip = -SIN * off_rate[0] + COS * off_rate[1] + R_PIN * omega
        f_t = -MU * slip / np.sqrt(slip * slip + W_SLIP * W_SLIP) * load
        f_local = np.array([-(load @ COS) - f_t @ SIN, -(load @ SIN) + f_t @ COS])
        torque = R_PIN * f_t.sum()
        slide = R_BORE * (math.sqrt(omega * omega + W_OMEGA * W_OMEGA) - W_OMEGA)
        return a2 @ f_local, torque, pin, p, load.sum(), slide

    def rhs(self, t, y):
        """dy/dt for y = [q, qd, h (180), int N ds]."""
        self.nfev += 1
        q, qd = y[:N_Q], y[N_Q:2 * N_Q]
        force = np.array([0.0, -M1 * G, 0.0, 0.0, -M2 * G, 0.0, 0.0, -M3 * G, 0.0])
        # slider spring: ground anchor (1, 0) to the slider centre, tension pulls them together
        d = np.array([q[6] - ANCHOR_X, q[7]])
        length = math.sqrt(d @ d + 1e-24)
        force[6:8] -= K_SPRING * (length - L0_SPRING) * d / length
        f, torque, at, p, load, slide = self.joint(q, qd)
        r1, r2 = at - q[0:2], at - q[3:5]
        force[0:3] += (f[0], f[1], r1[0] * f[1] - r1[1] * f[0] + torque)
        force[3:6] -= (f[0], f[1], r2[0] * f[1] - r2[1] * f[0] + torque)
        phi, jac, phi_t, gamma = self.constraints(q, qd, t)
        rhs = gamma - 2 * ALPHA * (jac @ qd + phi_t) - BETA * BETA * phi
        jm = jac * MINV
        lam = np.linalg.solve(jm @ jac.T, jm @ force - rhs)
        qdd = MINV * (force - jac.T @ lam)
        out = np.empty(N_STATE)
        out[:N_Q], out[N_Q:2 * N_Q] = qd, qdd
        out[2 * N_Q:2 * N_Q + N_THETA] = K_WEAR * p * slide
        out[-1] = load * slide
        return out

    def joint_force(self, ys):
        """|force| of the joint at each row of ``ys`` [N]."""
        return np.array([math.hypot(*self.joint(y[:N_Q], y[N_Q:2 * N_Q])[0]) for y in ys])


def initial_state() -> np.ndarray:
    """Consistent state at t = 0 (phi1 = 0: everything on the x axis), pin centred."""
    y = np.zeros(N_STATE)
    y[:N_Q] = [L1, 0, 0, 2 * L1 + L2, 0, 0, 2 * L1 + 2 * L2, 0, 0]
    w2 = -OMEGA * L1 / L2                       # slider end has no y velocity
    y[N_Q:2 * N_Q] = [0, OMEGA * L1, OMEGA, 0, OMEGA * L1, w2, 0, 0, 0]
    return y


# ---------------------------------------------------------------- cycles
def wear_cycle(rig: Rig, y, t0, *, t_eval=None, rtol=RTOL, atol=ATOL):
    """One crank cycle from ``y`` at ``t0`` (wear states reset): the solve_ivp result."""
    y = np.array(y, dtype=float)
    y[2 * N_Q:] = 0.0
    sol = solve_ivp(rig.rhs, (t0, t0 + PERIOD), y, method="RK45", rtol=rtol, atol=atol,
                    t_eval=t_eval)
    if sol.status != 0:
        raise RuntimeError(f"scipy peer: solve_ivp failed: {sol.message}")
    return sol


def evolve(cycles: float, dynamic: int, *, log=None) -> dict:
    """Warm-up + ``dynamic`` wear cycles with constant A = cycles / dynamic."""
    a = cycles / dynamic
    h = np.zeros(N_THETA)
    c0 = R_BORE - R_PIN
    y, t = initial_state(), 0.0
    stats = {"accepted_steps": 0, "nfev": 0, "cycle_s": []}
    for i in range(dynamic + 1):
        rig = Rig(c0 + h)
        t_start = time.perf_counter()
        sol = wear_cycle(rig, y, t)
        stats["cycle_s"].append(time.perf_counter() - t_start)
        stats["accepted_steps"] += sol.t.size - 1
        stats["nfev"] += sol.nfev
        y, t = sol.y[:, -1], t + PERIOD
        if i > 0:  # the warm-up's wear is discarded
            h = h + a * y[2 * N_Q:2 * N_Q + N_THETA]
        if log:
            log(f"  cycle {i}: {stats['cycle_s'][-1]:.2f} s, {sol.t.size - 1} steps")
    volume = DEPTH * R_BORE * DTHETA * h.sum()
    return {"depth": h, "max_depth_mm": h.max() * 1e3, "volume_mm3": volume * 1e9,
            "dynamic_cycles": dynamic + 1, "y": y, **stats}


def time_rhs(n: int = 2000) -> float:
    """Seconds per RHS evaluation at a state in contact (after one cycle)."""
    rig = Rig()
    y = wear_cycle(rig, initial_state(), 0.0).y[:, -1]
    t0 = time.perf_counter()
    for _ in range(n):
        rig.rhs(0.3, y)
    return (time.perf_counter() - t0) / n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=float, default=RIG_CYCLES)
    ap.add_argument("--dynamic", type=int, default=10)
    args = ap.parse_args()
    t0 = time.perf_counter()
    r = evolve(args.cycles, args.dynamic, log=print)
    wall = time.perf_counter() - t0
    print(f"{args.cycles:g} cycles, A = {args.cycles / args.dynamic:g}: max depth "
          f"{r['max_depth_mm']:.4f} mm, volume {r['volume_mm3']:.2f} mm^3; {wall:.1f} s, "
          f"{r['accepted_steps'] / r['dynamic_cycles']:.0f} accepted steps per cycle, "
          f"{time_rhs() * 1e6:.0f} us per RHS")


if __name__ == "__main__":
    main()
