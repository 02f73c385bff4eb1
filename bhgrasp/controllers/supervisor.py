"""Grasp supervisor: approach -> contact -> squeeze -> manipulate (thesis 5.4.2 and Figs 5.6-5.7).

Phases (logged as ``phase``: 0 approach, 1 squeeze, 2 manipulate):

0. **approach** — joint-space computed torque along a smooth step (5.36) from the start configuration to the
   contact configuration (from IK) closed a little further by ``approach.closing`` [rad] on every non-spread joint
   (or to a given ``q_close``), so that the fingers press once they touch.  A finger counts as arrived when its
   sensed normal force exceeds ``approach.contact_force``; when every grasping finger has arrived (or at
   ``approach.timeout``) the grasp controller takes over (:class:`~bhgrasp.controllers.supervisor_options.Approach`).
1. **squeeze** — the object-space grasp controller holds the object where it was caught (its QP brings the
   contact forces to the desired squeeze) for ``squeeze_time``.
2. **manipulate** — the grasp controller follows a minimum-jerk motion from the caught pose by ``offset``
   (position [m], rotation vector [rad], world) over ``move_time``; by default the part of it the grasp can make at
   the contacts sensed then (``planned_offset``, :meth:`GraspSupervisor._plan`); or any object ``path`` (e.g. the
   persistently exciting :class:`~bhgrasp.motion.excitation.PoseExcitation` of an identification run).

On a drive with fewer inputs than joints, :class:`~bhgrasp.controllers.motor_commands.MotorCommands` turns its
joint torques into motor commands.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._native import default_core
from bhgrasp._validation import as_positive, as_vector, require_name
from bhgrasp.controllers.base import Controller
from bhgrasp.controllers.compiled_control import CompiledControl, held_rows
from bhgrasp.controllers.grasping import ObjectGraspController
from bhgrasp.controllers.joint import ComputedTorque
from bhgrasp.controllers.supervisor_options import DEFAULT_APPROACH, DEFAULT_PLANNING, Approach, Planning
from bhgrasp.data import SimulatedState, State
from bhgrasp.errors import InputError, UnreachableError
from bhgrasp.grasp.manipulability import manipulable_space
from bhgrasp.grasp.path_check import path_contacts
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.hand import Hand
from bhgrasp.motion.pose_references import PoseMotion
from bhgrasp.motion.trajectories import Reference, SmoothStep

APPROACH, SQUEEZE, MANIPULATE = 0, 1, 2
APPROACH_ROWS = 2048  # the approach's reference samples a compiled loop is given at most (then it hands back)
_CYCLE = ("__call__", "_log_approach", "_log_grasp")  # what a compiled loop does in a cycle's place
PLAN_LENGTH = 0.1  # [m] the plan's metric (dx, L dtheta): 5 mrad weighs as 0.5 mm, the motion targets' ratio


class GraspSupervisor(Controller):
    """Sequence a joint-space approach and an object-space grasp controller.

    Logs ``phase``, ``arrived`` (per finger of the hand, 1.0 once it touched), plus the active controller's log
    (a recorded :class:`~bhgrasp.data.trajectory.Trajectory` has NaN for the grasp controller's keys during the
    approach).
    """

    def __init__(
        self,
        nominal: Hand,
        q_contact: Any,
        grasp: ObjectGraspController,
        offset: Any = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        *,
        approach: Approach = DEFAULT_APPROACH,
        squeeze_time: float = 0.3,
        move_time: float = 1.0,
        q_close: Any = None,
        fingers: Sequence[str] | None = None,
        path: Callable[..., Reference] | None = None,
        planning: Planning = DEFAULT_PLANNING,
    ) -> None:
        """Set up the sequence.

        Args:
            nominal: The controller's hand model.
            q_contact: Joint configuration [rad] with the fingertips at the contact points (from IK).
            grasp: The object-space controller for squeeze and manipulation (its reference is set here).
            offset: Object motion after the squeeze: position [m] and rotation vector [rad] change, world.
            approach: How the fingers close (:class:`~bhgrasp.controllers.supervisor_options.Approach`).
            squeeze_time: Hold [s] before the motion starts.
            move_time: Duration [s] of the minimum-jerk object motion.
            q_close: Configuration [rad] the approach drives to, instead of ``q_contact`` closed by
                ``approach.closing`` (for hands whose joint names do not say which joints spread; e.g. from IK with
                the contact points pushed into the object).
            fingers: The fingers that grasp (default: all); the grasp starts when all of them have arrived.
            path: The object reference after the squeeze instead of the minimum-jerk ``offset`` (which must then be
                zero; nothing is planned): called as ``path(pose, delay=start)`` with the pose the grasp caught and
                the motion's start time [s], e.g. ``functools.partial(PoseExcitation, amplitude=..., frequency=...)``
                (:class:`~bhgrasp.motion.excitation.PoseExcitation`).
            planning: How the motion is planned and checked
                (:class:`~bhgrasp.controllers.supervisor_options.Planning`).
        """
        super().__init__()
        if not isinstance(grasp, ObjectGraspController):
            raise InputError(f"`grasp` must be an ObjectGraspController, got {grasp!r}")
        if not isinstance(approach, Approach) or not isinstance(planning, Planning):
            raise InputError(
                f"`approach` and `planning` must be an Approach and a Planning, got {approach!r}, {planning!r}"
            )
        self.nominal = nominal
        self.q_contact = _within_limits(nominal, q_contact)
        self.grasp = grasp
        self.offset = as_vector(offset, "offset", 6)
        self.approach, self.planning = approach, planning
        self.squeeze_time = as_positive(squeeze_time, "squeeze_time")
        self.move_time = as_positive(move_time, "move_time")
        self.path = _checked_path(path, self.offset)
        self.planned_offset: np.ndarray | None = None
        self.sensing = ContactSensing(nominal)
        if q_close is None:
            closing_joints = np.array(["spread" not in name for name in nominal.joint_names], dtype=float)
            q_close = self.q_contact + approach.closing * closing_joints
        self.q_close = np.clip(as_vector(q_close, "q_close", nominal.nq), nominal.lower, nominal.upper)
        self.phase = APPROACH
        self.switch_time: float | None = None
        self._approach_law: ComputedTorque | None = None
        self._arrived = np.zeros(len(nominal.fingers))
        self._grasping = _finger_indices(nominal, fingers)
        self._pair_fingers: tuple[Any, np.ndarray] = (None, np.zeros(0, np.int64))  # a scene layout's, its rows

    def reset(self, state: State) -> None:
        """Start over with the approach from ``state``."""
        self.phase, self.switch_time = APPROACH, None
        self.planned_offset = None
        self._approach_law = None
        self._arrived[:] = 0.0
        self.log.clear()
        self.grasp.log.clear()
        self.grasp.reset(state)
        self.grasp.reference = None

    def __call__(self, t: float, state: State) -> np.ndarray:
        """Joint torques [N m] of the active phase."""
        if self._approach_law is None:
            approach = self.approach
            step = SmoothStep(np.asarray(state.q, dtype=float), self.q_close, approach.time, delay=t)
            self._approach_law = ComputedTorque(self.nominal, step, kp=approach.kp, kv=approach.kv)
        if self.phase == APPROACH:
            for finger, contact in self.sensing.fingers(state).items():
                if contact.normal_force >= self.approach.contact_force:
                    self._arrived[self.nominal.fingers.index(finger)] = 1.0
            if np.all(self._arrived[self._grasping]) or t >= self.approach.timeout:
                self._start_grasp(t, state)
        if self.phase == SQUEEZE and t >= self.switch_time + self.squeeze_time:
            self.phase = MANIPULATE
            if self.planning.plan and self.path is None:
                self._plan(t, state)
        if self.phase == APPROACH:
            tau = self._approach_law(t, state) + self.approach.damping * np.asarray(state.v, dtype=float)
            self._log_approach()
        else:
            tau = self.grasp(t, state)
            self._log_grasp(np.asarray(state.q))
        return tau

    def compiled_control(self, t: float, state: State) -> CompiledControl | None:
        """The cycles from ``state`` on as a compiled loop for :meth:`Simulator.run`, or ``None``.

        In the approach, the computed torque and the fingers' arrival (:meth:`_compiled_approach`), handing back the
        cycle that starts the grasp; then the grasp controller's compiled loop (``compiled_control``), stopped before
        the squeeze ends (the switch to the motion, and its plan, are :meth:`__call__`'s).
        """
        kind = type(self)  # a subclass's own cycle or logs would not run in the loop
        if any(getattr(kind, name) is not getattr(GraspSupervisor, name) for name in _CYCLE):
            return None
        if self.phase == APPROACH:
            return self._compiled_approach(t, state)
        offer = getattr(self.grasp, "compiled_control", None)
        if offer is None:
            return None
        until = math.inf if self.phase == MANIPULATE else self.switch_time + self.squeeze_time
        grasp = offer(t, state) if t < until else None
        if grasp is None:
            return None

        def log_rows(rows: np.ndarray, q_hand: np.ndarray) -> dict[str, np.ndarray]:
            entries = held_rows(self.log, len(rows))
            entries.update(grasp.log_rows(rows, q_hand))
            held = {"q_d": self.q_close, "phase": float(self.phase), "arrived": self._arrived}
            entries.update(held_rows(held, len(rows)), error=q_hand - self.q_close)
            return entries

        def settle(run: Any, q_hand: np.ndarray) -> None:
            grasp.settle(run, q_hand)
            if len(q_hand):
                self._log_grasp(q_hand[-1])

        return CompiledControl(grasp.loop, min(until, grasp.until), log_rows, settle, grasp.fail)

    def _compiled_approach(self, t: float, state: State) -> CompiledControl | None:
        """The approach's cycles from ``state`` on as a compiled loop (``bhgrasp._core.ApproachLoop``), or ``None``.

        Once the approach's first cycle made its computed torque (diagonal gains, the hand with nq = nv), for a state
        a compiled step made at t = k dt: the reference's samples up to the timeout (or :data:`APPROACH_ROWS` of them)
        in one table; the loop hands back the cycle in which every grasping finger has arrived.  Its RNEA runs on the
        hand's compiled dynamics, a copy of the model made when first asked for (a hand's inertias do not change).
        """
        law, core = self._approach_law, default_core()
        source = getattr(state, "_source", None) if type(state) is SimulatedState else None
        if law is None or law._time is None or core is None or source is None or t >= self.approach.timeout:
            return None
        diagonal = all(np.array_equal(gain, np.diag(np.diag(gain))) for gain in (law.kp, law.kv))
        hand, simulator = self.nominal, source.simulator
        dt = getattr(simulator, "dt", None)
        kinds = (type(law), type(law.reference), type(self.sensing))  # their subclasses may do otherwise
        if kinds != (ComputedTorque, SmoothStep, ContactSensing) or not diagonal or dt is None:
            return None
        first = round(t / dt)
        if first * dt != t or hand.nq != hand.nv or simulator.scene.nq_hand != hand.nq:
            return None
        times = np.arange(first, first + APPROACH_ROWS) * dt
        times = times[times < self.approach.timeout]
        loop = core.ApproachLoop(
            hand.compiled_dynamics(),
            hand.model.gravity.linear,
            times,
            law.reference.table(times),
            kp=np.diag(law.kp).copy(),
            kv=np.diag(law.kv).copy(),
            damping=self.approach.damping,
            finger_of_pair=self._finger_rows(simulator.layout),
            grasping=self._grasping,
            arrived=self._arrived,
            contact_force=self.approach.contact_force,
            last_time=law._time,
        )
        nv = hand.nv

        def log_rows(rows: np.ndarray, q_hand: np.ndarray) -> dict[str, np.ndarray]:
            entries = held_rows(self.log, len(rows))
            entries.update(q_d=rows[:, :nv], error=rows[:, nv : 2 * nv], arrived=rows[:, 2 * nv :])
            entries.update(held_rows({"phase": float(self.phase)}, len(rows)))
            return entries

        def settle(run: Any, q_hand: np.ndarray) -> None:
            law._time = loop.last_time
            if len(q_hand):
                row = np.array(run.log[len(q_hand) - 1])
                law.log["q_d"], law.log["error"] = row[:nv], row[nv : 2 * nv]
                self._arrived[:] = row[2 * nv :]
                self._log_approach()

        return CompiledControl(loop, self.approach.timeout, log_rows, settle, lambda run, after: None)

    def _finger_rows(self, layout: Any) -> np.ndarray:
        """The finger (-1: none) of every collision pair of ``layout``'s scene, by its hand link (as the sensing's)."""
        if self._pair_fingers[0] is not layout:
            self._pair_fingers = (layout, self.sensing.finger_rows(link for link, _ in layout.pair_bodies))
        return self._pair_fingers[1]

    def _log_approach(self) -> None:
        """The log of an approach cycle, after the computed torque's."""
        self.log.update(self._approach_law.log)
        self.log["phase"] = np.array(float(self.phase))
        self.log["arrived"] = self._arrived.copy()

    def _log_grasp(self, q: np.ndarray) -> None:
        """The log of a grasp-phase cycle at joint positions ``q`` [rad], after the grasp controller's."""
        self.log.update(self.grasp.log)
        self.log["q_d"], self.log["error"] = self.q_close, q - self.q_close
        self.log["phase"] = np.array(float(self.phase))
        self.log["arrived"] = self._arrived.copy()

    def _plan(self, t: float, state: State) -> None:
        """Track the offset the grasp can make: ``offset`` projected onto its manipulable space at the sensed contacts.

        The first-order space of :func:`~bhgrasp.grasp.manipulability.manipulable_space` at the contacts the fingers
        sense when the motion starts (not the planned ones: a fingertip's link body may touch a little off its pad,
        e.g. 1.6 mm below the thesis box's centre, so that a turn about y through the centre would drag F3 along x);
        the nearest offset the fingers make without sliding, in the metric (dx, :data:`PLAN_LENGTH` dtheta), becomes
        the motion (``planned_offset``).  With ``planning.object_shape`` the motion is then checked to its end
        (second order).

        Raises:
            UnreachableError: The plan differs from ``offset`` by more than ``planning.tolerance``; with
                ``planning.object_shape``: along the motion another part of a finger would come within
                ``planning.path_tolerance`` of the object (e.g. a distal link's body beside its pad) or a joint would
                leave its limits.
        """
        touching = self.grasp.touching(state)
        reference = self.grasp.reference
        if len(touching) < 2 or reference is None:
            return
        contacts = list(touching.values())
        points, normals, links = ([getattr(c, name) for c in contacts] for name in ("point", "normal", "link"))
        com = state.object_poses[0].translation
        space = manipulable_space(self.nominal, state.q, points, normals, links, com, list(touching))
        planned = space.nearest(self.offset, PLAN_LENGTH)
        unchanged = np.max(np.abs(planned - self.offset)) < 1e-12  # the fingers make it as asked: track it unchanged
        missing = self.offset - planned
        shortfall = np.array([np.linalg.norm(missing[:3]), np.linalg.norm(missing[3:])])
        if self.planning.tolerance is not None and np.any(shortfall > self.planning.tolerance):
            raise UnreachableError(
                f"at the contacts the fingers sense ({', '.join(touching)}) the grasp makes the motion "
                f"{np.round(self.offset, 6).tolist()} (dx [m], dtheta [rad]) only to within "
                f"{1e3 * shortfall[0]:.2f} mm and {1e3 * shortfall[1]:.2f} mrad (tolerance "
                f"{1e3 * self.planning.tolerance[0]:g} mm, {1e3 * self.planning.tolerance[1]:g} mrad): it cannot make "
                f"{np.round(missing, 6).tolist()}",
                planned,
            )
        self.planned_offset = self.offset.copy() if unchanged else planned
        if self.planning.object_shape is not None:  # second order: the fingers followed to the end of the motion
            pose, labels = state.object_poses[0], list(touching)
            followed = path_contacts(
                self.nominal,
                state.q,
                points,
                links,
                self.planning.object_shape,
                pose,
                self.planned_offset,
                tolerance=self.planning.path_tolerance,
                labels=labels,
            )
            followed.check()
        if not unchanged:
            self.grasp.reference = PoseMotion(reference.start, planned, self.move_time, reference.delay)

    def _start_grasp(self, t: float, state: State) -> None:
        self.grasp.reset(state)
        start, pose = t + self.squeeze_time, state.object_poses[0]
        self.grasp.reference = (
            PoseMotion(pose, self.offset, self.move_time, start)
            if self.path is None
            else (self.path(pin.SE3(pose), delay=start))
        )
        self.phase, self.switch_time = SQUEEZE, t


