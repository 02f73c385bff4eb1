"""State (what a controller sees) and Trajectory (what a run records): plain data, no physics.

Units SI, angles in radians, world frame.  Object poses are the world poses of the objects' centre-of-mass frames;
object twists are (linear [m/s], angular [rad/s]) of the centre of mass in world-aligned coordinates.  Contact
forces act on the contact's body b (an object); the opposite force acts on body a.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp.errors import InputError


@dataclass(frozen=True, slots=True)
class State:
    """One instant of a simulation (or of a real hand's sensors).

    A simulator's states are :class:`SimulatedState`: the same fields, those derived from the scene's
    configuration and the step's contacts built when first read.

    Attributes:
        t: Time [s].
        q: Hand joint positions [rad], shape (nv_hand,).
        v: Hand joint velocities [rad/s].
        object_poses: World pose of each object.
        object_twists: (n_objects, 6) object velocities, world-aligned.
        contact_points: (m, 3) contact points [m].
        contact_normals: (m, 3) unit normals from body a to body b.
        contact_forces: (m, 3) forces on body b [N].
        contact_bodies: (m, 2) names of (body a, body b).
        scene_q: Full scene configuration (hand + objects), for the simulator.
        scene_v: Full scene velocity.
        contact_memory: The simulator's memory of the last step's contacts (tangential spring displacements and
            stick/slip flags, a :class:`~bhgrasp.sim.contact_set.ContactMemory`); ``None`` = no contact remembered.
            A run from this state continues it exactly; ``dataclasses.replace(state, contact_memory=None)`` clears
            it.
        actuation_modes: The actuation's mode flags (e.g. TorqueSwitch per finger); ``None`` = re-armed.
        scene_signature: The signature of the scene whose ``scene_q`` and ``scene_v`` these are (a simulator
            refuses a state of another scene); ``None`` = not known (checked by sizes and values alone).
    """

    t: float
    q: np.ndarray
    v: np.ndarray
    object_poses: tuple[pin.SE3, ...] = ()
    object_twists: np.ndarray = field(default_factory=lambda: np.zeros((0, 6)))
    contact_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    contact_normals: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    contact_forces: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    contact_bodies: tuple[tuple[str, str], ...] = ()
    scene_q: np.ndarray | None = None
    scene_v: np.ndarray | None = None
    contact_memory: Any = None
    actuation_modes: np.ndarray | None = None
    scene_signature: str | None = None


DERIVED_FIELDS = frozenset(
    ("q", "v", "object_poses", "object_twists", "contact_points", "contact_normals", "contact_forces",
     "contact_bodies", "contact_memory")
)  # fmt: skip


class SimulatedState(State):
    """A :class:`State` a simulator stepped to: the fields in :data:`DERIVED_FIELDS` are built when first read.

    A step keeps the scene's ``q``, ``v``, its contacts and contact memory as the engine returned them (the compiled
    engine's arrays stay in C++ objects); a simulator's step sets the hand's ``q`` and ``v`` as read-only views of
    the scene's (and the scene's arrays read-only: a state is a value); the object poses and twists, the contact
    arrays and body names and the
    :class:`~bhgrasp.sim.contact_set.ContactMemory` are made from them on first access and kept.
    Reading a field gives the same value as an eagerly built :class:`State` would hold; ``dataclasses.replace``
    and pickling build every field first.
    """

    __slots__ = ("_source",)

    def __getattr__(self, name: str) -> Any:
        """Build a derived field on first access (Python calls this only for a field not set yet)."""
        if name not in DERIVED_FIELDS:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        try:
            source = object.__getattribute__(self, "_source")
        except AttributeError:  # made by dataclasses.replace or unpickled: every field was given
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}") from None
        for field_name, value in source.derive(name, self).items():
            object.__setattr__(self, field_name, value)
        return object.__getattribute__(self, name)

    @classmethod
    def lazy(
        cls,
        t: float,
        scene_q: np.ndarray,
        scene_v: np.ndarray,
        modes: np.ndarray,
        source: Any,
        hand_sizes: tuple[int, int] | None = None,
        scene_signature: str | None = None,
    ) -> SimulatedState:
        """A state with its time, scene ``q``, ``v`` and actuation modes, the rest built by ``source.derive``.

        With ``hand_sizes`` = (nq_hand, nv_hand) the hand's ``q`` and ``v`` are set at once as read-only views of
        the scene's arrays (which no one changes after the step that made them); otherwise they are derived too.

        ``source.derive(name, state)`` returns a dict of derived fields that includes ``name`` (it may add others
        it computed on the way, e.g. twists with poses).
        """
        state = object.__new__(cls)
        set_t, set_scene_q, set_scene_v, set_modes, set_source, set_q, set_v, set_signature = _SETTERS
        scene_q.flags.writeable = scene_v.flags.writeable = False
        set_t(state, t)
        set_scene_q(state, scene_q)
        set_scene_v(state, scene_v)
        set_modes(state, modes)
        set_source(state, source)
        set_signature(state, scene_signature)
        if hand_sizes is not None:  # the hand's q and v: read-only views of the scene's (built for every state)
            q, v = scene_q[: hand_sizes[0]], scene_v[: hand_sizes[1]]
            q.flags.writeable = v.flags.writeable = False
            set_q(state, q)
            set_v(state, v)
        return state


# the slots' own setters (a frozen dataclass refuses attribute assignment; these bypass it, as its __init__ does)
_SETTERS = tuple(
    owner.__dict__[name].__set__
    for owner, name in (
        (State, "t"),
        (State, "scene_q"),
        (State, "scene_v"),
        (State, "actuation_modes"),
        (SimulatedState, "_source"),
        (State, "q"),
        (State, "v"),
        (State, "scene_signature"),
    )
)


_ARRAYS = (
    "t",
    "q",
    "v",
    "u",
    "tau",
    "modes",
    "object_position",
    "object_quaternion",
    "object_twist",
    "contact_offsets",
    "contact_pair",
    "contact_point",
    "contact_normal",
    "contact_depth",
    "contact_force",
    "contact_sticking",
)


@dataclass
class Trajectory:
    """Time-indexed record of a run (N samples; contacts stored flat with per-sample offsets).

    Attributes:
        t: (N,) times [s].
        q, v: (N, nv_hand) hand joint positions [rad] and velocities [rad/s].
        u: (N, n_inputs) control inputs held over each sample (zero-order hold).
        tau: (N, nv_hand) joint torques the actuators delivered [N m] (inputs plus coupling reactions).
        modes: (N, n_modes) actuation modes (e.g. TorqueSwitch broken per finger).
        object_position: (N, n_objects, 3) [m]; object_quaternion: (N, n_objects, 4) as (x, y, z, w);
        object_twist: (N, n_objects, 6) world-aligned.
        contact_offsets: (N + 1,) contacts of sample k are rows ``contact_offsets[k]:contact_offsets[k + 1]``.
        contact_pair, contact_point, contact_normal, contact_depth, contact_force, contact_sticking: flat
            per-contact arrays (pair index, [m], unit, [m], force on body b [N], bool).
        log: Controller internals, name -> (N, ...) array; NaN in the samples where the controller did not log
            that name (e.g. a grasp controller's keys before a supervisor starts it).
        joint_names, object_names: Labels; pair_bodies: (n_pairs, 2) body names of each collision pair.
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    u: np.ndarray
    tau: np.ndarray
    modes: np.ndarray
    object_position: np.ndarray
    object_quaternion: np.ndarray
    object_twist: np.ndarray
    contact_offsets: np.ndarray
    contact_pair: np.ndarray
    contact_point: np.ndarray
    contact_normal: np.ndarray
    contact_depth: np.ndarray
    contact_force: np.ndarray
    contact_sticking: np.ndarray
    log: dict[str, np.ndarray] = field(default_factory=dict)
    joint_names: tuple[str, ...] = ()
    object_names: tuple[str, ...] = ()
    pair_bodies: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=str))

    def __len__(self) -> int:
        return len(self.t)

    def __repr__(self) -> str:
        span = f"{self.t[0]:.4g}..{self.t[-1]:.4g} s" if len(self) else "empty"
        return (
            f"Trajectory({len(self)} samples, {span}, joints={len(self.joint_names)}, "
            f"objects={list(self.object_names)}, contacts={len(self.contact_pair)}, log={sorted(self.log)})"
        )

    # ------------------------------------------------------------------ contacts
    def contacts_at(self, k: int) -> dict[str, np.ndarray]:
        """The contacts of sample ``k`` as arrays (pair, point, normal, depth, force, sticking, bodies)."""
        rows = slice(self.contact_offsets[k], self.contact_offsets[k + 1])
        pair = self.contact_pair[rows]
        return {
            "pair": pair,
            "point": self.contact_point[rows],
            "normal": self.contact_normal[rows],
            "depth": self.contact_depth[rows],
            "force": self.contact_force[rows],
            "sticking": self.contact_sticking[rows],
            "bodies": self.pair_bodies[pair] if len(self.pair_bodies) else np.zeros((len(pair), 2), dtype=str),
        }

    def contact_count(self) -> np.ndarray:
        """(N,) number of contact points per sample."""
        return np.diff(self.contact_offsets)

    def object_euler_zyz(self) -> np.ndarray:
        """(N, n_objects, 3) object orientations as the thesis' Z-Y-Z Euler angles [rad] (for reporting only)."""
        from bhgrasp.orientation import zyz_from_rotation

        n, m = self.object_quaternion.shape[:2]
        angles = np.empty((n, m, 3))
        for k in range(n):
            for i in range(m):
                rotation = pin.Quaternion(*np.roll(self.object_quaternion[k, i], 1)).toRotationMatrix()
                angles[k, i] = zyz_from_rotation(rotation)
        return angles

    def max_penetration(self) -> float:
        """Deepest contact of the whole run [m]."""
        return float(self.contact_depth.max()) if len(self.contact_depth) else 0.0

    # ------------------------------------------------------------------ slicing
    def between(self, start: float, stop: float) -> Trajectory:
        """Samples with ``start <= t <= stop`` [s]."""
        slack = 1e-9 * max(1.0, abs(start), abs(stop))  # times are k dt: do not lose a sample to rounding
        indices = np.flatnonzero((self.t >= start - slack) & (self.t <= stop + slack))
        if len(indices) == 0:
            raise InputError(f"no samples between t = {start} and {stop} s (run spans {self.t[0]}..{self.t[-1]} s)")
        return self[int(indices[0]) : int(indices[-1]) + 1]

    def __getitem__(self, index: slice) -> Trajectory:
        if not isinstance(index, slice) or index.step not in (None, 1):
            raise InputError(f"a Trajectory is sliced by a contiguous slice, got {index!r}")
        start, stop, _ = index.indices(len(self))
        rows = slice(int(self.contact_offsets[start]), int(self.contact_offsets[stop]))
        offsets = self.contact_offsets[start : stop + 1] - self.contact_offsets[start]
        sample = {name: getattr(self, name)[start:stop] for name in _ARRAYS if not name.startswith("contact_")}
        contacts = {name: getattr(self, name)[rows] for name in _ARRAYS if name.startswith("contact_")}
        contacts["contact_offsets"] = offsets
        log = {name: values[start:stop] for name, values in self.log.items()}
        return Trajectory(
            **sample, **contacts, log=log, joint_names=self.joint_names, object_names=self.object_names,
            pair_bodies=self.pair_bodies,
        )  # fmt: skip

    # ------------------------------------------------------------------ files
    def save(self, path: str | Path) -> Path:
        """Write an ``.npz`` file (plain arrays, no pickle)."""
        path = Path(path)
        arrays = {name: getattr(self, name) for name in _ARRAYS}
        arrays.update({f"log/{name}": values for name, values in self.log.items()})
        arrays["joint_names"] = np.array(self.joint_names, dtype=str)
        arrays["object_names"] = np.array(self.object_names, dtype=str)
        arrays["pair_bodies"] = np.asarray(self.pair_bodies, dtype=str)
        np.savez_compressed(path, **arrays)
        return path if path.suffix == ".npz" else path.with_suffix(path.suffix + ".npz")

    @classmethod
    def load(cls, path: str | Path) -> Trajectory:
        """Read a file written by :meth:`save` (``allow_pickle=False``: untrusted files cannot run code).

        Raises:
            InputError: The file is missing, is not an ``.npz`` archive, or holds pickled objects or other arrays.
        """
        path = Path(path)
        if not path.is_file():
            raise InputError(f"no trajectory file at {str(path)!r} (expected an .npz written by Trajectory.save)")
        try:
            data = np.load(path, allow_pickle=False)
        except (ValueError, OSError, EOFError) as error:  # raw pickles and other files: refused unread
            raise InputError(
                f"{str(path)!r} is not a bhgrasp trajectory (.npz of plain arrays written by Trajectory.save): {error}"
            ) from error
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise InputError(
                f"{str(path)!r} is not a bhgrasp trajectory: a single .npy array, expected an .npz archive"
            )
        with data:
            missing = [name for name in _ARRAYS if name not in data.files]
            if missing:
                raise InputError(f"{str(path)!r} is not a bhgrasp trajectory: missing arrays {missing}")
            try:
                arrays = {name: data[name] for name in _ARRAYS}
                log = {name[4:]: data[name] for name in data.files if name.startswith("log/")}
                names = (data["joint_names"], data["object_names"], data["pair_bodies"])
            except ValueError as error:  # an object array would need pickle: never unpickled
                raise InputError(
                    f"{str(path)!r} holds pickled objects, which are never loaded (untrusted code): {error}"
                ) from error
            return cls(
                **arrays, log=log, joint_names=tuple(str(n) for n in names[0]),
                object_names=tuple(str(n) for n in names[1]), pair_bodies=names[2],
            )  # fmt: skip
