"""One grasp-benchmark trial (:mod:`~bhgrasp.bench.protocol`): the scene, the controller, the run and its record."""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Callable, Sequence

import numpy as np
import pinocchio as pin

import bhgrasp as bh
from bhgrasp.barrett.commands import BarrettDriver
from bhgrasp.barrett.pucks import FINGER_PUCK
from bhgrasp.barrett.transmission import PROXIMAL_RATIO, WORM_EFFICIENCY, BarrettTransmission
from bhgrasp.bench.closing import finger_starts
from bhgrasp.bench.heading import hand_base
from bhgrasp.bench.metrics import GRAVITY, evaluate
from bhgrasp.bench.protocol import (
    APPROACH,
    APPROACH_GUARD,
    CLOSE_AT,
    DROP,
    DT,
    FRICTION,
    GRIP_MT,
    HELD_AT,
    LIFT,
    LIFT_AT,
    PUSH,
    RELEASE,
    SHAKE_TIME,
    STIFFNESS,
    Trial,
    push_axes,
)
from bhgrasp.bench.side import closing_fingers, trial_opening, trial_spread, way_in
from bhgrasp.bench.table import NEIGHBOUR_DRAG, Clutter, stand_of, supports
from bhgrasp.controllers.mount import MountServo
from bhgrasp.data.trajectory import Trajectory
from bhgrasp.errors import InputError
from bhgrasp.model.mount import mount_pose, mounted
from bhgrasp.motion.held import HeldReference
from bhgrasp.motion.pose_references import PosePath
from bhgrasp.motion.wrist import MountReference
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation, FullyActuated
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene


def idealised_damping(hand: bh.Hand) -> np.ndarray:
    """The idealised hand's joint damping [N m s/rad], as the BH8-280's motors damp the coordinates they drive.

    eta b_m r^2 with 125:1 on the proximal, 93.75:1 on the distal and 17.5:1 on the spread joints; none on the mount.
    """
    drive = BarrettTransmission(hand)
    damping = drive.joint_damping([0, 0, 0])  # armed: the spread and the proximal joints
    damping[drive.distal] = drive.joint_damping([1, 1, 1])[drive.distal]  # broken away: the distal joints
    damping[drive.spread[1]] = damping[drive.spread[0]]
    return damping


def contact_law() -> SpringDamper:
    """The benchmark's stiff contact law, from :data:`~bhgrasp.bench.protocol.STIFFNESS` and ``FRICTION``.

    Normal stiffness STIFFNESS, tangential a tenth of it, damping 2e-3 s of each.
    """
    return SpringDamper(
        stiffness=STIFFNESS,
        damping=2e-3 * STIFFNESS,
        friction=FRICTION,
        tangential_stiffness=0.1 * STIFFNESS,
        tangential_damping=2e-4 * STIFFNESS,
    )