def _within_limits(nominal: Hand, q_contact: Any) -> np.ndarray:
    """``q_contact`` checked to lie within the hand's joint limits."""
    q = as_vector(q_contact, "q_contact", nominal.nq)
    outside = (q < nominal.lower - 1e-9) | (q > nominal.upper + 1e-9)
    if np.any(outside):
        names = [n for n, o in zip(nominal.joint_names, outside) if o]
        raise InputError(f"`q_contact` is outside the joint limits at {names}: {q[outside]}")
    return q


def _checked_path(path: Any, offset: np.ndarray) -> Callable[..., Reference] | None:
    """``path``: ``None``, or a callable ``(pose, delay=start) -> Reference`` given with a zero ``offset``."""
    if path is not None and (not callable(path) or np.any(offset != 0.0)):
        raise InputError(
            f"`path` must be a callable (pose, delay=start) -> Reference, with a zero `offset`; got "
            f"{path!r} and offset {offset.tolist()}"
        )
    return path


def _finger_indices(nominal: Hand, fingers: Sequence[str] | None) -> np.ndarray:
    """The grasping fingers' indices in the hand (default: every finger)."""
    grasping = nominal.fingers if fingers is None else [require_name(f, nominal.fingers, "finger") for f in fingers]
    if not grasping:
        raise InputError("`fingers` must name at least one finger of the hand")
    return np.array([nominal.fingers.index(f) for f in grasping])


__all__ = ["APPROACH", "APPROACH_ROWS", "MANIPULATE", "PLAN_LENGTH", "SQUEEZE", "GraspSupervisor"]
