"""What a hand's algorithms read of it: :class:`HandDescription`, with its :class:`BaseFrame` and :class:`JointLayout`.

:class:`~bhgrasp.model.hand.Hand` is the hand there is; the algorithm families (:mod:`~bhgrasp.model.hand_joints`,
:mod:`~bhgrasp.model.hand_kinematics`, :mod:`~bhgrasp.model.hand_dynamics`, :mod:`~bhgrasp.model.urdf`), which it
offers as methods, type their argument with the protocol declared here, below them and the class: no import runs
between the class and its algorithms, not even one of types.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple, Protocol

import numpy as np
import pinocchio as pin

from bhgrasp.model.couplings import Coupling, TwinMap


class BaseFrame(NamedTuple):
    """The hand base in the world as the algorithms read it; a new one whenever the placement or gravity change."""

    placement: pin.SE3  # transform_base_to_world
    rotation: np.ndarray  # (3, 3) base -> world, read-only
    translation: np.ndarray  # (3,) [m] base origin in the world, read-only
    at_origin: bool  # the placement is the identity (world = base frame)
    gravity: np.ndarray  # (3,) [m/s^2] gravity in base coordinates, read-only


@dataclass(frozen=True)
class JointLayout:
    """Which coordinate of ``q``/``v`` is which joint, and which joints move which fingertip."""

    joint_names: tuple[str, ...]  # the joints with a coordinate, in Pinocchio's order (mimic joints have none)
    indices: Mapping[str, int]  # joint name -> its index in q and v
    finger_joints: Mapping[str, tuple[str, ...]]  # finger -> its joints from the base out (no base joint)

    @classmethod
    def of(
        cls, model: pin.Model, tip_ids: Mapping[str, int], base_joints: Sequence[str], couplings: Sequence[Coupling]
    ) -> JointLayout:
        """The layout of ``model`` with fingertip frames ``tip_ids`` (finger -> frame id).

        A mimic joint counts as the joint it mimics (listed once in a finger's joints, where first met).
        """
        mimics = {coupling.joint: coupling.mimics for coupling in couplings}
        names = tuple(name for name in model.names[1:] if name not in mimics)
        indices = {name: model.joints[model.getJointId(name)].idx_v for name in names}
        base, fingers = set(base_joints), {}
        for finger, frame in tip_ids.items():
            supports = model.supports[model.frames[frame].parentJoint][1:]
            joints = (mimics.get(model.names[j], model.names[j]) for j in supports if model.names[j] not in base)
            fingers[finger] = tuple(dict.fromkeys(joints))  # in order, each once
        return cls(names, indices, fingers)


class HandDescription(Protocol):
    """The members of a :class:`~bhgrasp.model.hand.Hand` its algorithm families read (the class documents each)."""

    name: str
    model: pin.Model
    data: pin.Data
    nv: int
    couplings: tuple[Coupling, ...]
    layout: JointLayout
    joint_names: tuple[str, ...]
    fingers: tuple[str, ...]
    fingertip_frames: dict[str, str]
    fingertip_ids: tuple[int, ...]
    base: BaseFrame
    twin: tuple[pin.Model, pin.Data, TwinMap]
    total_mass: float
    collision_geometry: pin.GeometryModel | None
    urdf_path: Path | None

    def check_q(self, q: Any) -> np.ndarray:
        """``q`` checked: finite, size ``nq``."""
        ...

    def check_v(self, v: Any, name: str = "v") -> np.ndarray:
        """A velocity-sized vector checked: finite, size ``nv``."""
        ...

    def frame_id(self, frame: str) -> int:
        """Pinocchio id of a frame."""
        ...

    def fingertip_id(self, finger: str) -> int:
        """Pinocchio frame id of a finger's tip."""
        ...

    def configuration(self, **joint_values: float) -> np.ndarray:
        """Neutral configuration with the named joints set [rad]."""
        ...

    def with_model(self, model: pin.Model, name: str) -> HandDescription:
        """The same hand on another model."""
        ...


__all__ = ["BaseFrame", "HandDescription", "JointLayout"]