def setup(trial: Trial, dt: float = DT, clutter: Clutter | None = None, start_check: str | None = None):
    """The simulator, its start state, the mounted hand and the wrist path of a trial.

    ``clutter``: the object where it settled and its neighbours on the table around its stand, and how high over
    them the hand starts (:mod:`~bhgrasp.bench.neighbours`); default: the object alone on its stand.

    ``start_check``: the simulator's (default: ``"warn"`` alone, ``"error"`` among neighbours).

    Raises:
        InputError: Among neighbours, a start that interpenetrates (e.g. a low object's fingers inside the table), or
            a trial without ``table``.
    """
    if clutter is not None and not trial.table:
        raise InputError("a trial among neighbours stands flush with a table: give it as Trial(..., table=True)")
    item = trial.item
    spread, opening = trial_spread(trial), trial_opening(trial)
    approach = APPROACH if clutter is None else clutter.approach  # [m] the open hand starts this far above
    heading = 0.0 if clutter is None else clutter.heading
    base = hand_base(trial, approach, heading)  # fingers together
    hand = mounted(bh.BarrettHand(base_placement=base))
    pedestal = stand_of(item)
    if clutter is None:
        scene = Scene(hand, [item.body(FRICTION)], environment=[pedestal])
    else:
        drag = (0.0, *[NEIGHBOUR_DRAG] * (len(clutter.objects) - 1))  # no rolling on forever of a neighbour
        scene = Scene(hand, clutter.objects, environment=[pedestal, *clutter.table], object_drag=drag)
    if trial.actuation == "barrett":
        actuation = BarrettActuation(hand, saturate=True)
    else:  # the same motors' damping on each joint, reflected as through the worms (bench.protocol)
        actuation = FullyActuated(hand, damping=idealised_damping(hand))
    check = start_check or ("warn" if clutter is None else "error")  # among neighbours: no trial from inside
    simulator = Simulator(scene, dt=dt, contact=contact_law(), actuation=actuation, start_check=check)
    q = hand.neutral()
    for finger in hand.fingers:
        q[hand.joint_index(f"{finger}_proximal")], q[hand.joint_index(f"{finger}_distal")] = opening, opening / 3
    q[[hand.joint_index("F1_spread"), hand.joint_index("F2_spread")]] = spread
    turn = pin.rpy.rpyToMatrix(0.0, 0.0, heading)
    inward, up = np.array([*(approach * turn @ way_in(trial)), 0, 0, 0]), np.array([0, 0, LIFT, 0, 0, 0])
    moves = [  # the shake's pushes run from the held grasp with the wrist held there (run_protocol)
        (inward, CLOSE_AT),
        (np.zeros(6), LIFT_AT - CLOSE_AT),
        (up, 1.0),
        (np.zeros(6), HELD_AT - LIFT_AT - 1.0),
        (-(LIFT - DROP) / LIFT * up, 1.0),
    ]
    path = MountReference(PosePath(base, moves), hand.base_placement)
    return simulator, simulator.initial_state(q), hand, path


