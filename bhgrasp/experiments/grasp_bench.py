"""The grasp benchmark: approach -> close -> lift 10 cm -> shake in six directions -> place, per object.

One trial (:func:`run_trial`) puts a wrist-mounted BH8-280 (:func:`~bhgrasp.mount.mounted`) palm down above an
object (:mod:`~bhgrasp.experiments.bench_objects`) standing on a stand of its own footprint, and runs DexGraspBench's
shake protocol:

1. **approach** (0-1 s): the wrist descends 5 cm to the grasp height, the fingers pre-shaped (proximal 0.8 rad),
   the spread held in position mode, the hand shifted along its F3 axis so that the fingers reach the object
   together (:mod:`~bhgrasp.experiments.bench_placement`);
2. **close** (from 1 s): ``power`` - the hand's own ``close()`` (libbarrett's CMD_CLOSE: each finger runs to a stall,
   then its puck idles and its worm holds it) at full puck torque, the knuckles touching the object's top;
   ``precision`` - the same close force-limited (puck MT lowered to :data:`PRECISION_MT`), the knuckles 2 cm
   above it; a power grasp whose closing fingers would meet the object's stand before the object is raised until
   they keep clear of it (:func:`~bhgrasp.experiments.bench_placement.grasp_clearance`); spheres, and cylinders in
   the precision grasp, take a 0.45 rad spread (:data:`ROUND_SPREAD`), boxes and the cylinders' power grasp 0 (F1,
   F2 facing F3);
3. **lift** (3-4 s): 10 cm up, then 0.5 s at rest; the object's pose in the palm frame at 4.5 s is the held pose;
4. **shake** (4.5-16.5 s): an external force of 10 m newtons on the object's centre of mass along +x, -x, +y, -y,
   +z, -z (world), 2 s each;
5. **place** (16.5-17.5 s): down to 5 mm above the start (:data:`DROP`), then ``open()`` for 0.5 s.

The stand: the environment stops the hand's links too, and on a table a top-down grasp of the low objects is
impossible - measured with the finger shapes, at every hand height at which the fingers reach the 5 cm box or the
3 cm flat box, some finger is 11-57 mm below the table top when it touches the object; a stand the object's size
lets the fingers pass beside it, as the thesis' pedestal does (:mod:`~bhgrasp.experiments.box_grasp`).

``actuation``: ``barrett`` - :class:`~bhgrasp.sim.actuation.BarrettActuation` (four saturated pucks, TorqueSwitch,
self-locking worms) commanded through :class:`~bhgrasp.barrett.commands.BarrettDriver`; ``full`` - the idealised
hand of the thesis (eight independent, back-drivable joint torques): each finger closes with the joint torques the
real close delivers at stall (eta r MT on the proximal joint, a third of it on the distal) and keeps them, each
joint damped as the real motors damp theirs, the spread held by a PD.  The wrist follows its path under
:class:`~bhgrasp.controllers.mount.MountServo` in both (without load feedforward: the object starts on its stand).

Success: through the shake the object stays within 5 cm and 15 deg of its held pose in the palm frame
(DexGraspBench's thresholds); ``strict`` is ours, 1 cm and 5 deg; ``placed``: a successful trial whose object is
back at its resting height after the release.  Every trial simulates a fixed 18 s, or stops when its object falls
below the stand.  Contacts: :data:`STIFFNESS` and :data:`DT` (their comment gives the reasons).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

import bhgrasp as bh
from bhgrasp.barrett.commands import BarrettDriver
from bhgrasp.barrett.pucks import FINGER_PUCK
from bhgrasp.barrett.transmission import PROXIMAL_RATIO, WORM_EFFICIENCY, BarrettTransmission
from bhgrasp.controllers.mount import MountServo
from bhgrasp.errors import InputError
from bhgrasp.experiments.bench_objects import BenchObject
from bhgrasp.experiments.bench_placement import STAND_HEIGHT, grasp_clearance, grasp_offset, hand_depth
from bhgrasp.mount import MountReference, mounted
from bhgrasp.objects import FixedBox
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation, FullyActuated
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene
from bhgrasp.trajectories import PosePath

GRASPS = ("power", "precision")
ACTUATIONS = ("barrett", "full")
FRICTION = 0.8
APPROACH, CLOSE_AT, LIFT_AT, HELD_AT, SHAKE_TIME = 0.05, 1.0, 3.0, 4.5, 2.0  # [m], [s], [s], [s], [s]
PRESHAPE = 0.8  # [rad] proximal angle of the open hand (the distal follows at a third)
# [rad] the spread of round objects' fingertip grasps, measured under the real drive (barrett, precision): at spread 0
# F1 and F2 pinch a cylinder 27 deg either side of its back, its wedge opens the back-drivable spread (0 -> 0.07 rad
# on the can as the grip closes), and under a +-x push the can turns 17 deg about the pinch axis; the can and the
# bottle hold at 0.3-0.6 rad, the 45 mm ball at 0.3-0.6, the 35 mm ball only at 0.4-0.5 (at 0.3 it is not lifted,
# from 0.52 it turns out between F1 and F2 under the +x push; at 60 deg, the spherical grasp, it slips out between
# them, and at 90 deg three of the four sphere trials failed).  Spheres take it in the power grasp too (both balls
# hold there); the cylinders' power grasp keeps spread 0, the hand's cylindrical wrap
ROUND_SPREAD = 0.45
LIFT = 0.10  # [m]
RELEASE = 0.5  # [s] of open() after the place
DROP = 0.005  # [m] the place stops this far above the lift's start: a stiff wrist setting the held object onto the
# stand would press it there through the locked fingers
# The contact law and step: the power close squeezes with hundreds of newtons, which the default 1e4 N/m would meet
# with centimetres of penetration; 3e5 N/m gives about 1 mm.  The contact's geometry is explicit in the step, so
# omega dt must stay below ~1 for the lightest link, a distal (0.042 kg): omega = 2700 rad/s, 0.67 at 0.25 ms.
# Measured: 1e6 N/m diverged in jammed grasps at 1 ms and 0.5 ms, and while opening on the can at 0.25 ms.
DT = 2.5e-4  # [s]
STIFFNESS = 3e5  # [N/m] normal; tangential a tenth; damping 2e-3 s of each
DIRECTIONS = ("+x", "-x", "+y", "-y", "+z", "-z")
PRECISION_MT = 600.0  # puck torque units (0.03 N m at the motor): the force-limited close
LOOSE, STRICT = (0.05, math.radians(15.0)), (0.01, math.radians(5.0))  # [m], [rad]
KNUCKLE_CLEARANCE = {"power": 0.0, "precision": 0.02}  # [m] the knuckles above the object's top
STAND = "pedestal"  # the stand's body name


@dataclass(frozen=True)
class Trial:
    """One benchmark case: an object, a grasp ('power' or 'precision') and an actuation ('barrett' or 'full').

    ``spread`` [rad] replaces the grasp's pre-shape spread (:func:`spread_of`), e.g. to measure how much it matters.
    """

    item: BenchObject
    grasp: str
    actuation: str = "barrett"
    spread: float | None = None

    def __post_init__(self) -> None:
        if self.grasp not in GRASPS:
            raise InputError(f"`grasp` must be one of {GRASPS}, got {self.grasp!r}")
        if self.actuation not in ACTUATIONS:
            raise InputError(f"`actuation` must be one of {ACTUATIONS}, got {self.actuation!r}")
        if self.spread is not None and not (math.isfinite(self.spread) and 0.0 <= self.spread <= math.pi):
            raise InputError(f"`spread` must be in [0, pi] rad (the BH8-280's spread range), got {self.spread!r}")

    @property
    def preshape_spread(self) -> float:
        """The spread [rad] the hand takes before closing: ``spread``, or the grasp's own (:func:`spread_of`)."""
        return spread_of(self.item, self.grasp) if self.spread is None else float(self.spread)


