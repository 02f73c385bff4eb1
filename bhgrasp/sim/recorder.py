"""Recorder: collects a simulation run sample by sample into a :class:`~bhgrasp.data.trajectory.Trajectory`."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._native import default_core
from bhgrasp.data import State, Trajectory
from bhgrasp.sim.actuation import Actuation
from bhgrasp.sim.scene import Scene

_FLOAT = np.dtype(float)  # the native float64 of a logged array that is copied as it is


class Recorder:
    """Collects a run sample by sample and assembles the :class:`~bhgrasp.data.trajectory.Trajectory`.

    A sample keeps references to what the step made (the scene's q and v, the input, the drive torques, the
    contacts as the engine returned them); the arrays of the trajectory are assembled once, at the end.
    """

    _CONTACT_FIELDS = ("pair", "point", "normal", "depth", "force", "sticking")

    def __init__(self, scene: Scene, actuation: Actuation) -> None:
        """Record ``scene`` driven through ``actuation`` (for its mode flags)."""
        self.scene, self.actuation = scene, actuation
        self.t, self.scene_q, self.scene_v = [], [], []
        self.u, self.tau, self.modes, self.contacts = [], [], [], []
        self.log: dict[str, list] = {}
        self._logged = 0  # samples whose log every list of self.log holds

    def add(self, state: State, u: np.ndarray, info: Any, log: Any) -> None:
        """Append one sample: state, held input, the step's contacts and drive torques, controller internals.

        ``u`` and ``info``'s arrays are kept, not copied: the simulator makes new ones at every step.
        """
        self.t.append(state.t)
        self.scene_q.append(state.scene_q)
        self.scene_v.append(state.scene_v)
        self.u.append(u)
        self.tau.append(info.drive_torques)
        modes = state.actuation_modes
        self.modes.append(self.actuation.modes() if modes is None else modes)
        self.contacts.append(info.contact_arrays)
        if isinstance(log, dict):
            self._add_log(log)

    def _add_log(self, log: dict) -> None:
        """Append the controller's log; a key absent from a sample (before it first appears, or skipped) is NaN."""
        count = len(self.t)
        logged = self.log
        if self._logged == count - 1 and log.keys() == logged.keys():  # the usual sample: the keys of the last one
            for name, value in log.items():  # a float array's copy, as np.array(value, dtype=float) makes it
                logged[name].append(value.copy() if getattr(value, "dtype", None) is _FLOAT else np.array(value, float))
            self._logged = count
            return
        self._logged = count
        for name, value in log.items():
            value = np.array(value, dtype=float)
            values = self.log.setdefault(name, [])
            if len(values) < count - 1:  # one NaN array for every missing sample (stacked, never written)
                values.extend([np.full(value.shape, np.nan)] * (count - 1 - len(values)))
            values.append(value)
        for values in self.log.values():
            if len(values) < count:
                values.append(np.full(values[-1].shape, np.nan))

    def _objects(self, scene_q: np.ndarray, scene_v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(N, n_objects, 3) COM positions [m], (N, n_objects, 4) quaternions (x, y, z, w), (N, n_objects, 6) twists.

        A free object's are read from the scene's coordinates (position and unit quaternion of its COM frame;
        world-aligned linear and body angular velocity, turned to world); a spring-mounted object slides along its
        direction with a fixed orientation.
        """
        scene = self.scene
        n, n_obj = len(scene_q), len(scene.objects)
        position, quaternion, twist = np.zeros((n, n_obj, 3)), np.zeros((n, n_obj, 4)), np.zeros((n, n_obj, 6))
        for i, item in enumerate(scene.objects):
            q, v = scene_q[:, scene.object_q_slice(i)], scene_v[:, scene.object_v_slice(i)]
            if q.shape[1] == 7:
                position[:, i], quaternion[:, i] = q[:, :3], q[:, 3:]
                twist[:, i, :3], twist[:, i, 3:] = v[:, :3], _rotate(q[:, 3:], v[:, 3:])
            else:
                position[:, i] = item.pose.translation + q[:, :1] * item.direction
                quaternion[:, i] = pin.SE3ToXYZQUAT(item.pose)[3:]
                twist[:, i, :3] = v[:, :1] * item.direction
        return position, quaternion, twist

    def _contact_arrays(self, parts: list) -> dict[str, np.ndarray]:
        """The recorded contacts' arrays (:attr:`_CONTACT_FIELDS`), one sample's rows after the other.

        A compiled run's contacts are joined in C++ (one call instead of six array reads per sample).
        """
        core = default_core()
        if core is not None and parts and all(isinstance(part, core.Contacts) for part in parts):
            parts = [core.concatenate(parts)]
        arrays = {}
        for name, shape, kind in zip(
            self._CONTACT_FIELDS,
            ((-1,), (-1, 3), (-1, 3), (-1,), (-1, 3), (-1,)),
            (int, float, float, float, float, bool),
        ):
            values = [getattr(part, name) for part in parts]
            arrays[name] = (np.concatenate(values) if values else np.zeros(0)).astype(kind).reshape(shape)
        return arrays

    def trajectory(self) -> Trajectory:
        """The recorded run."""
        scene = self.scene
        n = len(self.t)
        scene_q = np.array(self.scene_q).reshape(n, scene.nq)
        scene_v = np.array(self.scene_v).reshape(n, scene.nv)
        position, quaternion, twist = self._objects(scene_q, scene_v)
        counts = [len(contacts) for contacts in self.contacts]
        arrays = self._contact_arrays([contacts for contacts, count in zip(self.contacts, counts) if count])
        return Trajectory(
            t=np.array(self.t),
            q=scene_q[:, : scene.nq_hand].copy(),
            v=scene_v[:, : scene.nv_hand].copy(),
            u=np.array(self.u).reshape(n, -1),
            tau=np.array(self.tau).reshape(n, -1),
            modes=np.array(self.modes).reshape(n, -1),
            object_position=position,
            object_quaternion=quaternion,
            object_twist=twist,
            contact_offsets=np.concatenate(([0], np.cumsum(counts))).astype(int),
            contact_pair=arrays["pair"],
            contact_point=arrays["point"],
            contact_normal=arrays["normal"],
            contact_depth=arrays["depth"],
            contact_force=arrays["force"],
            contact_sticking=arrays["sticking"],
            log={name: np.array(values) for name, values in self.log.items()},
            joint_names=scene.hand.joint_names,
            object_names=tuple(scene.object_names),
            pair_bodies=np.array([(p.body_a, p.body_b) for p in scene.pairs], dtype=str).reshape(-1, 2),
        )


def _rotate(quaternions: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """R(q) x for rows of unit quaternions (x, y, z, w) and vectors (N, 3): x + 2 w (u x x) + 2 u x (u x x)."""
    axis, scalar = quaternions[:, :3], quaternions[:, 3:]
    turned = 2.0 * np.cross(axis, vectors)
    return vectors + scalar * turned + np.cross(axis, turned)