class BenchController:
    """The trial's commands: the wrist on its path (MountServo), the fingers by the driver or by joint torques.

    On its own clock: approach, close and lift to HELD_AT, then the place.  The shake's pushes run on copies taken
    at HELD_AT that hold the wrist there (:meth:`holding`; :func:`run_protocol`).
    """

    def __init__(
        self, trial: Trial, hand: bh.Hand, path: MountReference, pairs: Sequence[tuple[str, str]] = ()
    ) -> None:
        """The trial's commands along ``path``.

        ``pairs``: the scene's collision pairs' (body a, body b) names, in order; where the guarded approach stops,
        the hand's hardest contact is logged by its pair's index there (``approach_met_pair``).
        """
        self.trial, self.hand = trial, hand
        self.planned, self.path = path, HeldReference(path)
        self.guard = APPROACH_GUARD * pin.computeTotalMass(hand.model) * GRAVITY  # [N] what stops the approach
        self.armed = False  # the guard arms at the first stepped reading below it (a start in contact is no meeting)
        self.approach_stopped = math.nan  # [s] when the guard stopped it (NaN: it ran its course)
        self.links = frozenset(frame.name for frame in hand.model.frames)  # the hand's bodies
        self.pairs = {(str(a), str(b)): index for index, (a, b) in enumerate(pairs)}
        self.servo = MountServo(hand, self.path, fingers="zero", compensate_load=False)
        self.spread = [hand.joint_index("F1_spread"), hand.joint_index("F2_spread")]
        self.place_from = HELD_AT  # the place's descent starts (its own run from the held grasp: run_protocol)
        self.place_at = self.place_from + 1.0  # open here, or where the stand takes the object's weight first
        self.holds = False  # a copy for a push from the held grasp (holding)
        self.set_down = 0.5 * trial.item.mass * GRAVITY  # [N] the stand's push that ends the descent
        self.stand = supports(trial)  # the stand, and the table around it among neighbours
        self.log: dict = {}
        mt = GRIP_MT  # the force-limited close, in both grasps
        closing = closing_fingers(trial)  # all three, or a side pinch's F1 and F2
        starts = finger_starts(trial)  # [s] after CLOSE_AT: all 0 but on the closing planes (bench.closing)
        self.starts = {finger: starts[finger] for finger in closing}
        idle = [finger for finger in hand.fingers if finger not in closing]
        self.idle = [hand.joint_index(f"{finger}_{link}") for finger in idle for link in ("proximal", "distal")]
        if trial.actuation == "barrett":
            self.driver = BarrettDriver(hand, finger=FINGER_PUCK.with_(MT=mt))
            self.driver.script([(0.0, "set_position_mode", "SPREAD"), *self._closes()])
            self.log = self.driver.log
        else:
            self.close_torque = WORM_EFFICIENCY * PROXIMAL_RATIO * mt / FINGER_PUCK.IPNM  # the real close's stall

    def _closes(self) -> list[tuple[float, str, str | list[str]]]:
        """The driver's close commands: ``close("GRASP")`` at CLOSE_AT, or each closing finger at its start."""
        if len(self.starts) == 3 and not any(self.starts.values()):
            return [(CLOSE_AT, "close", "GRASP")]
        starts = sorted(set(self.starts.values()))
        return [(CLOSE_AT + s, "close", [f for f, t in self.starts.items() if t == s]) for s in starts]

    def _set_down(self, state: bh.State) -> bool:
        """Whether the stand pushes up, on the object or on a finger, with at least half the object's weight.

        What a wrist force sensor feels when the held load meets the stand, whichever touches it first.
        """
        pushes = [f for f, pair in zip(state.contact_forces, state.contact_bodies) if self.stand & set(pair)]
        return float(np.sum(pushes, axis=0)[2]) >= self.set_down if pushes else False

    def _meets(self, state: bh.State) -> bool:
        """Whether the hand meets anything with more than :attr:`guard`: the wrist force sensor's reading.

        The sum of the contact forces on the hand's links (the hand's own weight is the arm's, not a contact's).
        """
        links, total = self.links, np.zeros(3)
        for force, (a, b) in zip(state.contact_forces, state.contact_bodies):
            sign = (b in links) - (a in links)  # the force is on b, its opposite on a
            if sign:
                total += sign * force
        return bool(total @ total > self.guard**2)

    def _met(self, state: bh.State) -> int:
        """The index in :attr:`pairs` of the hand's contact pressing hardest (-1: the pairs are not known)."""
        pressed = [
            (float(np.linalg.norm(force)), self.pairs.get((a, b), -1))
            for force, (a, b) in zip(state.contact_forces, state.contact_bodies)
            if (a in self.links) != (b in self.links)
        ]
        return max(pressed)[1] if pressed else -1

    def _follow(self, reference: MountReference, state: bh.State) -> None:
        """Drive the wrist along ``reference`` from now on (the compiled servo copies its path: a new servo)."""
        self.path.reference = reference
        self.servo = MountServo(self.hand, self.path, fingers="zero", compensate_load=False, engine=self.servo.engine)
        self.servo.reset(state)

    def _stop_approach(self, t: float, state: bh.State) -> None:
        """Drop the rest of the approach at ``t`` [s].

        The wrist rests where it is (as an arm's guarded move stops it, not where its reference had gone on to)
        until the close, and every later move (the lift, the place) runs from there.
        """
        planned = self.planned.pose
        here = self.planned.origin * mount_pose(state.q[:6])  # where the wrist is, not where it was headed
        later = [(segment.offset, segment.duration) for segment in planned.segments[1:]]
        path = PosePath(here, [(np.zeros(6), CLOSE_AT - t), *later], delay=t)
        self._follow(MountReference(path, self.planned.origin), state)
        self.approach_stopped = t
        self.log["approach_stopped"], self.log["approach_met_pair"] = t, float(self._met(state))

    def holding(self) -> BenchController:
        """A copy of this controller, as it stands, for a push from the held grasp.

        It holds the wrist where the lift leaves it (at HELD_AT) and never places, nor opens the idealised hand's
        fingers.
        """
        held = copy.deepcopy(self)
        held.holds = True
        held.path.hold(HELD_AT)
        held.place_at = math.inf  # the idealised hand's fingers keep closing
        return held

    def reset(self, state: bh.State) -> None:
        """Start a trial at ``state`` (the driver's script, the spread hold); a :meth:`holding` copy keeps holding."""
        if not self.holds:
            self.path.release()
            if not math.isnan(self.approach_stopped):
                self._follow(self.planned, state)
                self.approach_stopped = math.nan
            self.armed = False
            for name in ("approach_stopped", "approach_met_pair"):
                self.log.pop(name, None)
            self.place_at = self.place_from + 1.0
        self.servo.reset(state)
        if self.trial.actuation == "barrett":
            self.driver.reset(state)
        else:
            self.spread_hold = float(state.q[self.spread[0]])
            self.open_hold = {j: float(state.q[j]) for j in self.idle}

    def __call__(self, t: float, state: bh.State) -> np.ndarray:
        """The inputs of the trial's actuation: puck torques (or joint torques), then the wrist's."""
        if t < CLOSE_AT and math.isnan(self.approach_stopped):  # a guarded move
            meets = len(state.contact_forces) > 0 and self._meets(state)
            if self.armed and meets:
                self._stop_approach(t, state)  # the hand met something on its way
            self.armed = self.armed or (t > 0.0 and not meets)  # the start state carries no contacts yet
        if self.path.held is None and t >= self.place_from and (t >= self.place_at or self._set_down(state)):
            self.path.hold(t)  # the wrist stops where the stand takes the object, and the hand opens
            self.place_at = t
            if self.trial.actuation == "barrett":
                self.driver.open("GRASP")
        mount = self.servo(t, state)[:6]
        if self.trial.actuation == "barrett":
            u = self.driver(t, state)
            u[4:] = mount
            return u
        tau = np.zeros(self.hand.nv)
        tau[:6] = mount
        for finger in self.hand.fingers:
            start = self.starts.get(finger)  # None: a side pinch's F3, left open
            sign = 0.0 if start is None or t < CLOSE_AT + start else (1.0 if t < self.place_at else -1.0)
            tau[self.hand.joint_index(f"{finger}_proximal")] = sign * self.close_torque
            tau[self.hand.joint_index(f"{finger}_distal")] = sign * self.close_torque / 3.0
        error = self.spread_hold - state.q[self.spread[0]]  # a stiff PD [N m/rad, N m s/rad] holds the spread
        tau[self.spread] = 2.0 * error - 0.05 * state.v[self.spread[0]]
        for j, hold in self.open_hold.items():  # a side pinch's open F3, as its worm holds the real one: the same PD
            tau[j] = 2.0 * (hold - state.q[j]) - 0.05 * state.v[j]
        return tau


