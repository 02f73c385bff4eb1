"""The compiled engine of :class:`~bhgrasp.controllers.adaptive_grasp.SMCAdaptiveGrasp`: one grasp cycle, one call.

``bhgrasp._core.SMCAdaptiveLaw`` (``src/smc_law.cpp``) runs, per grasp cycle, what the Python twin runs in
:meth:`ObjectGraspController.__call__ <bhgrasp.controllers.grasping.ObjectGraspController.__call__>`,
:meth:`~bhgrasp.controllers.adaptive_grasp.SMCAdaptiveGrasp.grasp_torques` and
:meth:`~bhgrasp.controllers.grasping.ObjectGraspController.distribute` once the reference is evaluated: the contacts
by finger, their frames, P, P_dot, G, J_h, J_h^+, the errors, the object regressor and estimate, the wrench, its QP
distribution (one warm-started QP per contact count), the force errors and their integrals, and the torques.  This
module keeps what stays in Python, exactly as the twin does it: the input checks, the approach branch (fewer than two
touching fingers), the hold pose, the clock and a reference other than a minimum-jerk pose path (a ``PoseMotion`` or
``PosePath`` is sampled by ``bhgrasp._core.PosePath``, its target rotation exp(b dtheta) R_0 given to the law as it
is, where the twin takes the exp of the sample's log); and it publishes the log.  The log's arrays are views
of one fresh buffer per call (a recorder may keep them).  ``tests/test_smc_law_twin.py`` holds both engines in
lockstep.
"""

from __future__ import annotations

import operator
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from bhgrasp._native import required_core
from bhgrasp._validation import as_array, as_vector
from bhgrasp.controllers._pose_path import compiled_path
from bhgrasp.data import SimulatedState
from bhgrasp.errors import InputError
from bhgrasp.grasp.forces import solver_arguments
from bhgrasp.grasp.frames import TANGENT_SWITCH, ZERO_NORMAL, contact_frames, grasp_map_from_frames
from bhgrasp.grasp.kinematics import grasp_kinematics_kernel, hand_index
from bhgrasp.model.spring_mounted import SpringMounted
from bhgrasp.motion.trajectories import time_of

if TYPE_CHECKING:
    from bhgrasp.model.hand_description import BaseFrame

_ROW_CACHE = 256  # contact-body tuples whose finger and joint rows are kept (a run meets a handful)


def log_layout(nv: int, fingers: int) -> list[tuple[str, Any]]:
    """(key, index into the buffer) in the order ``src/smc_law.hpp`` writes them; (F, 3) entries as (start, stop)."""
    keys = [
        ("tau", nv),
        ("object_error", 6),
        ("wrench", 6),
        ("feasible", 0),
        ("infeasible_cycles", 0),
        ("wrench_residual", 0),
        ("qp_iterations", 0),
        ("cone_margin", 0),
        ("commanded_normal", fingers),
        ("contacts", 0),
        ("object_sliding", 6),
        ("joint_sliding", nv),
        ("force_error", (fingers, 3)),
        ("desired_force", (fingers, 3)),
        ("object_parameters", 7),
    ]
    layout, start = [], 0
    for key, size in keys:
        if size == 0:  # a 0-d view
            layout.append((key, (start, Ellipsis)))
            start += 1
        else:
            stop = start + (size[0] * size[1] if isinstance(size, tuple) else size)
            layout.append((key, (start, stop) if isinstance(size, tuple) else slice(start, stop)))
            start = stop
    return layout


