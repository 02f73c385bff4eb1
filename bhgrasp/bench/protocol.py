"""The grasp benchmark: approach -> close -> lift 10 cm -> shake in six directions -> place, per object.

One trial (:func:`~bhgrasp.bench.trial.run_trial`) puts a wrist-mounted BH8-280 (:func:`~bhgrasp.model.mount.mounted`)
palm down above an object (:mod:`~bhgrasp.bench.objects`) standing on a stand of its own footprint, and runs
DexGraspBench's shake protocol:

1. **approach** (0-1 s): the wrist descends 5 cm to the grasp height, the fingers pre-shaped (proximal 0.8 rad, or
   wider where that open hand would meet the object on its way down: :mod:`~bhgrasp.bench.opening`), the spread
   held in position mode; a guarded move: where the hand meets anything with more than :data:`APPROACH_GUARD` of
   its weight, the wrist stops there and the trial goes on from there;
2. **close** (from 1 s): the hand's own ``close()`` (libbarrett's CMD_CLOSE: each finger runs to a stall, then its
   puck idles and its worm holds it), force-limited (the finger pucks' MT lowered to :data:`GRIP_MT`, in both
   grasps: at full MT the power grasps of the development set's box, can and bottle loaded F3's proximal joint,
   held by its worm against F1 and F2 across the object, at 1.5-2.2 times its rating).  Where the hand stands, by
   rules of the object's shape, the same for both grasps (:mod:`~bhgrasp.bench.placement`,
   :mod:`~bhgrasp.bench.height`, :mod:`~bhgrasp.bench.closing`):

   - the spread (:func:`spread_of`): 0 for a box (F1 and F2 facing F3, each closing in a plane normal to the faces
     it presses; the box sits where the fingers reach it together), :data:`THREE_FINGER_SPREAD` for a sphere or a
     cylinder, its axis where F1's and F2's closing planes meet: each finger presses towards the axis in its own
     plane, so the back-drivable spread carries no torque, and the three fingers stand 120 deg apart;
   - the height: ``power`` - the lowest, from the knuckles on the object's top, at which every finger, closing,
     first touches the object's side (not its top face or rim, not a sphere above its equator: a finger landing
     there presses the object onto its stand) and touches the object before its stand; ``precision`` - the same,
     with every first touch on a fingertip (distal link).  Where no height up to 6 cm qualifies, the hand comes
     from the side instead (:mod:`~bhgrasp.bench.side`: palm sideways, moving in along its normal; F1 and F2 spread
     to face each other pinch the object in a horizontal plane, F3 stays open); where no side pinch qualifies
     either, the trial runs with the knuckles on the object's top and its failure says so;

3. **lift** (3-4 s): 10 cm up, then 0.5 s at rest; the object's pose in the palm frame at 3 s, the closed grasp
   before the lift, is the reference pose (a sag in the lift counts);
4. **shake** (4.5-16.5 s): an external force of 10 m newtons on the object's centre of mass along +x, -x, +y, -y,
   +z, -z (world), 2 s each, each from the held grasp: as DexGraspBench applies each direction's force afresh to
   the squeezed grasp, push k runs from the state and the controller as they were at 4.5 s, the wrist held there,
   and is recorded from 4.5 + 2 k s (:func:`~bhgrasp.bench.trial.run_protocol`).  Applied one after the other, each
   push but the first would start as the reversal or turn of the last, a step of up to twice the load the source
   applies, from wherever the last push left the object;
5. **place** (from 16.5 s): from the held grasp too, down toward 5 mm above the start (:data:`DROP`) until the stand
   pushes up, on the object or on a finger, with half the object's weight (what a wrist force sensor feels; 17.5 s
   at the latest), where the wrist stops and ``open()`` runs.

The stand: the environment stops the hand's links too, and on a table a top-down grasp of the low objects is
impossible - measured with the finger shapes, at every hand height at which the fingers reach the 5 cm box or the
3 cm flat box, some finger is 11-57 mm below the table top when it touches the object; a stand the object's size
lets the fingers pass beside it, as the thesis' pedestal does (:mod:`~bhgrasp.scenarios.box_grasp`).

``actuation``: ``barrett`` - :class:`~bhgrasp.sim.actuation.BarrettActuation` (four saturated pucks, TorqueSwitch,
self-locking worms) commanded through :class:`~bhgrasp.barrett.commands.BarrettDriver`; ``full`` - the idealised
hand of the thesis (eight independent, back-drivable joint torques): each finger closes with the joint torques the
real close delivers at stall (eta r MT on the proximal joint, a third of it on the distal) and keeps them, each
joint damped as the real motors damp theirs, the spread held by a PD.  The wrist follows its path under
:class:`~bhgrasp.controllers.mount.MountServo` in both (without load feedforward: the object starts on its stand).

Success (:mod:`~bhgrasp.bench.metrics`): the object is lifted; gripped once lifted (each of the n fingers that close
presses it with at least m g / (n mu), n presses that carry its weight by friction, and no distal joint rests on its
stop: a cage is not a grip); from the closed grasp before the lift through the shake it stays within 5 cm and 15 deg
of its reference pose in the palm frame (DexGraspBench's thresholds); the whole trial stays inside the real hand's
envelope (no contact force above :data:`FORCE_LIMIT`, no finger joint torque above its rating); and it is
``placed``, back on its stand after the release (within 2 mm of its resting height, the stand carrying half its
weight; among neighbours the table flush around it too). ``strict`` is ours, 1 cm and 5 deg. Every trial simulates a
fixed 18 s, or stops when its object falls below the stand. Contacts: :data:`STIFFNESS` and :data:`DT` (their
comment gives the reasons).

Constants chosen on the development set's trials (:data:`~bhgrasp.bench.objects.DEVELOPMENT_SET`): :data:`GRIP_MT`
and :data:`PRESHAPE`. The spread and the height are rules (above), which replaced two constants chosen there (a 0.45
rad spread for round objects, the knuckles 0 or 2 cm above the object's top); success rates out of sample are the
held-out set's (:data:`~bhgrasp.bench.objects.HELD_OUT_SET`, fixed before any of them was changed; its trials under
the former protocol were run as a baseline, then once under the spread and height rules and once more with F3's
later start, each run driven by the development set; nothing of the top-down rules was chosen on them). A second
held-out set, :data:`~bhgrasp.bench.objects.HELD_OUT_SET_2`, was fixed before any of its trials ran. The side pinch
(:mod:`~bhgrasp.bench.side`) was tried by hand on three held-out objects (tuna can, pudding box, tennis ball) and
the development set's flat box before it was written; its first form ran once on all three sets, and its mend was
worked out on the flat box after those results were seen (that run's records are not in the repository: its code is
superseded): the side pinch's held-out rates are not out of sample (the README says what is). A third held-out set,
:data:`~bhgrasp.bench.objects.HELD_OUT_SET_3`, was fixed after that mend and before any of its trials ran, and run once.
Its mini soccer ball, side-pinched there, then led to the wider opening (:mod:`~bhgrasp.bench.opening`, found on that
ball's geometry after its trials were seen), and a fourth held-out set, :data:`~bhgrasp.bench.objects.HELD_OUT_SET_4`,
was fixed before that rule was written and before any of its trials ran; its run, with the pushes then applied one
after the other, led to each push starting from the held grasp (its water bottle failed as a push reversed).  A fifth
held-out set, :data:`~bhgrasp.bench.objects.HELD_OUT_SET_5`, was fixed before that change and before any of its trials
ran; it then ran under a variant tried and dropped (a rest before each push), under the sequential shake and under the
shake as it stands (the README gives all three): its rate is the protocol's out-of-sample one, read with that history.
None of the last two sets' objects reaches into the open hand (each takes the pre-shape or the side pinch), so they do
not test the opening rule, whose only evidence is that ball, in sample.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from bhgrasp.bench.objects import BenchObject
from bhgrasp.errors import InputError

GRASPS = ("power", "precision")
ACTUATIONS = ("barrett", "full")
FRICTION = 0.8
APPROACH, CLOSE_AT, LIFT_AT, HELD_AT, SHAKE_TIME = 0.05, 1.0, 3.0, 4.5, 2.0  # [m], [s], [s], [s], [s]
PRESHAPE = 0.8  # [rad] proximal angle of the open hand (the distal follows at a third); wider where it would meet the
# object on its way down (bench.opening)
# [rad] the spread of round objects (spheres, upright cylinders), both grasps: the three fingers 120 deg apart, each
# closing in a vertical plane through the object's axis (bench.placement.grasp_offset puts the axis where F1's and F2's
# planes meet, 14.4 mm towards F3).  A finger pressing towards the axis then loads its back-drivable spread with no
# torque, and three equal fingertip forces balance; at other spreads they cannot both hold.  Derived, not tuned: the
# former ROUND_SPREAD = 0.45, chosen on the development set's trials, put the planes' meeting point about 60 mm off
# the object's axis, and the squeeze opened the spread by 0.1 rad, which a push then closed, letting the ball out
THREE_FINGER_SPREAD = math.pi / 3
LIFT = 0.10  # [m]
# The approach is a guarded move, as an arm's is on a wrist force sensor: where the hand meets anything (the object,
# its stand, the table, a neighbour) with more than this fraction of its own weight, the wrist stops there and the
# trial goes on from there (the close on time, the lift and place from where it stopped).  Half, as the place stops
# where the stand takes half the object's weight: the fraction is a sensor's threshold, not chosen on any trial.
# An unguarded approach drives a finger on into whatever it meets with the arm's force, which no hand resists
# (tests/test_bench_neighbours.py measures it on a post).  The guard cannot soften the touch itself, an impact at the
# approach's speed in the step it happens; it arms once the hand reads below it (a start in contact is no meeting)
APPROACH_GUARD = 0.5
RELEASE = 0.5  # [s] of open() after the place
DROP = 0.005  # [m] the place stops this far above the lift's start: a stiff wrist setting the held object onto the
# stand would press it there through the locked fingers
# The contact law and step: chosen when the drive (before its calibration) squeezed with hundreds of newtons, which
# the default 1e4 N/m would meet with centimetres of penetration; 3e5 N/m gives about 1 mm there, 0.1 mm at the
# calibrated drive's 20-40 N.  The contact's geometry is explicit in the step, so omega dt must stay below ~1 for the
# lightest link, a distal (0.042 kg): omega = 2700 rad/s, 0.67 at 0.25 ms.  Measured: 1e6 N/m diverged in jammed
# grasps at 1 ms and 0.5 ms, and while opening on the can at 0.25 ms.
DT = 2.5e-4  # [s]
STIFFNESS = 3e5  # [N/m] normal; tangential a tenth; damping 2e-3 s of each
DIRECTIONS = ("+x", "-x", "+y", "-y", "+z", "-z")
PUSH = 10.0  # [N per kg of the object] the shake's push along each direction in turn (bench.trial.shake_force)
GRIP_MT = 600.0  # puck torque units (0.0058 N m at the motor, 27 % of MT): the force-limited close (both grasps)
LOOSE, STRICT = (0.05, math.radians(15.0)), (0.01, math.radians(5.0))  # [m], [rad]
# The real hand's envelope (bhgrasp.barrett.transmission, urdf/README.md): Barrett's stalled fingertip force is
# 15-25 N; a trial in which any contact (on the object or the stand) passes twice that, or a finger joint carries more
# than its rating (the URDF's effort limit: the pucks' MT through ideal gears), needed what the hand cannot give
FORCE_LIMIT = 2 * 25.0  # [N]
STAND = "pedestal"  # the stand's body name
DISTURBED = 0.005  # [m] among neighbours (bench.neighbours): one moved further than this from where it settled


@dataclass(frozen=True)
class Trial:
    """One benchmark case: an object, a grasp ('power' or 'precision') and an actuation ('barrett' or 'full').

    ``spread`` [rad] replaces the grasp's pre-shape spread (:func:`spread_of`), e.g. to measure how much it matters;
    such a trial is grasped from above, never pinched from the side (:mod:`~bhgrasp.bench.side`).
    """

    item: BenchObject
    grasp: str
    actuation: str = "barrett"
    spread: float | None = None
    table: bool = False  # the stand flush with a table around it (a trial among neighbours, bench.neighbours)

    def __post_init__(self) -> None:
        if self.grasp not in GRASPS:
            raise InputError(f"`grasp` must be one of {GRASPS}, got {self.grasp!r}")
        if self.actuation not in ACTUATIONS:
            raise InputError(f"`actuation` must be one of {ACTUATIONS}, got {self.actuation!r}")
        if not isinstance(self.table, bool):
            raise InputError(f"`table` must be True or False, got {self.table!r}")
        if self.spread is not None and not (math.isfinite(self.spread) and 0.0 <= self.spread <= math.pi):
            raise InputError(f"`spread` must be in [0, pi] rad (the BH8-280's spread range), got {self.spread!r}")

    @property
    def preshape_spread(self) -> float:
        """The spread [rad] the hand takes before closing: ``spread``, or the grasp's own (:func:`spread_of`)."""
        return spread_of(self.item) if self.spread is None else float(self.spread)