def shake_force(mass: float, objects: int = 1, heading: float = 0.0):
    """The shake, ``t -> (objects, 3)`` world force [N]: 10 m newtons along each direction for 2 s, on object 0.

    The directions: :data:`~bhgrasp.bench.protocol.DIRECTIONS`, turned ``heading`` [rad] about +z with the hand
    (:mod:`~bhgrasp.bench.heading`: the same pushes in the hand's frame); the other objects (neighbours) are not
    pushed.
    """
    axes = push_axes(heading)
    none = np.zeros((objects, 3))

    def force(t: float) -> np.ndarray:
        k = math.floor((t - HELD_AT) / SHAKE_TIME)
        if not 0 <= k < 6:
            return none
        pushed = none.copy()
        pushed[0] = PUSH * mass * axes[k]
        return pushed

    return force


def simulate_trial(
    trial: Trial, dt: float = DT, record_every: int = 40, duration: float | None = None, clutter: Clutter | None = None
):
    """The trial's trajectory (a sample every ``record_every`` steps) and its mounted hand.

    ``duration`` [s] cuts the protocol short (default: all of it); ``clutter`` as :func:`setup` takes it.
    """
    simulator, state, hand, path = setup(trial, dt, clutter)
    controller = BenchController(trial, hand, path, [(p.body_a, p.body_b) for p in simulator.scene.pairs])
    heading = 0.0 if clutter is None else clutter.heading
    return run_protocol(simulator, state, controller, record_every, duration, heading), hand


