#!/usr/bin/env python3
"""An Exudyn peer: the thesis Table 2-1 ideal slider-crank in Exudyn 1.13.

Run it where the project's ``bench`` extra installed exudyn (it imports
nothing from diffwear):

    pip install -e ".[bench]"
    python benchmarks/peers/exudyn_slider_crank.py [--step 5e-4]

It prints one JSON object on stdout.  `benchmarks/run.py` (case
``exudyn-peer``) runs it as a subprocess and compares it with diffwear.

The model, as diffwear's `presets.slider_crank(TABLE_2_1)` builds it:

* lengths are half-lengths (thesis Eq. 2-9): l1 = 1 m, l2 = 1.75 m; crank
  pivot at the origin, crank COM at l1 (cos phi1, sin phi1), the rod COM l2
  from either end, the slider on the global x axis;
* masses 10 / 15 / 30 kg, inertias 45 / 35 / 1 kg m^2 (the slider's is not in
  the thesis and changes nothing: it cannot rotate); gravity -y, 9.80665 m/s^2;
* Exudyn items: three `ObjectRigidBody2D` (node `NodeRigidBody2D`, coordinates
  x, y, phi of the COM), `ObjectJointRevolute2D` ground-crank, crank-rod and
  rod-slider, `ObjectJointPrismatic2D` (with `constrainRotation`) slider-ground,
  gravity by `LoadMassProportional`;
* driver phi1 = pi t: an `ObjectConnectorCoordinate` on the crank's phi
  coordinate.  Default ``--driver velocity``: the velocity-level form
  phi1_dot = pi (with phi1(0) = 0 the same motion; no Python callback, so the
  timing is Exudyn's C++ alone).  ``--driver position``: phi1 = pi t through an
  ``offsetUserFunction`` (a Python callback per evaluation);
* start at phi1 = 0 (everything on the x axis) with consistent velocities;
* solver: Exudyn's implicit generalized-alpha (index 3, its default for
  constrained systems), fixed step ``--step``, spectral radius ``--rho``
  (Exudyn's default 0.9), Newton tolerances Exudyn's defaults.

``--kv-stiffness K``: the crank-rod revolute becomes a clearance joint
(``--clearance``, default 0.5 mm; `KVJoint`: diffwear's Kelvin-Voigt point law
with Coulomb friction, mu 0.13, e_r 0.8, pin radius 20 mm) applied as four
loads (force and moment on crank and rod) with Python user functions that read
the current Newton iterate; the joint force is then recomputed from the
recorded body states.

Outputs (sampled every ``--sample`` s): slider x, slider x-velocity, the
crank-rod joint reaction force (|.| of the Lagrange multiplier force of the
revolute joint, global frame), the driver torque (the multiplier of the
coordinate constraint), and the wall time of model building (items +
``Assemble``) and of the solve separately.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (
    LoadMassProportional,
    MarkerBodyMass,
    MarkerBodyPosition,
    MarkerBodyRigid,
    MarkerNodeCoordinate,
    NodePointGround,
    NodeRigidBody2D,
    ObjectConnectorCoordinate,
    ObjectGround,
    ObjectJointPrismatic2D,
    ObjectJointRevolute2D,
    ObjectRigidBody2D,
    SensorNode,
    SensorObject,
)

G = 9.80665                       # m/s^2
OMEGA = math.pi                   # rad/s (30 rpm)
L1, L2 = 1.00, 1.75               # m, Table 2-1 half-lengths
M1, I1 = 10.0, 45.0               # crank
M2, I2 = 15.0, 35.0               # rod
M3, I3 = 30.0, 1.0                # slider (I3 not in the thesis, arbitrary)
DURATION = 2.0                    # s, one revolution
# node reference coordinates (x, y, phi) of the COMs at phi1 = 0; Exudyn's node
# "Coordinates" output is the displacement from these
REFERENCE = {"crank": (L1, 0.0, 0.0), "rod": (2 * L1 + L2, 0.0, 0.0),
             "slider": (2 * L1 + 2 * L2, 0.0, 0.0)}


class KVJoint:
    """Crank-rod clearance joint as diffwear's point-contact ``KelvinVoigt`` law
    with `CoulombFriction` (contact/laws.py, contact/friction.py), written out:
    pin (crank point (+l1, 0)) in a bushing (rod point (-l2, 0)), e = pin -
    bushing centre, n = e / |e| (|e| smoothed by 1e-12 m), delta = |e| - c,
    delta_dot = e_dot . n, slip = e_dot . t - omega_rod |e| + R_pin (omega_crank
    - omega_rod) with t = perp(n);
    F_N = K ramp(delta, 1e-8 m) (e_r + (1 - e_r) (1 + sign(delta_dot, 1 mm/s)) / 2),
    F_t = -mu sign(slip, 1 mm/s) F_N; force on the pin -F_N n + F_t t at the pin
    centre plus the moment R_pin F_t; the rod gets the opposite at the same point.
    (smoothed sign(x, w) = x / sqrt(x^2 + w^2); ramp: cubic blend over [0, w].)"""

    def __init__(self, stiffness, clearance, pin_radius=0.020, mu=0.13, restitution=0.8,
                 rebound_width=1e-3, slip_width=1e-3, penetration_width=1e-8):
        self.k, self.c, self.r_pin, self.mu, self.e_r = (stiffness, clearance, pin_radius, mu,
                                                          restitution)
        self.w_rebound, self.w_slip, self.w_pen = rebound_width, slip_width, penetration_width

    @staticmethod
    def _sign(x, w):
        return x / math.sqrt(x * x + w * w)

    def _ramp(self, x):
        w = self.w_pen
        return 0.0 if x <= 0.0 else (x if x >= w else x * x * (2 * w - x) / (w * w))

    def evaluate(self, q1, v1, q2, v2):
        """(force on the pin [2], moment on the pin, pin point [2]) from the crank
        (q1, v1) and rod (q2, v2) COM coordinates (x, y, phi) and their rates."""
        c1, s1, c2, s2 = math.cos(q1[2]), math.sin(q1[2]), math.cos(q2[2]), math.sin(q2[2])
        pin = (q1[0] + L1 * c1, q1[1] + L1 * s1)
        bush = (q2[0] - L2 * c2, q2[1] - L2 * s2)
        v_pin = (v1[0] - v1[2] * L1 * s1, v1[1] + v1[2] * L1 * c1)
        v_bush = (v2[0] + v2[2] * L2 * s2, v2[1] - v2[2] * L2 * c2)  # arm (-l2 c2, -l2 s2)
        ex, ey = pin[0] - bush[0], pin[1] - bush[1]
        dx, dy = v_pin[0] - v_bush[0], v_pin[1] - v_bush[1]
        dist = math.sqrt(ex * ex + ey * ey + 1e-24)
        nx, ny = ex / dist, ey / dist
        tx, ty = -ny, nx
        delta_dot = dx * nx + dy * ny
        loading = 0.5 * (1.0 + self._sign(delta_dot, self.w_rebound))
        f_n = self.k * self._ramp(dist - self.c) * (self.e_r + (1.0 - self.e_r) * loading)
        slip = dx * tx + dy * ty - v2[2] * dist + self.r_pin * (v1[2] - v2[2])
        f_t = -self.mu * self._sign(slip, self.w_slip) * f_n
        return (-f_n * nx + f_t * tx, -f_n * ny + f_t * ty), self.r_pin * f_t, pin


def build(driver: str = "velocity", joint: KVJoint | None = None):
    """(SystemContainer, mbs, sensors dict) of the assembled slider-crank; with
    ``joint`` the crank-rod revolute is replaced by that clearance joint (loads
    with Python user functions)."""
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground = mbs.AddObject(ObjectGround(referencePosition=[0, 0, 0]))
    m_ground = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))

    w2 = -OMEGA * L1 / L2                 # rod angular velocity at t = 0
    # (COM position, angle), (COM velocity, angular velocity) at phi1 = 0
    init = {
        "crank": (REFERENCE["crank"], [0, OMEGA * L1, OMEGA], M1, I1),
        "rod": (REFERENCE["rod"], [0, OMEGA * L1, w2], M2, I2),
        "slider": (REFERENCE["slider"], [0, 0, 0], M3, I3),
    }
    nodes, bodies = {}, {}
    for name, (q0, v0, m, inertia) in init.items():
        n = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=q0, initialVelocities=v0))
        b = mbs.AddObject(ObjectRigidBody2D(nodeNumber=n, mass=m, inertia=inertia))
        mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=b)),
                                         loadVector=[0, -G, 0]))
        nodes[name], bodies[name] = n, b

    def pos(body, x):
        return mbs.AddMarker(MarkerBodyPosition(bodyNumber=bodies[body], localPosition=[x, 0, 0]))

    m_g0 = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0, 0, 0]))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[m_g0, pos("crank", -L1)]))
    if joint is None:
        j_crank_rod = mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[pos("crank", L1),
                                                                         pos("rod", -L2)]))
    else:
        j_crank_rod = None
        add_clearance_loads(mbs, nodes, bodies, joint)
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[pos("rod", L2), pos("slider", 0.0)]))
    m_slider = mbs.AddMarker(MarkerBodyRigid(bodyNumber=bodies["slider"], localPosition=[0, 0, 0]))
    mbs.AddObject(ObjectJointPrismatic2D(markerNumbers=[m_ground, m_slider], axisMarker0=[1, 0, 0],
                                         normalMarker1=[0, 1, 0], constrainRotation=True))

    # driver on the crank angle: q(phi1) - q(ground) = offset
    n_ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    m_gc = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n_ground, coordinate=0))
    m_phi1 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes["crank"], coordinate=2))
    if driver == "velocity":
        j_driver = mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[m_gc, m_phi1],
                                                           velocityLevel=True, offset=OMEGA))
    elif driver == "position":
        j_driver = mbs.AddObject(ObjectConnectorCoordinate(
            markerNumbers=[m_gc, m_phi1],
            offsetUserFunction=lambda mbs_, t, item, offset: OMEGA * t,
            offsetUserFunction_t=lambda mbs_, t, item, offset: OMEGA))
    else:
        raise ValueError(f"driver must be 'velocity' or 'position', not {driver!r}")

    out = exu.OutputVariableType

    def sensor(kind, number, variable):
        item = (SensorNode(nodeNumber=number, outputVariableType=variable, storeInternal=True,
                           writeToFile=False) if kind == "node" else
                SensorObject(objectNumber=number, outputVariableType=variable, storeInternal=True,
                             writeToFile=False))
        return mbs.AddSensor(item)

    sensors = {  # name: (sensor, column; None: |.| of the x, y columns)
        "slider_x": (sensor("node", nodes["slider"], out.Position), 0),
        "slider_vx": (sensor("node", nodes["slider"], out.Velocity), 0),
        "crank_phi": (sensor("node", nodes["crank"], out.Coordinates), 2),
        "crank_q": (sensor("node", nodes["crank"], out.Coordinates), "all"),
        "crank_v": (sensor("node", nodes["crank"], out.Coordinates_t), "all"),
        "rod_q": (sensor("node", nodes["rod"], out.Coordinates), "all"),
        "rod_v": (sensor("node", nodes["rod"], out.Coordinates_t), "all"),
        "driver_torque": (sensor("object", j_driver, out.Force), 0),
    }
    if j_crank_rod is not None:
        sensors["joint_force"] = (sensor("object", j_crank_rod, out.Force), None)
    mbs.Assemble()
    return sc, mbs, sensors


def add_clearance_loads(mbs, nodes, bodies, joint: KVJoint) -> None:
    """The clearance joint as four loads with user functions on the current
    state: force on the crank pin point, the opposite on the rod's bushing point,
    and the moments (friction R_pin F_t on the crank; on the rod its opposite
    plus e x (-F), since diffwear applies the rod's force at the pin centre)."""
    from exudyn.itemInterface import LoadForceVector, LoadTorqueVector

    coords, rates = exu.OutputVariableType.Coordinates, exu.OutputVariableType.Coordinates_t

    def contact():
        q1 = mbs.GetNodeOutput(nodes["crank"], coords) + REFERENCE["crank"]
        q2 = mbs.GetNodeOutput(nodes["rod"], coords) + REFERENCE["rod"]
        v1, v2 = mbs.GetNodeOutput(nodes["crank"], rates), mbs.GetNodeOutput(nodes["rod"], rates)
        f, m, pin = joint.evaluate(q1, v1, q2, v2)
        bush = (q2[0] - L2 * math.cos(q2[2]), q2[1] - L2 * math.sin(q2[2]))
        e = (pin[0] - bush[0], pin[1] - bush[1])
        return f, m, e

    def on_pin(mbs_, t, load):
        f, _, _ = contact()
        return [f[0], f[1], 0.0]

    def on_bushing(mbs_, t, load):
        f, _, _ = contact()
        return [-f[0], -f[1], 0.0]

    def moment_pin(mbs_, t, load):
        return [0.0, 0.0, contact()[1]]

    def moment_bushing(mbs_, t, load):
        f, m, e = contact()
        return [0.0, 0.0, -m - (e[0] * f[1] - e[1] * f[0])]

    def rigid(body, x):
        return mbs.AddMarker(MarkerBodyRigid(bodyNumber=bodies[body], localPosition=[x, 0, 0]))

    m_pin, m_bush = rigid("crank", L1), rigid("rod", -L2)
    mbs.AddLoad(LoadForceVector(markerNumber=m_pin, loadVectorUserFunction=on_pin))
    mbs.AddLoad(LoadForceVector(markerNumber=m_bush, loadVectorUserFunction=on_bushing))
    mbs.AddLoad(LoadTorqueVector(markerNumber=m_pin, loadVectorUserFunction=moment_pin))
    mbs.AddLoad(LoadTorqueVector(markerNumber=m_bush, loadVectorUserFunction=moment_bushing))


def settings(step: float, rho: float, sample: float, duration: float = DURATION):
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.endTime, ti.numberOfSteps = duration, int(round(duration / step))
    ti.generalizedAlpha.spectralRadius = rho
    ti.verboseMode = 0
    s.solution.file.write = False
    s.solution.sensors.writePeriod = sample
    s.show.computationTime = False
    s.show.statistics = False
    return s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=float, default=5e-4, help="fixed step [s] (default %(default)s)")
    ap.add_argument("--rho", type=float, default=0.9, help="spectral radius (Exudyn default 0.9)")
    ap.add_argument("--sample", type=float, default=None,
                    help="sensor sampling period [s] (default: every step)")
    ap.add_argument("--driver", choices=("velocity", "position"), default="velocity")
    ap.add_argument("--repeats", type=int, default=3, help="timed solves; the median is reported")
    ap.add_argument("--duration", type=float, default=DURATION, help="simulated time [s]")
    ap.add_argument("--kv-stiffness", type=float, default=None,
                    help="clearance crank-rod joint: Kelvin-Voigt K [N/m] (default: ideal joint)")
    ap.add_argument("--clearance", type=float, default=0.5e-3, help="radial clearance [m]")
    args = ap.parse_args(argv)
    sample = args.sample or args.step
    joint = None if args.kv_stiffness is None else KVJoint(args.kv_stiffness, args.clearance)

    build_s, solve_s, steps = [], [], None
    for _ in range(max(args.repeats, 1)):
        t0 = time.perf_counter()
        sc, mbs, sensors = build(args.driver, joint)
        sim = settings(args.step, args.rho, sample, args.duration)
        solver = exu.MainSolverImplicitSecondOrder()
        t1 = time.perf_counter()
        ok = solver.SolveSystem(mbs, sim)
        t2 = time.perf_counter()
        if not ok:
            print(json.dumps({"ok": False, "error": solver.GetErrorString()}))
            return 1
        build_s.append(t1 - t0)
        solve_s.append(t2 - t1)
        steps = int(round(args.duration / args.step))
        step_index = int(solver.it.currentStepIndex)
        newton = int(solver.it.newtonStepsCount)
        jacobians = int(solver.it.newtonJacobiCount)

    data, states = {}, {}
    for key, (sensor, col) in sensors.items():
        arr = np.asarray(mbs.GetSensorStoredData(sensor))
        data["t"] = arr[:, 0].tolist()
        if col is None:  # vector: |.| of the planar part
            data[key] = np.hypot(arr[:, 1], arr[:, 2]).tolist()
        elif col == "all":  # body states, for the clearance joint's force
            states[key] = arr[:, 1:4] + (REFERENCE[key[:-2]] if key.endswith("_q") else 0.0)
        else:
            data[key] = arr[:, 1 + col].tolist()
    if joint is not None:
        data["joint_force"] = [
            math.hypot(*joint.evaluate(q1, v1, q2, v2)[0]) for q1, v1, q2, v2 in
            zip(states["crank_q"], states["crank_v"], states["rod_q"], states["rod_v"])]
    print(json.dumps({
        "ok": True, "exudyn": exu.__version__, "python": sys.version.split()[0],
        "solver": "GeneralizedAlpha (index 3)", "step_s": args.step,
        "spectral_radius": args.rho, "driver": args.driver, "steps": steps,
        "duration_s": args.duration,
        "joint": "ideal" if joint is None else {"law": "kv", "stiffness": joint.k,
                                                "clearance": joint.c, "mu": joint.mu,
                                                "restitution": joint.e_r},
        "step_index_at_end": step_index,
        "newton_iterations": newton, "jacobians": jacobians,
        "build_s": float(np.median(build_s)), "solve_s": float(np.median(solve_s)),
        "solve_s_all": solve_s, "build_s_all": build_s, **data,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