def spread_of(item: BenchObject, grasp: str = "power") -> float:
    """The pre-shape spread [rad]: :data:`ROUND_SPREAD` for spheres and for cylinders' ``precision`` grasp, else 0.

    At 0, F1 and F2 face F3.
    """
    round_grasp = item.kind == "sphere" or (item.kind == "cylinder" and grasp == "precision")
    return ROUND_SPREAD if round_grasp else 0.0


def idealised_damping(hand: bh.Hand) -> np.ndarray:
    """The idealised hand's joint damping [N m s/rad], as the BH8-280's motors damp the coordinates they drive.

    eta b_m r^2 with 125:1 on the proximal, 93.75:1 on the distal and 17.5:1 on the spread joints; none on the mount.
    """
    drive = BarrettTransmission(hand)
    damping = drive.joint_damping([0, 0, 0])  # armed: the spread and the proximal joints
    damping[drive.distal] = drive.joint_damping([1, 1, 1])[drive.distal]  # broken away: the distal joints
    damping[drive.spread[1]] = damping[drive.spread[0]]
    return damping


def setup(trial: Trial, dt: float = DT):
    """The simulator, its start state, the mounted hand and the wrist path of a trial."""
    item = trial.item
    top = 2 * item.half_extents[2]
    clearance, spread = KNUCKLE_CLEARANCE[trial.grasp], trial.preshape_spread
    if trial.grasp == "power":  # the fingers off the stand (precision keeps 2 cm: at 46 mm the box slips, full)
        clearance = grasp_clearance(item, spread, clearance, PRESHAPE)
    grasp_height = top + clearance + hand_depth(spread, PRESHAPE)  # the hand base
    rotation = pin.rpy.rpyToMatrix(math.pi, 0.0, 0.0)  # palm down
    offset = np.array([0.0, grasp_offset(item, spread, clearance, PRESHAPE), 0.0])
    base = pin.SE3(rotation, np.array([0.0, 0.0, grasp_height + APPROACH]) - rotation @ offset)  # fingers together
    hand = mounted(bh.BarrettHand(base_placement=base))
    width = 2 * item.half_extents[:2]  # the stand: the object's footprint
    pedestal = FixedBox(size=(*width, STAND_HEIGHT), pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, -0.5 * STAND_HEIGHT])),
                        friction=FRICTION, name=STAND)  # fmt: skip
    scene = Scene(hand, [item.body(FRICTION)], environment=[pedestal])
    if trial.actuation == "barrett":
        actuation = BarrettActuation(hand, saturate=True)
    else:  # the same motors' damping on each joint, reflected as through the worms (module docstring)
        actuation = FullyActuated(hand, damping=idealised_damping(hand))
    law = SpringDamper(
        stiffness=STIFFNESS, damping=2e-3 * STIFFNESS, friction=FRICTION, tangential_stiffness=0.1 * STIFFNESS,
        tangential_damping=2e-4 * STIFFNESS,
    )  # fmt: skip
    simulator = Simulator(scene, dt=dt, contact=law, actuation=actuation)
    q = hand.neutral()
    for finger in hand.fingers:
        q[hand.joint_index(f"{finger}_proximal")], q[hand.joint_index(f"{finger}_distal")] = PRESHAPE, PRESHAPE / 3
    q[[hand.joint_index("F1_spread"), hand.joint_index("F2_spread")]] = spread
    down, up = np.array([0, 0, -APPROACH, 0, 0, 0]), np.array([0, 0, LIFT, 0, 0, 0])
    shake = 6 * SHAKE_TIME
    moves = [(down, CLOSE_AT), (np.zeros(6), LIFT_AT - CLOSE_AT), (up, 1.0), (np.zeros(6), HELD_AT - LIFT_AT - 1.0),
             (np.zeros(6), shake), (-(LIFT - DROP) / LIFT * up, 1.0)]  # fmt: skip
    path = MountReference(PosePath(base, moves), hand.base_placement)
    return simulator, simulator.initial_state(q), hand, path