class _Resumed:
    """A controller run on from where it stands: its ``reset`` is not called again (its log is still recorded)."""

    def __init__(self, controller: BenchController) -> None:
        self.controller = controller

    @property
    def log(self) -> dict:
        return self.controller.log

    def __call__(self, t: float, state: bh.State) -> np.ndarray:
        return self.controller(t, state)


class _LastState:
    """An ``until`` that keeps the last state a run reached and stops it where the object fell."""

    def __init__(self, scene: Scene) -> None:
        self.fell = fallen(scene)
        self.state: bh.State | None = None
        self.stopped = False

    def __call__(self, state: bh.State) -> bool:
        self.state = state
        self.stopped = self.fell(state)
        return self.stopped


def run_protocol(
    simulator: Simulator,
    state: bh.State,
    controller: BenchController,
    record_every: int = 40,
    duration: float | None = None,
    heading: float = 0.0,
) -> Trajectory:
    """The protocol's runs from ``state``, joined in the protocol's time (a sample every ``record_every`` steps).

    As DexGraspBench applies each direction's force afresh to the squeezed grasp, each push starts from the held
    grasp: the approach, close and lift run to HELD_AT; then push k runs for SHAKE_TIME from the state and the
    controller as they were at HELD_AT (the wrist held there), its samples after its start recorded in
    (HELD_AT + k SHAKE_TIME, HELD_AT + (k + 1) SHAKE_TIME]; then the place runs from the held grasp too, recorded after
    HELD_AT + 6 SHAKE_TIME.  The held grasp is the sample at HELD_AT alone: from one push's last sample to the next
    push's first the record jumps back to near it (as a replay shows).  ``duration`` [s] of protocol time cuts it
    short (default: all of it); a run in which the object falls ends the trial.  With ``record_every`` dividing the
    steps of the lift, a push and the place (the protocol's times are multiples of 10 ms), the samples are evenly
    spaced.
    """
    end = HELD_AT + 6 * SHAKE_TIME + 1.0 + RELEASE if duration is None else duration
    shake = shake_force(controller.trial.item.mass, len(simulator.scene.objects), heading)
    watch = _LastState(simulator.scene)

    def run(runner, start: bh.State, span: float, offset: float) -> Trajectory:
        part = simulator.run(
            runner,
            span,
            state=start,
            progress=False,
            record_every=record_every,
            object_forces=lambda t: shake(t + offset),
            until=watch,
        )
        return dataclasses.replace(part, t=part.t + offset) if offset else part

    lifted = run(controller, state, min(end, HELD_AT), 0.0)
    if end <= HELD_AT or watch.stopped:
        return lifted
    held = watch.state
    parts = [lifted]  # its last sample is the held grasp each push starts from
    for k in range(7):  # the six pushes, then the place
        start = HELD_AT + k * SHAKE_TIME
        if start >= end:
            break
        stop = end if k == 6 else min(end, start + SHAKE_TIME)
        runner = controller.holding() if k < 6 else copy.deepcopy(controller)
        part = run(_Resumed(runner), held, stop - start, start - HELD_AT)
        parts.append(part[1:])  # from its first step on; its last sample, at stop, ends it
        if watch.stopped:
            break
    return Trajectory.joined(parts)


def run_trial(trial: Trial, dt: float = DT, record_every: int = 40) -> dict:
    """Run one trial (:mod:`~bhgrasp.bench.protocol`) and return its record (SI units; rotations [rad], forces [N])."""
    trajectory, hand = simulate_trial(trial, dt, record_every)
    return evaluate(trial, trajectory, hand)


def fallen(scene: Scene) -> Callable[[bh.State], bool]:
    """Whether the object fell: its centre 5 cm below the stand's top (the trial stops there).

    Read from the scene's coordinates (the object's position is their first three; no pose is built each step).
    """
    height = scene.object_q_slice(0).start + 2

    def below(state: bh.State) -> bool:
        return bool(state.scene_q[height] < -0.05)

    return below


__all__ = [
    "BenchController",
    "contact_law",
    "fallen",
    "idealised_damping",
    "run_protocol",
    "run_trial",
    "setup",
    "shake_force",
    "simulate_trial",
]