class CompiledSMCLaw:
    """The compiled law of one controller, with its caches.

    Contact rows by body names and by collision pair (per scene layout), the hand's base, the compiled path of the
    last reference object.
    """

    def __init__(self, law: Any, core: ModuleType) -> None:
        """Build ``core.SMCAdaptiveLaw`` on the hand's kernels and configure it from ``law``."""
        hand = law.nominal
        self._regressor = core.object_regressor
        self.kernel = core.SMCAdaptiveLaw(grasp_kinematics_kernel(hand), hand.compiled_dynamics(), len(hand.fingers))
        self._sensing = law.sensing
        self._joint_of = hand_index(hand).joints
        self._rows: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}
        self._base: BaseFrame | None = None  # the hand base the kernel was last given
        self._held: tuple[Any, np.ndarray, np.ndarray] | None = None  # law._hold and its arrays
        self._scene: Any = None  # the scene of the last simulated state and its object's free-body slices
        self._body: tuple[slice, slice] | None = None
        self._target: tuple[bytes, np.ndarray | None] = (b"", None)  # the last target rotation vector, its exp
        self._core, self._reference = core, (None, None)  # the last reference and its compiled path
        self._contacts_type = core.Contacts  # a compiled step's contacts, and the last layout's rows of its pairs
        self._pairs: tuple[Any, tuple[np.ndarray, np.ndarray]] = (None, (np.zeros(0, np.int64), np.zeros(0, np.int64)))
        self._zeros = np.zeros(6)
        self._zeros.flags.writeable = False
        nv, fingers = hand.nv, len(hand.fingers)
        self._size = self.kernel.log_size
        layout = log_layout(nv, fingers)
        self._layout, self._fingers = layout, fingers
        self._tau = layout[0][1]
        flat = [(key, index) for key, index in layout[1:] if not isinstance(index, tuple) or index[1] is Ellipsis]
        self._flat_keys = [key for key, _ in flat]
        self._flat_views = operator.itemgetter(*(index for _, index in flat))  # buffer -> its views, in one call
        self._blocks = [
            (key, slice(*index), (fingers, 3))
            for key, index in layout
            if isinstance(index, tuple) and index[1] is not Ellipsis
        ]
        self._wrench = dict(layout)["wrench"]
        parameters = dict(layout)["object_parameters"]
        self._mass = slice(parameters.start, parameters.start + 1)
        self._parameters = parameters
        assert parameters.stop == self._size, "the log layout of src/smc_law.hpp and this module differ"
        self.configure(law)

    def configure(self, law: Any) -> None:
        """Copy ``law``'s gains, QP settings and initial estimate into the kernel, and reset it."""
        arguments = solver_arguments(1, law.design_mu, min_normal_force=law.min_normal_force)[1:]
        rates = law.object_adaptation if law.identification is None else np.zeros(7)  # then updated in identify()
        self.kernel.configure(
            law.rho,
            law.k_o,
            rates,
            law.force_gain,
            law.force_integral,
            law.k_f,
            law.force_error == "normal",
            law.squeeze,
            law.friction_margin is not None,
            law.gravity,
            law._initial_object,
            *arguments,
            ZERO_NORMAL,
            TANGENT_SWITCH,
        )

    def _pair_rows(self, layout: Any) -> tuple[np.ndarray, np.ndarray]:
        """The finger (-1: none) and parent joint of every collision pair of ``layout``'s scene, by its hand link."""
        if layout is not self._pairs[0]:
            self._pairs = (layout, self._rows_of(layout.pair_bodies))
        return self._pairs[1]

    def _rows_of(self, bodies: tuple) -> tuple[np.ndarray, np.ndarray]:
        """The finger (-1: none) and parent joint of each (hand link, body): ContactSensing's, parent_joints' maps."""
        joint_of = self._joint_of
        return (
            self._sensing.finger_rows(link for link, _ in bodies),
            np.array([joint_of.get(link, -1) for link, _ in bodies], dtype=np.int64),
        )

    def _index(self, bodies: tuple) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`_rows_of` the contact rows' bodies, kept for the next call with the same bodies."""
        rows = self._rows_of(bodies)
        if len(self._rows) >= _ROW_CACHE:
            self._rows.clear()
        self._rows[bodies] = rows
        return rows

    def __call__(self, law: Any, t: float, state: Any) -> np.ndarray:
        """Joint torques [N m]: ``law.__call__`` (ObjectGraspController's then SMCAdaptiveGrasp's) on the kernel."""
        hand, log, kernel = law.nominal, law.log, self.kernel
        # a simulator's step made it (not dataclasses.replace, which leaves no source): finite, read-only
        q = state.q
        trusted = type(state) is SimulatedState and not q.flags.writeable
        source = getattr(state, "_source", None) if trusted else None
        trusted = source is not None
        if not trusted or q.shape != (hand.nq,):
            q = as_vector(q, "state.q", hand.nq)
        # the object's free-body coordinates in the scene's arrays: its pose and twist are not built in Python
        body = self._free_body(source.simulator.scene) if trusted else None
        pose = None
        if body is None:
            if not state.object_poses:
                raise InputError(f"{type(law).__name__} needs the object's pose in the state (a scene with an object)")
            pose = state.object_poses[0]
        contacts = source.contacts if trusted else None
        if type(contacts) is self._contacts_type:  # the compiled step's: read in C++, rows by their collision pairs
            touching = kernel.sense_contacts(contacts, *self._pair_rows(source.simulator.layout))
        else:
            bodies = state.contact_bodies
            finger, joint = self._rows.get(bodies) or self._index(bodies)
            touching = kernel.sense(finger, joint, state.contact_points, state.contact_normals, state.contact_forces)
        if touching < 2:
            return self._approach(law, q, touching)
        if law._hold is None:
            law._hold = pin.SE3(state.object_poses[0])
        dt = 0.0 if law._time is None else t - law._time
        if dt < 0.0:
            raise InputError(f"time went backwards: t = {t} after {law._time}; call reset() to restart")
        law._time = t
        on_path = None  # a compiled pose path the kernel samples in the grasp call
        if law.reference is None:
            held = self._held
            if held is None or held[0] is not law._hold:
                rotation = law._hold.rotation.copy(order="F")  # Eigen's order: no converted temporary per call
                held = self._held = (law._hold, rotation, law._hold.translation.copy())
            rotation_d, position_d, velocity, acceleration = held[1], held[2], self._zeros, self._zeros
        else:
            path = self._path(law.reference)
            if path is None:
                sample, velocity, acceleration = law.reference(t)
                rotation_d, position_d = self._target_rotation(sample[3:]), sample[:3]
            elif pose is None and law.identification is None:  # a minimum-jerk pose path, sampled in the law's call
                on_path, path_time = path, time_of(t)  # (the reference's check of t)
            else:  # sampled in C++ too, its targets wanted here (its rotation not through log3 and exp3)
                rotation_d, position_d, velocity, acceleration = path.sample(time_of(t))
        v = state.v
        if not trusted or v.shape != (hand.nv,):
            v = as_vector(v, "v", hand.nv)  # (Hand.slotine_li_torque's check)
        self._set_base(hand)
        out = np.empty(self._size)
        if pose is not None:
            targets = (rotation_d, position_d, velocity, acceleration, out)
            status = kernel.grasp(q, v, pose.rotation, pose.translation, state.object_twists[0], dt, *targets)
        else:
            object_q, object_v = state.scene_q[body[0]], state.scene_v[body[1]]
            if on_path is not None:
                status = kernel.grasp_free_body_on_path(q, v, object_q, object_v, dt, on_path, path_time, out)
            else:
                targets = (rotation_d, position_d, velocity, acceleration, out)
                status = kernel.grasp_free_body(q, v, object_q, object_v, dt, *targets)
        if status in (1, 2, 3):
            self._raise(law, state, status, out)
        self._publish(log, out, mass=False)
        tau = out[self._tau]
        if status:
            raise InputError(f"{type(law).__name__} produced non-finite torques {tau} at t = {t} s")
        if law.identification is not None:
            pose, sliding = state.object_poses[0], log["object_sliding"]
            twist = np.asarray(state.object_twists[0], dtype=float)
            v_r, a_r = twist - sliding, acceleration - law.rho * (twist - velocity)
            law.identify(dt, state, self._regressor(pose.rotation, twist[3:], v_r, a_r, law.gravity), sliding)
            log["object_parameters"] = out[self._parameters] = kernel.object_estimate
        log["mass_estimate"] = out[self._mass]
        return tau

    def _set_base(self, hand: Any) -> None:
        """Give the kernel ``hand``'s base (a new object whenever its placement or gravity change) if it changed."""
        base = hand.base
        if self._base is not base:
            self.kernel.set_base(base.rotation, base.translation, base.gravity)
            self._base = base

    def _publish(self, log: dict, out: np.ndarray, mass: bool = True) -> None:
        """The log entries of a grasp cycle's ``out`` (views of it); its mass estimate too if ``mass``."""
        log.update(zip(self._flat_keys, self._flat_views(out)))
        for key, index, shape in self._blocks:
            log[key] = out[index].reshape(shape)
        if mass:
            log["mass_estimate"] = out[self._mass]

    def loop(self, law: Any, state: Any) -> Any | None:
        """The grasp cycles from ``state`` on as a compiled loop controller (``bhgrasp._core.SMCGraspLoop``), or None.

        Only where :meth:`__call__` would sample a compiled pose path in the kernel's grasp call for a state a
        compiled step made (the object a free body, no identification) and a grasp is under way (a hold pose and a
        last grasp cycle): the loop's cycles are then :meth:`__call__`'s, bit for bit, while two fingers or more touch.
        """
        if law._hold is None or law._time is None or law.identification is not None or law.reference is None:
            return None
        source = getattr(state, "_source", None) if type(state) is SimulatedState else None
        if source is None or type(source.contacts) is not self._contacts_type or state.scene_q.flags.writeable:
            return None
        scene, hand = source.simulator.scene, law.nominal
        body = self._free_body(scene)
        path = self._path(law.reference)
        if body is None or path is None or (scene.nq_hand, scene.nv_hand) != (hand.nq, hand.nv):
            return None
        self._set_base(hand)
        finger, joint = self._pair_rows(source.simulator.layout)
        sizes = (hand.nq, hand.nv, body[0].start, body[1].start)
        return self._core.SMCGraspLoop(self.kernel, path, finger, joint, *sizes, law._time)

    def log_rows(self, rows: np.ndarray) -> dict[str, np.ndarray]:
        """The log entries of grasp cycles from the kernel's rows (n, log_size): ``(n, *shape)`` views of ``rows``."""
        n, fingers = len(rows), self._fingers
        entries = {}
        for key, index in self._layout[1:]:
            if isinstance(index, tuple) and index[1] is Ellipsis:
                entries[key] = rows[:, index[0]]
            elif isinstance(index, tuple):
                entries[key] = rows[:, index[0] : index[1]].reshape(n, fingers, 3)
            else:
                entries[key] = rows[:, index]
        entries["mass_estimate"] = rows[:, self._mass]
        return entries

    def settle(self, law: Any, loop: Any, run: Any, cycles: int) -> None:
        """After a ``run`` of :meth:`loop`'s ``loop``: the law's clock and log as its last completed cycle left them.

        ``cycles``: the cycles it completed (the run's first log rows); the clock as a failed cycle after them left it.
        """
        law._time = loop.last_time
        if cycles:
            self._publish(law.log, np.array(run.log[cycles - 1]))  # a fresh buffer, as each call's

    def fail(self, law: Any, run: Any, state: Any) -> None:
        """Raise what :meth:`__call__` raises at ``state`` for the cycle that stopped ``run`` (its status 1-4)."""
        status = int(run.status) if run.stop == 1 else 0
        if status <= 0:
            return
        out = np.array(run.log[run.steps])
        if status in (1, 2, 3):
            self._raise(law, state, status, out)
        self._publish(law.log, out, mass=False)
        raise InputError(f"{type(law).__name__} produced non-finite torques {out[self._tau]} at t = {state.t} s")

    def _free_body(self, scene: Any) -> tuple[slice, slice] | None:
        """The (q, v) slices of the scene's object 0 when it is a free body (as Scene.object_pose tells), else None."""
        if scene is not self._scene:
            free = bool(scene.objects) and not isinstance(scene.objects[0], SpringMounted)
            self._scene, self._body = scene, (scene.object_q_slice(0), scene.object_v_slice(0)) if free else None
        return self._body

    def _path(self, reference: Any) -> Any | None:
        """The compiled path of ``reference`` (kept while the law's reference is that object), else None."""
        if reference is not self._reference[0]:
            self._reference = (reference, compiled_path(self._core, reference))
        return self._reference[1]

    def _target_rotation(self, rotation_vector: np.ndarray) -> np.ndarray:
        """exp(rotation_vector) as the kernel takes it (Eigen's order); a repeated vector's is the last call's."""
        key = rotation_vector.tobytes()
        if key != self._target[0]:
            self._target = (key, pin.exp3(rotation_vector).copy(order="F"))
        return self._target[1]

    def _approach(self, law: Any, q: np.ndarray, touching: int) -> np.ndarray:
        """Fewer than two touching fingers: SMCAdaptiveGrasp's zero logs, then the base's closing torques."""
        hand = law.nominal
        law._hold = None
        estimate, zeros = self.kernel.object_estimate, np.zeros((len(hand.fingers), 3))
        law.log.update(
            joint_sliding=np.zeros(hand.nv),
            force_error=zeros,
            desired_force=zeros,
            object_sliding=np.zeros(6),
            object_parameters=estimate,
            mass_estimate=estimate[:1],
            contacts=np.array(float(touching)),
            commanded_normal=np.zeros(len(hand.fingers)),
        )
        return hand.gravity_torques(q) + law._closing

    def _raise(self, law: Any, state: Any, status: int, out: np.ndarray) -> None:
        """Raise what the twin's check raises for the kernel's status 1 (normals), 2 (G) or 3 (the wrench)."""
        contacts = list(law.touching(state).values())
        normals = np.array([c.normal for c in contacts])
        if status == 1:
            contact_frames(normals)  # raises InputError naming the zero or non-finite normal
        elif status == 2:  # GraspContacts.grasp_map's check, then ContactForceQP.solve's
            com = as_vector(state.object_poses[0].translation, "reference", 3)
            points = np.array([c.point for c in contacts])
            as_array(grasp_map_from_frames(points, contact_frames(normals), com), "grasp_map", (6, 3 * len(contacts)))
        else:
            as_vector(out[self._wrench], "wrench", 6)
        raise InputError(f"{type(law).__name__}: the compiled law found non-finite values (status {status})")