class BenchController:
    """The trial's commands: the wrist on its path (MountServo), the fingers by the driver or by joint torques."""

    def __init__(self, trial: Trial, hand: bh.Hand, path: MountReference) -> None:
        self.trial, self.hand = trial, hand
        self.servo = MountServo(hand, path, fingers=lambda t, s: np.zeros(hand.nv), compensate_load=False)
        self.spread = [hand.joint_index("F1_spread"), hand.joint_index("F2_spread")]
        self.place_at = HELD_AT + 6 * SHAKE_TIME + 1.0
        self.log: dict = {}
        mt = PRECISION_MT if trial.grasp == "precision" else FINGER_PUCK.MT  # the finger pucks' torque limit
        if trial.actuation == "barrett":
            self.driver = BarrettDriver(hand, finger=FINGER_PUCK.with_(MT=mt))
            self.driver.script([(0.0, "set_position_mode", "SPREAD"), (CLOSE_AT, "close", "GRASP"),
                                (self.place_at, "open", "GRASP")])  # fmt: skip
            self.log = self.driver.log
        else:
            self.close_torque = WORM_EFFICIENCY * PROXIMAL_RATIO * mt / FINGER_PUCK.IPNM  # the real close's stall

    def reset(self, state: bh.State) -> None:
        """Start a trial at ``state`` (the driver's script, the spread hold)."""
        self.servo.reset(state)
        if self.trial.actuation == "barrett":
            self.driver.reset(state)
        else:
            self.spread_hold = float(state.q[self.spread[0]])

    def __call__(self, t: float, state: bh.State) -> np.ndarray:
        """The inputs of the trial's actuation: puck torques (or joint torques), then the wrist's."""
        mount = self.servo(t, state)[:6]
        if self.trial.actuation == "barrett":
            u = self.driver(t, state)
            u[4:] = mount
            return u
        tau = np.zeros(self.hand.nv)
        tau[:6] = mount
        sign = 0.0 if t < CLOSE_AT else (1.0 if t < self.place_at else -1.0)
        for finger in self.hand.fingers:
            tau[self.hand.joint_index(f"{finger}_proximal")] = sign * self.close_torque
            tau[self.hand.joint_index(f"{finger}_distal")] = sign * self.close_torque / 3.0
        error = self.spread_hold - state.q[self.spread[0]]  # a stiff PD [N m/rad, N m s/rad] holds the spread
        tau[self.spread] = 2.0 * error - 0.05 * state.v[self.spread[0]]
        return tau