def push_axes(heading: float = 0.0) -> np.ndarray:
    """(6, 3) unit world directions of the shake's pushes, :data:`DIRECTIONS` turned ``heading`` [rad] about +z."""
    axes = np.vstack([np.eye(3)[[0, 0, 1, 1, 2, 2]] * np.array([1, -1, 1, -1, 1, -1])[:, None]])
    if heading != 0.0:
        axes = axes @ pin.rpy.rpyToMatrix(0.0, 0.0, heading).T
    return axes


def spread_of(item: BenchObject) -> float:
    """The pre-shape spread [rad], the same for both grasps: 0 for a box, else :data:`THREE_FINGER_SPREAD`.

    A sphere or a cylinder takes the three-finger spread.  At 0, F1 and F2 face F3 across the box, each closing in a
    plane normal to the faces it presses: no spread torque.
    """
    return 0.0 if item.kind == "box" else THREE_FINGER_SPREAD


__all__ = [
    "ACTUATIONS",
    "APPROACH",
    "CLOSE_AT",
    "DIRECTIONS",
    "DISTURBED",
    "DROP",
    "DT",
    "FRICTION",
    "GRASPS",
    "GRIP_MT",
    "HELD_AT",
    "LIFT",
    "LIFT_AT",
    "LOOSE",
    "PRESHAPE",
    "PUSH",
    "RELEASE",
    "SHAKE_TIME",
    "STAND",
    "STIFFNESS",
    "STRICT",
    "THREE_FINGER_SPREAD",
    "Trial",
    "push_axes",
    "spread_of",
]