def compiled_state(law: Any, state: dict) -> dict:
    """``state`` (a copy of ``law.__dict__``) for pickling an SMC-adaptive law, its compiled kernel left out.

    :func:`restore_compiled` rebuilds the kernel; refused once the law has run grasp cycles since its reset.
    """
    compiled = state["_compiled"]
    if compiled is not None:
        if law._time is not None:
            raise InputError(
                "a compiled SMCAdaptiveGrasp that has run grasp cycles cannot be copied or pickled (its force "
                "integrals and QP warm starts live in C++): call reset() first, or use engine='python'"
            )
        state.update(_compiled=None, _object_estimate=compiled.kernel.object_estimate, _rebuild=True)
    return state


def restore_compiled(law: Any, state: dict) -> None:
    """Restore ``law`` from :func:`compiled_state`'s ``state``, building its own compiled kernel if it had one."""
    rebuild = state.pop("_rebuild", False)
    law.__dict__.update(state)
    if rebuild:
        estimate = law._object_estimate
        law._compiled = CompiledSMCLaw(law, required_core("the compiled SMC-adaptive law"))
        law.object_estimate = estimate


def uncovered_options(law: Any, base: type) -> str:
    """The options of ``law`` (an SMC-adaptive law; ``base`` its class) the compiled law does not cover ('' if none)."""
    overridden = [
        name
        for name in ("grasp_torques", "_finger_law", "distribute", "limit_squeeze", "errors", "target", "touching")
        if getattr(type(law), name) is not getattr(base, name)
    ]
    return ", ".join(
        [f"hand_adaptation={law.hand_adaptation}"] * (law.hand_adaptation is not None)
        + [f"distribution={law.distribution!r}"] * (law.distribution != "qp")
        + [f"torque_limit={law.options.torque_limit}"] * (law.options.torque_limit is not None)
        + [f"a subclass overriding {name}" for name in overridden]
    )