def shake_force(mass: float):
    """The shake, ``t -> (1, 3)`` world force [N]: 10 m newtons along each of :data:`DIRECTIONS` for 2 s."""
    axes = np.vstack([np.eye(3)[[0, 0, 1, 1, 2, 2]] * np.array([1, -1, 1, -1, 1, -1])[:, None]])
    none = np.zeros((1, 3))

    def force(t: float) -> np.ndarray:
        k = math.floor((t - HELD_AT) / SHAKE_TIME)
        return 10.0 * mass * axes[k][None, :] if 0 <= k < 6 else none

    return force


def simulate_trial(trial: Trial, dt: float = DT, record_every: int = 40, duration: float | None = None):
    """The trial's trajectory (a sample every ``record_every`` steps) and its mounted hand.

    ``duration`` [s] cuts the protocol short (default: all of it).
    """
    simulator, state, hand, path = setup(trial, dt)
    controller = BenchController(trial, hand, path)
    duration = HELD_AT + 6 * SHAKE_TIME + 1.0 + RELEASE if duration is None else duration
    trajectory = simulator.run(controller, duration, state=state, progress=False, record_every=record_every,
                               object_forces=shake_force(trial.item.mass), until=gone)  # fmt: skip
    return trajectory, hand


def run_trial(trial: Trial, dt: float = DT, record_every: int = 40) -> dict:
    """Run one trial (module docstring) and return its record (SI units; rotations [rad], forces [N])."""
    from bhgrasp.experiments.bench_metrics import evaluate  # (it imports this module's protocol constants)

    trajectory, hand = simulate_trial(trial, dt, record_every)
    return evaluate(trial, trajectory, hand)


def gone(state: bh.State) -> bool:
    """Whether the object fell: below the stand's top (the trial stops there)."""
    return bool(state.object_poses[0].translation[2] < -0.05)


__all__ = [
    "ACTUATIONS", "DIRECTIONS", "GRASPS", "STAND", "BenchController", "Trial", "gone", "run_trial", "setup",
    "shake_force", "simulate_trial", "spread_of",
]  # fmt: skip
