"""What a step reads of a scene beyond its model: free bodies' spin, spring coordinates, quaternions, its signature.

Plain data computed once from a :class:`~bhgrasp.sim.scene.Scene`, for the engines (the implicit-midpoint gyroscopic
torque, the object springs) and for the Simulator's check of an incoming state (whose scene it is, which of its
coordinates are unit quaternions).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from bhgrasp.model.objects import RigidObject
from bhgrasp.sim.geometry_text import geometry_text
from bhgrasp.sim.scene import Scene

_NAME_CACHE = 1024  # contact lists whose body names are kept (a grasp meets a handful, a pile more)


@dataclass(frozen=True, eq=False)
class SceneLayout:
    """A scene's layout as its steps read it.

    Attributes:
        spinning_bodies: Per free body: (its angular velocity coordinates, principal axes (columns, body frame),
            principal moments [kg m^2]).
        spring_q, spring_v: Configuration and velocity coordinates of the spring-mounted objects.
        quaternions: Per free body, the slice of its unit quaternion (x, y, z, w) in the scene ``q``.
        pair_bodies: (body a, body b) names of each collision pair.
        signature: A digest of the scene's model and collision geometry: equal for scenes built alike, different
            when a body, a shape, a joint or a placement differs.
    """

    spinning_bodies: tuple[tuple[slice, np.ndarray, tuple[float, float, float]], ...]
    spring_q: np.ndarray
    spring_v: np.ndarray
    quaternions: tuple[slice, ...]
    pair_bodies: tuple[tuple[str, str], ...]
    signature: str
    _names: dict[bytes, tuple[tuple[str, str], ...]] = field(default_factory=dict, init=False, repr=False)

    def body_names(self, pairs: np.ndarray) -> tuple[tuple[str, str], ...]:
        """(body a, body b) of each contact's pair index in ``pairs``; a repeated list's tuple is kept."""
        key = np.asarray(pairs, dtype=np.int64).tobytes()  # (an int32 [1, 0] has the bytes of an int64 [1])
        names = self._names.get(key)
        if names is None:
            if len(self._names) >= _NAME_CACHE:
                self._names.clear()
            bodies = self.pair_bodies
            names = self._names[key] = tuple(bodies[k] for k in pairs)
        return names

    @classmethod
    def of(cls, scene: Scene) -> SceneLayout:
        """The layout of ``scene`` (serialises its model and geometry once, for the signature)."""
        spinning, quaternions, springs = [], [], []
        for i, item in enumerate(scene.objects):
            if isinstance(item, RigidObject):
                moments, axes = np.linalg.eigh(item.spatial_inertia().inertia)
                velocity = scene.object_v_slice(i)
                spinning.append((slice(velocity.start + 3, velocity.stop), axes, tuple(float(x) for x in moments)))
                position = scene.object_q_slice(i)
                quaternions.append(slice(position.start + 3, position.stop))
            else:
                springs.append(i)
        digest = hashlib.sha256(scene.model.saveToString().encode())
        digest.update(geometry_text(scene.geometry).encode())
        return cls(
            spinning_bodies=tuple(spinning),
            spring_q=np.array([scene.object_q_slice(i).start for i in springs], dtype=int),
            spring_v=np.array([scene.object_v_slice(i).start for i in springs], dtype=int),
            quaternions=tuple(quaternions),
            pair_bodies=tuple((pair.body_a, pair.body_b) for pair in scene.pairs),
            signature=digest.hexdigest(),
        )


def object_states(scene: Scene, q: np.ndarray, v: np.ndarray) -> tuple[tuple[pin.SE3, ...], np.ndarray]:
    """Object poses (COM frames, world) and twists (n_objects, 6) (COM velocity, angular velocity; world)."""
    n = len(scene.objects)
    poses = tuple(scene.object_pose(q, i) for i in range(n))
    return poses, np.array([scene.object_twist(q, v, i) for i in range(n)]).reshape(n, 6)


__all__ = ["SceneLayout", "object_states"]
