"""A free rigid body of any closed triangle mesh: mass properties from the mesh, collision as its convex hull.

Conventions as :mod:`bhgrasp.model.objects`: SI units; the body frame sits at the centre of mass with the axes of the
mesh's own frame (not its principal axes: the inertia is a full 3 x 3 tensor), so ``pose`` places the COM frame and
``center_of_mass`` says where the COM lies in the mesh's frame (a mesh placed at ``T`` has ``pose = T *
SE3(I, center_of_mass)``; :meth:`Mesh.at` does this).  Mass properties are the solid's (uniform density) from
trimesh's integration over the closed surface; a mesh that does not bound a volume is refused.  The body collides as
its convex hull (``collision="hull"``, as MuJoCo collides meshes: a mug's hole is filled) or as the hulls of the convex
pieces CoACD cuts it into (``collision="decomposed"``, :mod:`~bhgrasp.model.convex_decomposition`, cached on disk).
Grasp planning (:meth:`Mesh.geometry`) reads the hull either way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_array, as_positive
from bhgrasp.errors import InputError
from bhgrasp.model.convex_decomposition import convex_pieces
from bhgrasp.model.objects import RigidObject, frozen_array

__all__ = ["COLLISION", "Mesh"]

COLLISION = ("hull", "decomposed")


@dataclass(frozen=True, eq=False, repr=False)
class Mesh(RigidObject):
    """A solid of uniform density bounded by a closed triangle mesh.

    Args:
        mesh: A mesh file (``.obj``, ``.stl``, ``.ply``, ... read by trimesh, nothing fetched), a
            ``trimesh.Trimesh``, or ``(vertices (n, 3) [m], faces (m, 3) vertex indices)``; its frame is the file's.
        scale: Factor applied to the vertices (e.g. 0.001 for a file in millimetres).
        collision: ``"hull"`` (one convex shape) or ``"decomposed"`` (convex pieces, for a non-convex body).
        concavity: CoACD's threshold for ``"decomposed"`` (its default 0.05; smaller, more pieces).
        mass / density / pose / velocity / friction / name: As every :class:`~bhgrasp.model.objects.RigidObject`;
            ``pose`` places the body frame (the COM, mesh axes), see :meth:`at`.

    After construction ``mesh`` holds ``(vertices, faces)`` in the mesh's frame before scaling (read-only arrays),
    so ``dataclasses.replace`` rebuilds the same body.

    Raises:
        InputError: The file is missing or unreadable, the mesh is empty, open, inconsistently wound or of zero
            volume (its message names which; ``Mesh(trimesh_mesh.convex_hull, ...)`` takes the hull's mass instead).
    """

    mesh: Any
    scale: float = 1.0
    collision: str = "hull"
    concavity: float = 0.05

    def __post_init__(self) -> None:
        vertices, faces = _read(self.mesh)
        label = f"mesh {str(self.mesh)!r}" if isinstance(self.mesh, str | Path) else None
        object.__setattr__(self, "mesh", (frozen_array(vertices), frozen_array(faces, np.int64)))
        object.__setattr__(self, "_label", label or f"mesh of {len(vertices)} vertices, {len(faces)} faces")
        object.__setattr__(self, "scale", as_positive(self.scale, "scale"))
        object.__setattr__(self, "concavity", as_positive(self.concavity, "concavity"))
        if self.collision not in COLLISION:
            raise InputError(f"`collision` must be one of {COLLISION}, got {self.collision!r}")
        scaled = vertices * self.scale
        if not np.all(np.isfinite(scaled)):
            raise InputError(f"the {self.mesh_label} scaled by {self.scale!r} is not finite")
        solid = _solid(scaled, faces, self.mesh_label)
        volume = float(solid.volume)
        center = np.asarray(solid.center_mass, dtype=float)
        inertia_per_mass = np.asarray(solid.moment_inertia, dtype=float) / volume  # trimesh: density 1, about COM
        object.__setattr__(self, "center_of_mass", frozen_array(center))
        object.__setattr__(self, "vertices", frozen_array(solid.vertices - center))
        object.__setattr__(self, "faces", frozen_array(solid.faces, np.int64))
        object.__setattr__(self, "hull", _hull(solid.vertices - center))
        if self.collision == "hull":
            pieces: tuple = (self.hull,)
        else:
            source = (*self.mesh, self.scale)
            parts = convex_pieces(self.vertices, self.faces, self.concavity, source)
            pieces = tuple(_hull(part) for part in parts)
        object.__setattr__(self, "pieces", pieces)
        for piece in {id(p): p for p in (self.hull, *pieces)}.values():
            _convex(*piece, label=self.mesh_label)  # coal refuses some hulls: say so now, not in a later step
        if not (np.all(np.isfinite(center)) and np.all(np.isfinite(inertia_per_mass))):
            raise InputError(f"the {self.mesh_label}'s mass properties are not finite (scale {self.scale!r})")
        object.__setattr__(self, "_unit_inertia", frozen_array(0.5 * (inertia_per_mass + inertia_per_mass.T)))
        object.__setattr__(self, "_volume", volume)
        super().__post_init__()

    @property
    def mesh_label(self) -> str:
        """The mesh's name in messages: its file or its size."""
        return self._label

    @property
    def hull_volume(self) -> float:
        """Volume [m^3] of the mesh's convex hull (equal to :attr:`volume` for a convex body)."""
        import trimesh

        return float(trimesh.Trimesh(*self.hull).volume)

    @property
    def inertia(self) -> np.ndarray:
        """Rotational inertia about the COM in the body (mesh-aligned) frame, (3, 3) [kg m^2] (a fresh array)."""
        return self.mass * np.array(self._unit_inertia)

    def at(self, mesh_pose: pin.SE3, **changes: Any) -> Mesh:
        """This body with its mesh frame placed at ``mesh_pose`` (world): ``pose = mesh_pose * SE3(I, COM)``."""
        if not isinstance(mesh_pose, pin.SE3):
            raise InputError(f"`mesh_pose` must be a pinocchio.SE3, got {type(mesh_pose).__name__}")
        pose = mesh_pose * pin.SE3(np.eye(3), np.array(self.center_of_mass))
        return _replaced(self, pose=pose, **changes)

    def geometry(self) -> coal.Convex:
        """A new ``coal.Convex`` of the mesh's convex hull in the body frame (what grasp planning reads)."""
        return _convex(*self.hull)

    def collision_shapes(self) -> list[coal.Convex]:
        """What the simulator collides: the hull, or each convex piece's hull (body frame)."""
        return [_convex(*piece) for piece in self.pieces]

    def surface(self) -> coal.BVHModelOBBRSS:
        """The mesh's own triangles in the body frame as a coal triangle model, for drawing (not what collides)."""
        model = coal.BVHModelOBBRSS()
        model.beginModel(len(self.faces), len(self.vertices))
        model.addSubModel(_points(self.vertices), _triangles(self.faces))
        model.endModel()
        return model

    def __setstate__(self, state: dict) -> None:
        """Unpickled: its arrays read-only again (pickle does not keep the flag)."""
        for key, value in state.items():
            object.__setattr__(self, key, _frozen(value))

    def _mass_properties(self) -> tuple[float, np.ndarray, float]:
        radius = float(np.sqrt((self.vertices**2).sum(axis=1)).max())
        return self._volume, np.linalg.eigvalsh(self._unit_inertia), radius

    def _shape_fields(self) -> list[str]:
        return []  # the mesh is checked in __post_init__

    def __repr__(self) -> str:
        label = "" if self.name is None else f"name={self.name!r}, "
        position = (np.round(self.pose.translation, 6) + 0.0).tolist()
        size = f"{len(self.vertices)} vertices, {self.collision} ({len(self.pieces)} convex)"
        return f"Mesh({label}{size}, mass={self.mass:.6g}, position={position})"


def _replaced(item: Mesh, **changes: Any) -> Mesh:
    fields = {"mesh": item.mesh, "scale": item.scale, "pose": item.pose, "velocity": item.velocity}
    fields.update(friction=item.friction, name=item.name, collision=item.collision, concavity=item.concavity)
    fields.update(changes)
    if "mass" not in changes and "density" not in changes:
        fields["mass"] = item.mass
    return Mesh(**fields)


def _read(source: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices, faces)`` of a path, a trimesh.Trimesh or a (vertices, faces) pair."""
    import trimesh

    if isinstance(source, str | Path):
        path = Path(source)
        if not path.is_file():
            raise InputError(f"mesh file {str(path)!r} does not exist")
        try:
            loaded = trimesh.load(path, force="mesh", process=True)
        except Exception as error:  # trimesh raises many kinds for a malformed file
            raise InputError(f"mesh file {str(path)!r} could not be read: {error}") from error
        source = loaded
    if isinstance(source, trimesh.Trimesh):
        return as_array(np.asarray(source.vertices), "mesh vertices", (None, 3)), np.asarray(source.faces)
    if isinstance(source, tuple | list) and len(source) == 2:
        vertices = as_array(source[0], "mesh vertices", (None, 3))
        faces = np.asarray(source[1])
        if faces.ndim != 2 or faces.shape[1] != 3 or not np.issubdtype(faces.dtype, np.integer):
            raise InputError(f"mesh faces must be an (m, 3) integer array, got shape {faces.shape} {faces.dtype}")
        if faces.size and (faces.min() < 0 or faces.max() >= len(vertices)):
            raise InputError(
                f"mesh faces index vertices 0..{len(vertices) - 1}, got indices {faces.min()}..{faces.max()}"
            )
        return vertices, faces
    raise InputError(f"`mesh` must be a file path, a trimesh.Trimesh or (vertices, faces), got {type(source).__name__}")


def _solid(vertices: np.ndarray, faces: np.ndarray, label: str):
    """The trimesh of a closed, consistently wound, positive-volume mesh (else an InputError saying which)."""
    import trimesh

    if len(faces) < 4:
        raise InputError(f"a solid needs at least 4 faces, got a {label}")
    solid = trimesh.Trimesh(vertices=vertices, faces=faces, process=True)
    if not solid.is_watertight:
        raise InputError(
            f"the {label} is not closed (watertight), so it bounds no volume; repair it or pass "
            "`trimesh_mesh.convex_hull` to use its hull's mass properties"
        )
    if not solid.is_winding_consistent:
        raise InputError(f"the {label} has inconsistently wound faces; fix them with trimesh.repair.fix_winding")
    if solid.volume < 0.0:
        solid.invert()  # inward-facing normals: the same solid
    if not solid.volume > 0.0 or not math.isfinite(solid.volume):
        raise InputError(f"the {label} encloses no volume (volume {solid.volume!r} m^3)")
    return solid


def _hull(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, outward triangles) of the convex hull of ``points`` (qhull through trimesh), read-only."""
    import trimesh

    hull = trimesh.convex.convex_hull(np.asarray(points, dtype=float))
    return frozen_array(hull.vertices), frozen_array(hull.faces, np.int64)


def _convex(vertices: np.ndarray, faces: np.ndarray, label: str = "mesh") -> coal.Convex:
    try:
        return coal.Convex(_points(vertices), _triangles(faces))
    except RuntimeError as error:  # coal keeps at most 255 neighbours a vertex ("Too many neighbors.")
        raise InputError(
            f"coal cannot collide the convex hull of the {label} ({len(vertices)} vertices): "
            f"{str(error).strip().splitlines()[-1]} (a vertex of the hull joins more than 255 triangles, e.g. a cap "
            "of over 255 sides); give a coarser mesh"
        ) from error


def _points(vertices: np.ndarray) -> coal.StdVec_Vec3s:
    points = coal.StdVec_Vec3s()
    points.extend(np.array(vertices, dtype=np.float64))
    return points


def _triangles(faces: np.ndarray) -> coal.StdVec_Triangle:
    triangles = coal.StdVec_Triangle()
    triangles.extend(coal.Triangle(int(a), int(b), int(c)) for a, b, c in faces)
    return triangles


def _frozen(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        value.setflags(write=False)
    elif isinstance(value, tuple):
        for item in value:
            _frozen(item)
    return value
