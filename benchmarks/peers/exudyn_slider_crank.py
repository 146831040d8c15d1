#!/usr/bin/env python3
"""An Exudyn peer: the thesis Table 2-1 ideal slider-crank in Exudyn 1.13.

Run it with an interpreter that has ``exudyn`` (not diffwear's venv; it imports
nothing from diffwear):

    /work/venv-exudyn/bin/python benchmarks/peers/exudyn_slider_crank.py [--step 5e-4]

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


def build(driver: str = "velocity"):
    """(SystemContainer, mbs, sensors dict) of the assembled slider-crank."""
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground = mbs.AddObject(ObjectGround(referencePosition=[0, 0, 0]))
    m_ground = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))

    w2 = -OMEGA * L1 / L2                 # rod angular velocity at t = 0
    # (COM position, angle), (COM velocity, angular velocity) at phi1 = 0
    init = {
        "crank": ([L1, 0, 0], [0, OMEGA * L1, OMEGA], M1, I1),
        "rod": ([2 * L1 + L2, 0, 0], [0, OMEGA * L1, w2], M2, I2),
        "slider": ([2 * L1 + 2 * L2, 0, 0], [0, 0, 0], M3, I3),
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
    j_crank_rod = mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[pos("crank", L1), pos("rod", -L2)]))
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
        "joint_force": (sensor("object", j_crank_rod, out.Force), None),
        "driver_torque": (sensor("object", j_driver, out.Force), 0),
    }
    mbs.Assemble()
    return sc, mbs, sensors


def settings(step: float, rho: float, sample: float):
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.endTime, ti.numberOfSteps = DURATION, int(round(DURATION / step))
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
    args = ap.parse_args(argv)
    sample = args.sample or args.step

    build_s, solve_s, steps = [], [], None
    for _ in range(max(args.repeats, 1)):
        t0 = time.perf_counter()
        sc, mbs, sensors = build(args.driver)
        sim = settings(args.step, args.rho, sample)
        solver = exu.MainSolverImplicitSecondOrder()
        t1 = time.perf_counter()
        ok = solver.SolveSystem(mbs, sim)
        t2 = time.perf_counter()
        if not ok:
            print(json.dumps({"ok": False, "error": solver.GetErrorString()}))
            return 1
        build_s.append(t1 - t0)
        solve_s.append(t2 - t1)
        steps = int(round(DURATION / args.step))
        step_index = int(solver.it.currentStepIndex)
        newton = int(solver.it.newtonStepsCount)
        jacobians = int(solver.it.newtonJacobiCount)

    data = {}
    for key, (sensor, col) in sensors.items():
        arr = np.asarray(mbs.GetSensorStoredData(sensor))
        data["t"] = arr[:, 0].tolist()
        if col is None:  # vector: |.| of the planar part
            data[key] = np.hypot(arr[:, 1], arr[:, 2]).tolist()
        else:
            data[key] = arr[:, 1 + col].tolist()
    print(json.dumps({
        "ok": True, "exudyn": exu.__version__, "python": sys.version.split()[0],
        "solver": "GeneralizedAlpha (index 3)", "step_s": args.step,
        "spectral_radius": args.rho, "driver": args.driver, "steps": steps,
        "step_index_at_end": step_index,
        "newton_iterations": newton, "jacobians": jacobians,
        "build_s": float(np.median(build_s)), "solve_s": float(np.median(solve_s)),
        "solve_s_all": solve_s, "build_s_all": build_s, **data,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
