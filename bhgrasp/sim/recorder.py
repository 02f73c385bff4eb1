"""Recorder: collects a simulation run sample by sample into a :class:`~bhgrasp.sim.state.Trajectory`."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp.sim.actuation import Actuation
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.state import State, Trajectory


class Recorder:
    """Collects a run sample by sample and assembles the :class:`~bhgrasp.sim.state.Trajectory`."""

    def __init__(self, scene: Scene, actuation: Actuation) -> None:
        """Record ``scene`` driven through ``actuation`` (for its mode flags)."""
        n_obj = len(scene.objects)
        self.scene, self.actuation = scene, actuation
        self.t, self.q, self.v = [], [], []
        self.u, self.tau, self.modes = [], [], []
        self.position, self.quaternion, self.twist = [], [], []
        self.offsets = [0]
        self.contacts: dict[str, list] = {k: [] for k in ("pair", "point", "normal", "depth", "force", "sticking")}
        self.log: dict[str, list] = {}
        self.n_obj = n_obj

    def add(self, state: State, u: np.ndarray, info: Any, log: Any) -> None:
        """Append one sample: state, held input, the step's contacts and drive torques, controller internals."""
        self.t.append(state.t)
        self.q.append(state.q)
        self.v.append(state.v)
        self.u.append(u.copy())
        self.tau.append(info.drive_torques)
        self.modes.append(self.actuation.modes())
        self.position.append([pose.translation for pose in state.object_poses])
        self.quaternion.append([pin.SE3ToXYZQUAT(pose)[3:] for pose in state.object_poses])
        self.twist.append(state.object_twists)
        contacts = info.contacts
        self.offsets.append(self.offsets[-1] + len(contacts))
        for name in self.contacts:
            self.contacts[name].append(getattr(contacts, name))
        if isinstance(log, dict):
            self._add_log(log)

    def _add_log(self, log: dict) -> None:
        """Append the controller's log; a key absent from a sample (before it first appears, or skipped) is NaN."""
        count = len(self.t)
        for name, value in log.items():
            value = np.array(value, dtype=float)
            values = self.log.setdefault(name, [])
            values.extend(np.full(value.shape, np.nan) for _ in range(count - 1 - len(values)))
            values.append(value)
        for values in self.log.values():
            if len(values) < count:
                values.append(np.full(values[-1].shape, np.nan))

    def trajectory(self) -> Trajectory:
        """The recorded run."""
        n_obj = self.n_obj
        contacts = {name: np.concatenate(values) if values else np.zeros(0) for name, values in self.contacts.items()}
        for name, width in (("point", 3), ("normal", 3), ("force", 3)):
            contacts[name] = contacts[name].reshape(-1, width)
        scene = self.scene
        return Trajectory(
            t=np.array(self.t),
            q=np.array(self.q),
            v=np.array(self.v),
            u=np.array(self.u),
            tau=np.array(self.tau),
            modes=np.array(self.modes).reshape(len(self.t), -1),
            object_position=np.array(self.position).reshape(len(self.t), n_obj, 3),
            object_quaternion=np.array(self.quaternion).reshape(len(self.t), n_obj, 4),
            object_twist=np.array(self.twist).reshape(len(self.t), n_obj, 6),
            contact_offsets=np.array(self.offsets, dtype=int),
            contact_pair=contacts["pair"].astype(int),
            contact_point=contacts["point"],
            contact_normal=contacts["normal"],
            contact_depth=contacts["depth"],
            contact_force=contacts["force"],
            contact_sticking=contacts["sticking"].astype(bool),
            log={name: np.array(values) for name, values in self.log.items()},
            joint_names=scene.hand.joint_names,
            object_names=tuple(scene.object_names),
            pair_bodies=np.array([(p.body_a, p.body_b) for p in scene.pairs], dtype=str).reshape(-1, 2),
        )
