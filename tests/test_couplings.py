"""Issue 32 item 7: hands with mimic joints, loaded coupled (one coordinate), through dynamics, simulator and pickles.

The hand is written here: a two-finger gripper driven by one coordinate (F1's proximal joint); F2's proximal joint
mimics it (x 1) and both distal joints follow at x 0.5 + 0.1 rad, as an underactuated gripper's URDF says with
``<mimic>``.  The independent truth is the same URDF loaded with ``mimic="independent"`` (Pinocchio's own model of
four free joints, not bhgrasp's twin) under the coupling written as a constraint: M = G^T M_4 G and the like, Lagrange
multipliers for the accelerations, and SciPy's integrator for a run.
"""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import solve_ivp
from urdf_parts import rod

import bhgrasp as bh
from bhgrasp.model.couplings import Coupling, independent_model, twin_map

LINKS = (0.07, 0.05)  # [m] proximal, distal
LEVER = (0.003, 0.001)  # [m] each link's centre of mass off its axis (x, y)
MIMIC = {  # joint -> (mimicked joint, multiplier, offset [rad])
    "F1_distal_joint": ("F1_proximal_joint", 0.5, 0.1),
    "F2_proximal_joint": ("F1_proximal_joint", 1.0, 0.0),
    "F2_distal_joint": ("F1_proximal_joint", 0.5, 0.1),
}


def gripper_urdf() -> str:
    """Palm top face at z = 0, fingers up along z at x = +-0.05 m, closing toward each other (about -y and +y)."""
    parts = [
        '<?xml version="1.0"?><robot name="gripper2">',
        '<link name="palm"><inertial><origin xyz="0 0 -0.01"/><mass value="0.5"/><inertia ixx="4e-4" iyy="6e-4" '
        'izz="9e-4" ixy="0" ixz="0" iyz="0"/></inertial><collision><origin xyz="0 0 -0.01"/>'
        '<geometry><box size="0.16 0.1 0.02"/></geometry></collision></link>',
    ]
    limit = '<limit lower="-0.6" upper="1.6" effort="2" velocity="3"/>'
    for name, x, sign in (("F1", 0.05, -1.0), ("F2", -0.05, 1.0)):
        mimic = {
            joint: f'<mimic joint="{source}" multiplier="{multiplier}" offset="{offset}"/>'
            for joint, (source, multiplier, offset) in MIMIC.items()
        }
        parts += [
            rod(f"{name}_proximal", LINKS[0], LEVER),
            rod(f"{name}_distal", LINKS[1], LEVER),
            f'<link name="{name}"><inertial><mass value="0.01"/><inertia ixx="4e-7" iyy="4e-7" izz="4e-7" ixy="0" '
            f'ixz="0" iyz="0"/></inertial><collision><geometry><sphere radius="0.01"/></geometry></collision></link>',
            f'<joint name="{name}_proximal_joint" type="revolute"><parent link="palm"/><child link="{name}_proximal"/>'
            f'<origin xyz="{x} 0 0"/><axis xyz="0 {sign} 0"/>{limit}{mimic.get(f"{name}_proximal_joint", "")}'
            "</joint>",
            f'<joint name="{name}_distal_joint" type="revolute"><parent link="{name}_proximal"/>'
            f'<child link="{name}_distal"/><origin xyz="0 0 {LINKS[0]}"/><axis xyz="0 {sign} 0"/>{limit}'
            f"{mimic[f'{name}_distal_joint']}</joint>",
            f'<joint name="{name}_tip" type="fixed"><parent link="{name}_distal"/><child link="{name}"/>'
            f'<origin xyz="0 0 {LINKS[1]}"/></joint>',
        ]
    return "".join([*parts, "</robot>"])


