"""Simulator speed on the reference grasp scene, against MuJoCo and Drake on the same URDF and box, in one run.

Reference scene (issue "simulation engine"): the Barrett hand squeezes a 0.08 x 0.067 x 0.05 m, 0.2 kg box between
F1 + F2 and F3 (three fingertip contacts) under a posture PD with gravity compensation and Jacobian-transpose
squeeze forces; 2 s simulated.  Every engine runs the same controller law from Python, each with its own
kinematics.  Prints microseconds per step, real-time factor, the box's creep, and wall-time ratios.
MuJoCo and Drake (its SAP discrete solver, point contact) are benchmark-only dependencies (``pip install mujoco
drake``); a missing one is reported and skipped.

Usage: ``python benchmarks/bench_sim.py [--duration 2.0] [--stiffness-sweep]``.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np
import pinocchio as pin

import bhgrasp as bh
from bhgrasp.errors import SimulationDiverged
from bhgrasp.experiments.hold import JOINT_DAMPING, POSTURE_GAIN, SQUEEZE, reference_hold


def run_bhgrasp(duration: float, dt: float, stiffness: float = 1e4) -> dict:
    hold = reference_hold(dt=dt, stiffness=stiffness)
    start = time.perf_counter()
    trajectory = hold.simulator.run(hold.controller, duration, state=hold.state, progress=False)
    wall = time.perf_counter() - start
    position = trajectory.object_position[:, 0]
    return {"wall": wall, "steps": len(trajectory) - 1, "drop": hold.box_height - position[-1, 2], "position": position}


def run_mujoco(duration: float, dt: float) -> dict:
    import mujoco

    hold = reference_hold(dt=dt)
    q0, height = hold.state.q, hold.box_height
    size = np.array(hold.simulator.scene.objects[0].size)
    spec = mujoco.MjSpec.from_file(str(bh.barrett_urdf_path()))
    spec.option.timestep = dt
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    body = spec.worldbody.add_body(name="box", pos=[0.0, 0.0, height])
    body.add_freejoint()
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=size / 2, mass=0.2, friction=[0.8, 0.005, 0.0001])
    for joint in spec.joints:
        joint.damping = [JOINT_DAMPING, 0.0, 0.0]  # MuJoCo 4: (damping, polynomial coefficients)
    model = spec.compile()
    data = mujoco.MjData(model)
    data.qpos[:8] = q0
    mujoco.mj_forward(model, data)
    tips = [model.body(f"{finger}_distal_link").id for finger in ("F1", "F2", "F3")]
    jacobian = np.zeros((3, model.nv))
    steps = round(duration / dt)
    start = time.perf_counter()
    for _ in range(steps):
        q = data.qpos[:8]
        tau = data.qfrc_bias[:8] + POSTURE_GAIN * (q0 - q)  # gravity + Coriolis compensation, posture spring
        for body_id, force in zip(tips, SQUEEZE.values()):
            tip = data.xpos[body_id] + data.xmat[body_id].reshape(3, 3) @ np.array([0.05, 0.0, 0.0])
            mujoco.mj_jac(model, data, jacobian, None, tip, body_id)
            tau += jacobian[:, :8].T @ force
        data.qfrc_applied[:8] = tau
        mujoco.mj_step(model, data)
    wall = time.perf_counter() - start
    return {"wall": wall, "steps": steps, "drop": height - data.qpos[10]}


def run_drake(duration: float, dt: float) -> dict:
    """The same scene in Drake: MultibodyPlant with the SAP discrete solver, point contact, same controller law."""
    from pydrake.geometry import AddContactMaterial, ProximityProperties, RoleAssign
    from pydrake.geometry import Box as DrakeBox
    from pydrake.math import RigidTransform
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import (
        AddMultibodyPlantSceneGraph,
        CoulombFriction,
        DiscreteContactApproximation,
    )
    from pydrake.multibody.tree import JacobianWrtVariable, RevoluteJoint, SpatialInertia
    from pydrake.systems.analysis import Simulator as DrakeSimulator
    from pydrake.systems.framework import DiagramBuilder

    hold = reference_hold(dt=dt)
    q0, height = hold.state.q, hold.box_height
    size = np.array(hold.simulator.scene.objects[0].size)
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=dt)
    plant.set_discrete_contact_approximation(DiscreteContactApproximation.kSap)
    (hand,) = Parser(plant).AddModels(str(bh.barrett_urdf_path()))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("palm", hand))
    box = plant.AddRigidBody("box", plant.AddModelInstance("box"), SpatialInertia.SolidBoxWithMass(0.2, *size))
    # Our contact law on every surface: k = 1e4 N/m, c = 20 N s/m (SAP's linear dissipation: relaxation time c / k),
    # mu = 0.8; the hand's URDF geometries get the same properties (Drake combines the two sides' values)
    properties = ProximityProperties()
    AddContactMaterial(point_stiffness=1e4, friction=CoulombFriction(0.8, 0.8), properties=properties)
    properties.AddProperty("material", "relaxation_time", 2e-3)
    plant.RegisterCollisionGeometry(box, RigidTransform(), DrakeBox(*size), "box", properties)
    for index in plant.GetBodyIndices(hand):
        for geometry in plant.GetCollisionGeometriesForBody(plant.get_body(index)):
            scene_graph.AssignRole(plant.get_source_id(), geometry, properties, RoleAssign.kReplace)
    names = hold.hand.joint_names
    joints = [plant.GetJointByName(name, hand) for name in names]
    for joint in joints:
        if isinstance(joint, RevoluteJoint):
            joint.set_default_damping(JOINT_DAMPING)
    plant.Finalize()
    simulator = DrakeSimulator(builder.Build())
    context = plant.GetMyMutableContextFromRoot(simulator.get_mutable_context())
    for joint, value in zip(joints, q0):
        joint.set_angle(context, value)
    plant.SetFreeBodyPose(context, box, RigidTransform([0.0, 0.0, height]))
    rows = [joint.velocity_start() for joint in joints]
    tips = [plant.GetBodyByName(f"{finger}_tip", hand).body_frame() for finger in SQUEEZE]
    port = plant.get_applied_generalized_force_input_port()
    steps = round(duration / dt)
    start = time.perf_counter()
    for k in range(steps):
        q = plant.GetPositions(context)[[joint.position_start() for joint in joints]]
        tau = plant.CalcBiasTerm(context) - plant.CalcGravityGeneralizedForces(context)  # gravity + Coriolis
        tau[rows] += POSTURE_GAIN * (q0 - q)
        for frame, force in zip(tips, SQUEEZE.values()):
            jacobian = plant.CalcJacobianTranslationalVelocity(context, JacobianWrtVariable.kV, frame, np.zeros(3),
                                                               plant.world_frame(), plant.world_frame())  # fmt: skip
            tau[rows] += jacobian[:, rows].T @ force
        mask = np.zeros_like(tau)
        mask[rows] = tau[rows]
        port.FixValue(context, mask)
        simulator.AdvanceTo((k + 1) * dt)
    wall = time.perf_counter() - start
    return {"wall": wall, "steps": steps, "drop": height - plant.EvalBodyPoseInWorld(context, box).translation()[2]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--duration", type=float, default=2.0, help="simulated time [s]")
    parser.add_argument("--stiffness-sweep", action="store_true", help="hold quality per contact stiffness and step")
    args = parser.parse_args()
    print(f"machine: {platform.machine()} python {platform.python_version()}, pinocchio {pin.__version__}")
    rows = []
    for dt in (1e-3, 2e-3, 5e-3, 1e-2):
        ours = run_bhgrasp(args.duration, dt)
        rows.append((f"bhgrasp implicit, dt {dt * 1e3:g} ms", ours))
    try:
        import mujoco

        print(f"mujoco {mujoco.__version__}")
        theirs = run_mujoco(args.duration, 1e-3)
        rows.append(("mujoco implicitfast, dt 1 ms", theirs))
        for dt in (2e-3, 5e-3, 1e-2):
            rows.append((f"mujoco implicitfast, dt {dt * 1e3:g} ms", run_mujoco(args.duration, dt)))
    except ImportError:
        theirs = None
        print("mujoco not installed: no comparison")
    drake_rows = []
    try:
        import pydrake

        print(f"drake {pydrake.__version__ if hasattr(pydrake, '__version__') else ''}".strip())
        for dt in (1e-3, 1e-2):
            drake_rows.append((f"drake SAP, dt {dt * 1e3:g} ms", run_drake(args.duration, dt)))
    except ImportError:
        print("drake not installed (pip install drake): no Drake comparison")
    rows += drake_rows
    print(f"\n{'engine':<30}{'us/step':>10}{'RTF':>8}{'wall/sim-s [s]':>16}{'box drop [mm]':>15}")
    for name, result in rows:
        per_step = result["wall"] / result["steps"] * 1e6
        rtf = args.duration / result["wall"]
        print(f"{name:<30}{per_step:10.1f}{rtf:8.2f}{result['wall'] / args.duration:16.3f}{result['drop'] * 1e3:15.3f}")
    for name, result in drake_rows:
        same = next(r for n, r in rows[:4] if n.endswith(name.rsplit(",", 1)[1]))
        print(f"ratio bhgrasp / {name} (wall per simulated second, same step): {same['wall'] / result['wall']:.2f}")
    if theirs is not None:
        ours_rows, mujoco_rows = rows[:4], rows[4:8]
        for (name, result), (_, matched) in zip(ours_rows, mujoco_rows):
            print(
                f"ratio {name} / mujoco (wall per simulated second): {result['wall'] / theirs['wall']:.1f} vs its 1 ms"
                f" step, {result['wall'] / matched['wall']:.1f} at the same step"
            )
    if args.stiffness_sweep:
        print("\nhold over 1 s per contact stiffness and step: box drop [mm] / creep over the last 0.5 s [um/s]")
        steps = (2e-2, 1e-2, 5e-3, 1e-3)
        print(f"{'k [N/m]':>10}" + "".join(f"{f'dt {dt * 1e3:g} ms':>22}" for dt in steps))
        for stiffness in (1e3, 1e4, 5e4):
            cells = []
            for dt in steps:
                try:
                    result = run_bhgrasp(1.0, dt, stiffness)
                except SimulationDiverged:
                    cells.append("diverged")
                    continue
                position = result["position"]
                late = position[len(position) // 2 :]
                creep = np.linalg.norm(late[-1] - late[0]) / 0.5 * 1e6
                cells.append(f"{result['drop'] * 1e3:.3f} / {creep:.2g}")
            print(f"{stiffness:10.0f}" + "".join(f"{cell:>22}" for cell in cells))


if __name__ == "__main__":
    main()