@pytest.fixture(scope="module")
def urdf(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("coupled") / "gripper2.urdf"
    path.write_text(gripper_urdf())
    return path


@pytest.fixture(scope="module")
def hand(urdf) -> bh.Hand:
    return bh.Hand.from_urdf(urdf)


@pytest.fixture(scope="module")
def free(urdf) -> bh.Hand:
    """The same URDF with four independent joints (Pinocchio's model, not bhgrasp's twin)."""
    return bh.Hand.from_urdf(urdf, mimic="independent")


def coupling_matrix(free: bh.Hand) -> tuple[np.ndarray, np.ndarray]:
    """G (4, 1) and c (4,) with q_free = G q + c, from MIMIC (written by hand, not read from any model)."""
    g, c = np.zeros((free.nv, 1)), np.zeros(free.nq)
    for joint in free.joint_names:
        source, multiplier, offset = MIMIC.get(joint, (joint, 1.0, 0.0))
        assert source == "F1_proximal_joint"
        g[free.joint_index(joint), 0], c[free.joint_index(joint)] = multiplier, offset
    return g, c


def constraint_rows(free: bh.Hand) -> np.ndarray:
    """A (3, 4): A v_free = 0 is the coupling (each mimic joint's speed = multiplier x its source's)."""
    rows = []
    for joint, (source, multiplier, _) in MIMIC.items():
        row = np.zeros(free.nv)
        row[free.joint_index(joint)], row[free.joint_index(source)] = 1.0, -multiplier
        rows.append(row)
    return np.array(rows)


def lagrange_acceleration(free: bh.Hand, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Accelerations of the free hand under tau with the coupling as a constraint: [M A^T; A 0] [a; lambda]."""
    a_rows = constraint_rows(free)
    m = free.mass_matrix(q)
    kkt = np.block([[m, a_rows.T], [a_rows, np.zeros((len(a_rows), len(a_rows)))]])
    rhs = np.concatenate((tau - free.nonlinear_effects(q, v), np.zeros(len(a_rows))))
    return np.linalg.solve(kkt, rhs)[: free.nv]


def test_a_mimic_urdf_loads_with_one_coordinate_per_independent_joint(urdf, hand, free):
    assert (hand.nq, hand.nv, free.nv) == (1, 1, 4)
    assert hand.joint_names == ("F1_proximal_joint",)
    assert hand.couplings == tuple(Coupling(joint, *MIMIC[joint]) for joint in MIMIC)
    assert hand.finger_joints("F2") == ("F1_proximal_joint",)
    np.testing.assert_array_equal(hand.finger_indices("F2"), [0])
    assert "mimic F2_distal_joint: 0.5 x F1_proximal_joint + 0.1" in hand.summary()
    with pytest.raises(bh.InputError, match=r"'F2_distal_joint' mimics 'F1_proximal_joint' .* use 'F1_proximal_joint'"):
        hand.configuration(F2_distal_joint=0.3)
    with pytest.raises(bh.InputError, match="`mimic` must be 'coupled' or 'independent', got 'refuse'"):
        bh.Hand.from_urdf(urdf, mimic="refuse")


def test_the_coupled_dynamics_are_the_free_hands_under_the_coupling(hand, free):
    """M = G^T M_4 G, C = G^T C_4 G, tau = G^T tau_4, J = J_4 G and the same poses, at seeded states."""
    g, c = coupling_matrix(free)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, v, a = rng.uniform(-0.5, 1.4, 1), rng.normal(size=1), rng.normal(size=1)
        q4, v4, a4 = g @ q + c, g @ v, g @ a
        np.testing.assert_allclose(hand.mass_matrix(q), g.T @ free.mass_matrix(q4) @ g, rtol=1e-12)
        np.testing.assert_allclose(hand.coriolis_matrix(q, v), g.T @ free.coriolis_matrix(q4, v4) @ g, atol=1e-15)
        np.testing.assert_allclose(hand.inverse_dynamics(q, v, a), g.T @ free.inverse_dynamics(q4, v4, a4), rtol=1e-12)
        np.testing.assert_allclose(hand.gravity_torques(q), g.T @ free.gravity_torques(q4), rtol=1e-12)
        np.testing.assert_allclose(hand.fingertip_positions(q), free.fingertip_positions(q4), atol=1e-15)
        for finger in hand.fingers:
            np.testing.assert_allclose(
                hand.fingertip_jacobian(q, finger), free.fingertip_jacobian(q4, finger) @ g, atol=1e-15
            )
            np.testing.assert_allclose(
                hand.fingertip_bias_acceleration(q, v, finger),
                free.fingertip_bias_acceleration(q4, v4, finger),
                atol=1e-14,
            )
        # Pinocchio's regressor has no mimic joints: bhgrasp's is G^T Y on the twin, and it must still give RNEA.
        np.testing.assert_allclose(
            hand.regressor(q, v, a) @ hand.inertial_parameters(), hand.inverse_dynamics(q, v, a), rtol=1e-10
        )
        y = hand.slotine_li_regressor(q, v, 2.0 * v, a)
        expected = hand.slotine_li_torque(q, v, 2.0 * v, a)
        np.testing.assert_allclose(y @ hand.inertial_parameters(), expected, rtol=1e-10)


def test_forward_dynamics_are_the_lagrange_multiplier_solution(hand, free):
    """ABA refuses mimic joints; bhgrasp's M^-1 (tau - b) must equal the constrained free hand's accelerations."""
    g, c = coupling_matrix(free)
    rng = np.random.default_rng(4)
    for _ in range(5):
        q, v, tau = rng.uniform(-0.5, 1.4, 1), rng.normal(size=1), rng.normal(0.0, 0.05, 1)
        tau4 = np.zeros(free.nv)
        tau4[free.joint_index("F1_proximal_joint")] = tau[0]  # the drive acts on the driving joint
        expected = lagrange_acceleration(free, g @ q + c, g @ v, tau4)
        np.testing.assert_allclose(g @ hand.forward_dynamics(q, v, tau), expected, rtol=1e-9, atol=1e-12)


def test_the_twin_is_pinocchios_independent_model_and_pickles_rebuild_the_coupled_hand(hand, free):
    twin = independent_model(hand.model)
    mapping = twin_map(hand.model, twin)
    g, c = coupling_matrix(free)
    np.testing.assert_array_equal(mapping.velocity, g)
    np.testing.assert_allclose(mapping.configuration(np.array([0.7])), g @ [0.7] + c, rtol=1e-15)
    q4 = np.array([0.4, 0.3, 0.2, 0.5])
    data, free_data = twin.createData(), free.model.createData()
    np.testing.assert_allclose(pin.crba(twin, data, q4), pin.crba(free.model, free_data, q4), atol=1e-18)
    # Pinocchio 4.1's own pickle of a coupled model loses the mimic joints' sizes (every algorithm then reads past
    # its vectors); the hand pickles through its twin.
    heavier = hand.perturbed(mass_scale=1.5)
    heavier.model.armature = np.array([2e-4])  # a rotor's reflected inertia [kg m^2]: CRBA adds it to M's diagonal
    copy = pickle.loads(pickle.dumps(heavier))
    assert copy.couplings == hand.couplings and copy.nq == 1
    q, v = np.array([0.6]), np.array([0.4])
    np.testing.assert_allclose(copy.mass_matrix(q), 1.5 * hand.mass_matrix(q) + 2e-4, rtol=1e-12)
    np.testing.assert_array_equal(copy.mass_matrix(q), heavier.mass_matrix(q))
    np.testing.assert_array_equal(copy.velocity_limit, hand.velocity_limit)
    np.testing.assert_array_equal(copy.effort_limit, hand.effort_limit)
    np.testing.assert_allclose(copy.nonlinear_effects(q, v), 1.5 * hand.nonlinear_effects(q, v), rtol=1e-12)
    np.testing.assert_array_equal(copy.lower, hand.lower)
    # A simulator travels to a process pool or Dask worker as a pickle: the copy runs the same bits.
    sim = bh.Simulator(bh.Scene(hand), dt=1e-3)
    runs = [
        s.run(lambda t, state: np.array([0.01]), 0.05, progress=False) for s in (sim, pickle.loads(pickle.dumps(sim)))
    ]
    np.testing.assert_array_equal(runs[0].q, runs[1].q)
    assert runs[0].q[-1, 0] != runs[0].q[0, 0]


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_the_simulated_coupled_hand_follows_the_constrained_free_hand(hand, free, engine):
    """No contact: 0.2 s under gravity and a constant drive torque, against SciPy on the Lagrange-multiplier ODE."""
    g, c = coupling_matrix(free)
    drive = 0.01  # [N m] on F1_proximal_joint
    sim = bh.Simulator(bh.Scene(hand), dt=1e-3, integrator="rk4", engine=engine)
    q0 = np.array([0.2])
    traj = sim.run(lambda t, state: np.array([drive]), 0.2, state=sim.initial_state(q0), progress=False)

    tau4 = np.zeros(free.nv)
    tau4[free.joint_index("F1_proximal_joint")] = drive

    def rate(_: float, x: np.ndarray) -> np.ndarray:
        q4, v4 = x[: free.nq], x[free.nq :]
        return np.concatenate((v4, lagrange_acceleration(free, q4, v4, tau4)))

    x0 = np.concatenate((g @ q0 + c, np.zeros(free.nv)))
    truth = solve_ivp(rate, (0.0, 0.2), x0, t_eval=traj.t, rtol=1e-11, atol=1e-13, method="DOP853")
    assert np.abs(constraint_rows(free) @ truth.y[free.nq :]).max() < 1e-9  # the free hand kept the coupling
    assert 0.5 < traj.q[-1, 0] - q0[0] and traj.q[:, 0].max() < 1.5  # it moved, clear of its stop (1.6 rad)
    np.testing.assert_allclose(traj.q[:, 0], truth.y[0], atol=1e-9)
    np.testing.assert_allclose(traj.v[:, 0], truth.y[free.nq], atol=1e-8)


def closing_on_a_box(hand: bh.Hand, engine: str) -> tuple[bh.Simulator, object]:
    box = bh.Box(size=(0.04, 0.03, 0.04), mass=0.05, pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.02])))
    sim = bh.Simulator(bh.Scene(hand, [box]), dt=5e-4, engine=engine)
    traj = sim.run(lambda t, state: np.array([0.05]), 0.9, state=sim.initial_state(np.array([0.1])), progress=False)
    return sim, traj


def test_a_coupled_gripper_closes_on_a_box_and_both_engines_agree(hand):
    """One coordinate drives both fingers onto the box; at rest the drive balances gravity and the contact torques
    sum_i J_i^T f_i (Newton, from the recorded contacts), and the two engines give the same run."""
    runs = {engine: closing_on_a_box(hand, engine) for engine in ("compiled", "python")}
    traj = runs["compiled"][1]
    k = len(traj.t) - 1
    assert abs(traj.v[k, 0]) < 1e-4  # at rest on the box
    rows = slice(traj.contact_offsets[k], traj.contact_offsets[k + 1])
    bodies = traj.pair_bodies[traj.contact_pair[rows]]
    fingers_touching = {str(a).split("_")[0] for a, _ in bodies}
    assert {"F1", "F2"} <= fingers_touching  # both fingers squeeze, the one coordinate drives both
    torque = np.zeros(1)
    for (body, _), point, force in zip(bodies, traj.contact_point[rows], traj.contact_force[rows]):
        if str(body) in hand.frame_names():
            torque += hand.point_jacobian(traj.q[k], str(body), point).T @ (-force)  # force on the hand
    residual = 0.05 - hand.gravity_torques(traj.q[k]) + torque
    assert np.abs(residual).max() < 1e-5 * 0.05  # measured 2.7e-8 N m
    other = runs["python"][1]
    np.testing.assert_allclose(other.q, traj.q, rtol=0.0, atol=1e-12)


def test_the_viewer_draws_each_mimic_link_where_the_free_hand_has_it(hand, free):
    from bhgrasp.viz import SceneViewer

    g, c = coupling_matrix(free)
    q = np.array([0.8])
    viewer = SceneViewer(bh.Scene(hand))
    try:
        shown = viewer.placements(q, [])
    finally:
        viewer.close()
    scene = bh.Scene(free)
    data, geometry_data = scene.model.createData(), pin.GeometryData(scene.geometry)
    pin.updateGeometryPlacements(scene.model, data, scene.geometry, geometry_data, g @ q + c)
    assert len(shown) == len(geometry_data.oMg) == 7  # palm, two rods and a pad per finger
    for placement, truth in zip(shown, geometry_data.oMg):
        np.testing.assert_allclose(placement, truth.homogeneous, atol=1e-15)


def test_the_grasp_kinematics_refuse_a_coupled_hand_by_name(hand):
    """Pinocchio 4.1 mixes mimic joints into their source's Jacobian column and gets J_dot wrong (measured here)."""
    from bhgrasp.grasp.kinematics import parent_joints

    model, data = hand.model, hand.model.createData()
    free = bh.Hand.from_urdf(hand.urdf_path, mimic="independent")
    g, c = coupling_matrix(free)
    q, v = np.array([0.5]), np.array([0.7])
    free_data = free.model.createData()
    pin.computeJointJacobiansTimeVariation(model, data, q, v)
    pin.computeJointJacobiansTimeVariation(free.model, free_data, g @ q + c, g @ v)
    distal = model.getJointId("F2_distal_joint")
    coupled = pin.getJointJacobianTimeVariation(model, data, distal, pin.LOCAL_WORLD_ALIGNED)
    truth = pin.getJointJacobianTimeVariation(free.model, free_data, distal, pin.LOCAL_WORLD_ALIGNED) @ g
    assert np.abs(coupled - truth).max() > 1e-2
    with pytest.raises(
        bh.ModelError, match=r"grasp kinematics .* mimic joints \(F1_distal_joint, .*mimic='independent'"
    ):
        parent_joints(hand, ["F1_distal"])


def test_joint_controllers_drive_the_one_coordinate(hand):
    """Computed torque with the exact model gives e'' + Kv e' + Kp e = 0 in the coupled coordinate (closed form, as
    tests/test_controllers.py checks on the BH8-280); the adaptive sliding law (regressors through the twin) learns a
    nominal model 30 % light and tracks better than it starts."""
    from bhgrasp.controllers import AdaptiveSlidingMode, ComputedTorque, inertia_gain
    from bhgrasp.motion.trajectories import Sinusoid

    sim = bh.Simulator(bh.Scene(hand), dt=1e-3)
    reference = Sinusoid(np.array([0.5]), np.array([0.15]), 0.7)  # as the BH8-280's test
    e0 = 0.05
    traj = sim.run(ComputedTorque(hand, reference), 1.0, state=sim.initial_state([0.5 + e0]), progress=False)
    kp, kv = 400.0, 160.0
    slow, fast = np.roots([1.0, kv, kp])  # e = a exp(slow t) + b exp(fast t)
    de0 = -reference(0.0)[1][0]
    b = (de0 - slow * e0) / (fast - slow)
    expected = (e0 - b) * np.exp(slow * traj.t) + b * np.exp(fast * traj.t)
    error = traj.q[:, 0] - traj.log["q_d"][:, 0]
    assert np.max(np.abs(error - expected)) < 1e-3  # the 1 ms zero-order hold is the only difference

    nominal = hand.perturbed(0.7)
    controller = AdaptiveSlidingMode(nominal, reference, k_s=inertia_gain(nominal, 40.0))
    traj = sim.run(controller, 2.0, state=sim.initial_state([0.5]), progress=False)
    error = np.abs(traj.q[:, 0] - traj.log["q_d"][:, 0])
    first, last = error[traj.t < 0.5].max(), error[traj.t > 1.5].max()
    assert last < 0.2 * first and last < 1e-3


def test_info_prints_the_couplings(urdf, capsys):
    from bhgrasp.cli import main

    assert main(["info", "--urdf", str(urdf)]) == 0
    out = capsys.readouterr().out
    assert "gripper2: 1 joints, 2 fingers" in out and "mimic F2_proximal_joint: 1 x F1_proximal_joint + 0" in out
    assert main(["info", "--urdf", str(urdf), "--mimic", "independent"]) == 0
    assert "gripper2: 4 joints, 2 fingers" in capsys.readouterr().out


def chain_urdf(second: str, third: str = "") -> str:
    """palm -> J1 -> J2 -> (J3) -> tip, rods along z, axes along x; ``second``/``third`` are extra <joint> contents."""
    links = "".join(rod(f"L{k}", 0.04, LEVER) for k in (1, 2, 3))
    joints = []
    for k, extra in ((1, ""), (2, second), (3, third)):
        parent = "palm" if k == 1 else f"L{k - 1}"
        kind = "continuous" if "continuous" in extra else "revolute"
        limit = (
            '<limit effort="1" velocity="2"/>'
            if kind == "continuous"
            else '<limit lower="-1" upper="1" effort="1" velocity="2"/>'
        )
        body = extra.replace("continuous", "")
        joints.append(
            f'<joint name="J{k}" type="{kind}"><parent link="{parent}"/><child link="L{k}"/>'
            f'<origin xyz="0 0 {0.0 if k == 1 else 0.04}"/><axis xyz="1 0 0"/>{limit}{body}</joint>'
        )
    return f'<?xml version="1.0"?><robot name="chain"><link name="palm"/>{links}{"".join(joints)}</robot>'


def test_coupled_trees_pinocchio_cannot_compute_are_refused_by_name(tmp_path, hand):
    """Pinocchio 4.1's CRBA accumulates across calls when a mimic joint has moving joints above and below it (a
    wrist mount, or independent -> mimic -> independent); continuous mimic joints do not map linearly.  Refused."""
    from bhgrasp.model.mount import mounted

    path = tmp_path / "chain.urdf"
    path.write_text(chain_urdf('<mimic joint="J1" multiplier="0.5"/>'))
    with pytest.raises(bh.ModelError, match=r"J2 mimic other joints\) changes from one call to the next by up to"):
        bh.Hand.from_urdf(path, fingertips=["L3"])
    assert bh.Hand.from_urdf(path, fingertips=["L3"], mimic="independent").nv == 3
    with pytest.raises(bh.ModelError, match="changes from one call to the next.*mimic='independent'"):
        mounted(bh.Hand.from_urdf(bh.barrett_urdf_path()))
    path.write_text(chain_urdf("continuous", 'continuous<mimic joint="J2" multiplier="1"/>'))
    with pytest.raises(bh.ModelError, match=r"mimic joint 'J3' follows 'J2', a joint of 2 configuration coordinates"):
        bh.Hand.from_urdf(path, fingertips=["L3"])
    mounted(hand)  # the gripper's mimic joints have no moving joint below them: its mass matrix holds


def test_a_negative_multiplier_and_the_finger_maps(tmp_path, hand):
    """The twin's speed limits are magnitudes (|multiplier| x the source's); contact sensing puts a mimic joint's
    link on its own finger; the opposition search, one IK per finger, refuses a coupled hand by name."""
    from bhgrasp.grasp.pad_placement import knuckles
    from bhgrasp.grasp.sensing import ContactSensing

    path = tmp_path / "mirror.urdf"
    path.write_text(
        chain_urdf('<mimic joint="J1" multiplier="-2" offset="0.1"/>').replace(
            '"J3" type="revolute"', '"J3" type="fixed"'
        )
    )
    mirror = bh.Hand.from_urdf(path, fingertips=["L3"])
    twin = independent_model(mirror.model)
    np.testing.assert_array_equal(twin.upperVelocityLimit, [2.0, 4.0])
    np.testing.assert_array_equal(twin.lowerVelocityLimit, [2.0, 4.0])
    np.testing.assert_allclose(twin.lowerPositionLimit[1:], [-1.9])
    np.testing.assert_allclose(twin.upperPositionLimit[1:], [2.1])
    sensing = ContactSensing(hand)
    assert [sensing.finger_of(link) for link in ("F1_distal", "F2_proximal", "F2_distal", "F2", "palm")] == [
        "F1",
        "F2",
        "F2",
        "F2",
        None,
    ]
    with pytest.raises(bh.ModelError, match="opposition search .* does not support mimic joints"):
        knuckles(hand, np.array([0.3]))


def test_a_coupled_scenes_energy_is_its_free_twins(hand, free) -> None:
    """Scene.energy of a hand with mimic joints (Pinocchio's potential energy refuses them) equals that of the free
    hand at q_free = G q + c, v_free = G v, with a free box in both."""
    g, c = coupling_matrix(free)
    box = bh.Box(size=(0.02, 0.03, 0.04), mass=0.2, pose=pin.SE3(pin.rpy.rpyToMatrix(0.3, 0.2, 0.1), np.ones(3)))
    coupled, twin = bh.Scene(hand, [box]), bh.Scene(free, [box])
    q, v = coupled.initial_state(np.array([0.7]))
    v[:] = np.random.default_rng(5).normal(size=coupled.nv)
    q_free, v_free = twin.initial_state(g @ q[:1] + c)
    q_free[twin.nq_hand :], v_free[:] = q[coupled.nq_hand :], np.concatenate((g @ v[:1], v[coupled.nv_hand :]))
    assert coupled.energy(q, v) == pytest.approx(twin.energy(q_free, v_free), rel=1e-12)
