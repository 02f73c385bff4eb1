"""Household objects as meshes, built by code (nothing is downloaded): a mug, a bottle, a bowl, a banana, a drill.

Sizes and masses are of the YCB objects of the same kind (Calli et al., "Benchmarking in manipulation research: the
YCB object and model set", IEEE RAM 2015; its object table), rounded, the shapes simplified: a mug (025), a mustard
bottle (006), a bowl (024), a banana (011), a power drill (035).  Each is a closed triangle mesh of a few hundred to two
thousand triangles, made with trimesh's solids of revolution and manifold3d's unions and hulls; the frame is the
object's standing pose, z up, the base at z = 0.  :func:`household` gives it as a :class:`~bhgrasp.model.mesh_object.
Mesh` standing on a point; the non-convex ones (mug, bowl, banana, drill) collide as convex pieces by default.
"""

from __future__ import annotations

import itertools
import math
import warnings
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_vector
from bhgrasp.errors import InputError
from bhgrasp.model.mesh_object import Mesh

SECTIONS = 32  # facets around a solid of revolution

# name: (YCB mass [kg], whether the shape is non-convex)
HOUSEHOLD = {
    "mug": (0.118, True),
    "bottle": (0.30, False),
    "bowl": (0.147, True),
    "banana": (0.066, True),
    "drill": (0.895, True),
}

__all__ = ["HOUSEHOLD", "household", "household_mesh"]


def household_mesh(name: str):
    """The closed ``trimesh.Trimesh`` of a household object (its standing frame, [m])."""
    import trimesh

    builders = {"mug": _mug, "bottle": _bottle, "bowl": _bowl, "banana": _banana, "drill": _drill}
    if name not in builders:
        raise InputError(f"unknown household object {name!r}; valid: {', '.join(HOUSEHOLD)}")
    mesh = builders[name]()
    # On a 1 nm grid: a machine whose sine differs in the last bit builds the same mesh, so finds its shipped pieces
    return trimesh.Trimesh(vertices=np.round(mesh.vertices, 9), faces=mesh.faces, process=True)


def household(kind: str, position: Any = (0.0, 0.0, 0.0), collision: str | None = None, **fields: Any) -> Mesh:
    """A household object standing with its base centre at ``position`` (world) [m], its YCB mass.

    Args:
        kind: One of :data:`HOUSEHOLD`.
        position: Where its base's centre stands.
        collision: ``"hull"`` or ``"decomposed"`` (default: decomposed for the non-convex ones).
        fields: Any other :class:`~bhgrasp.model.mesh_object.Mesh` field (``mass``, ``friction``, ``name``: default
            ``kind``, ...).
    """
    mass, concave = HOUSEHOLD[kind] if kind in HOUSEHOLD else (None, False)
    mesh = household_mesh(kind)
    collision = collision or ("decomposed" if concave else "hull")
    if collision == "decomposed":
        _warn_unless_shipped(kind, mesh, fields.get("concavity", 0.05))
    fields.setdefault("name", kind)
    if "density" not in fields:
        fields.setdefault("mass", mass)
    standing = Mesh(mesh, collision=collision, **fields)
    place = pin.SE3(np.eye(3), as_vector(position, "position", 3))
    return standing.at(place)


def _warn_unless_shipped(kind: str, mesh, concavity: float) -> None:
    """Warn when this machine builds a household mesh whose pieces were not shipped.

    (Another trimesh or manifold3d may triangulate it otherwise: its pieces are then cut afresh and differ from those
    behind the committed results.)
    """
    from bhgrasp.model import convex_decomposition as cd

    key = cd.decomposition_key(np.asarray(mesh.vertices), np.asarray(mesh.faces), 1.0, concavity)
    if not (cd.SHIPPED / f"{key}.npz").is_file():
        warnings.warn(
            f"the household {kind}'s mesh differs from the one its shipped pieces were cut from (another trimesh or "
            "manifold3d?): it is cut afresh, and its simulations differ from the committed results",
            stacklevel=3,
        )


def _revolved(profile: list[tuple[float, float]]):
    """The solid of revolution about z of a closed (r, z) profile that starts and ends on the axis."""
    import trimesh

    return trimesh.creation.revolve(np.array(profile, dtype=float), sections=SECTIONS)


def _from_manifold(solid):
    import trimesh

    mesh = solid.to_mesh()
    return trimesh.Trimesh(vertices=np.asarray(mesh.vert_properties)[:, :3], faces=np.asarray(mesh.tri_verts))


def _to_manifold(mesh):
    import manifold3d

    return manifold3d.Manifold(
        manifold3d.Mesh(
            vert_properties=np.asarray(mesh.vertices, dtype=np.float32), tri_verts=np.asarray(mesh.faces, np.uint32)
        )
    )


def _mug():
    """A mug 80 mm across, 95 mm tall, 4 mm walls on a 6 mm base, a ring handle."""
    import manifold3d

    profile = [(0.0, 0.0), (0.040, 0.0), (0.040, 0.095), (0.036, 0.095), (0.036, 0.006), (0.0, 0.006)]
    cup = _to_manifold(_revolved(profile))
    outer = manifold3d.Manifold.cylinder(0.012, 0.030, 0.030, SECTIONS)
    hole = manifold3d.Manifold.cylinder(0.014, 0.022, 0.022, SECTIONS).translate((0.0, 0.0, -0.001))
    handle = (outer - hole).translate((0.0, 0.0, -0.006)).rotate((90.0, 0.0, 0.0)).translate((0.048, 0.0, 0.050))
    handle = handle - manifold3d.Manifold.cylinder(0.095, 0.038, 0.038, SECTIONS)  # not into the cup's inside
    return _from_manifold(cup + handle)


def _bottle():
    """A mustard-like bottle: a 66 mm body 140 mm tall, a shoulder, a 28 mm neck to 190 mm."""
    return _revolved([(0.0, 0.0), (0.033, 0.0), (0.033, 0.140), (0.014, 0.165), (0.014, 0.190), (0.0, 0.190)])


def _bowl():
    """A bowl 160 mm across and 55 mm tall, 5 mm walls curving up from a 90 mm foot."""
    sweep = np.linspace(0.0, math.pi / 2, 9)
    outer = [(0.045 + 0.035 * math.sin(a), 0.055 * (1.0 - math.cos(a))) for a in sweep]
    inner = [(0.040 + 0.035 * math.sin(a), 0.005 + 0.050 * (1.0 - math.cos(a))) for a in sweep[::-1]]
    return _revolved([(0.0, 0.0), *outer, *inner, (0.0, 0.005)])


def _banana():
    """A banana: 12 spheres of 13-18 mm radius along a 100 mm arc, joined by their pairwise hulls (162 mm long)."""
    import manifold3d

    angles = np.linspace(-0.75, 0.75, 12)
    radii = 0.018 - 0.005 * np.abs(angles) / 0.75
    centres = [(0.1 * math.sin(a), 0.0, 0.1 * (1.0 - math.cos(a))) for a in angles]
    balls = [manifold3d.Manifold.sphere(r, 16).translate(c) for r, c in zip(radii, centres)]
    segments = [manifold3d.Manifold.batch_hull([a, b]) for a, b in itertools.pairwise(balls)]
    solid = manifold3d.Manifold.batch_boolean(segments, manifold3d.OpType.Add)
    return _standing(_from_manifold(solid))


def _drill():
    """A drill as an L: a 60 mm x 200 mm barrel on a 45 mm x 50 mm handle 130 mm tall, on a 70 x 110 mm battery."""
    import manifold3d

    battery = manifold3d.Manifold.cube((0.110, 0.070, 0.040), True).translate((0.0, 0.0, 0.020))
    handle = manifold3d.Manifold.cube((0.050, 0.045, 0.130), True).translate((0.0, 0.0, 0.105))
    barrel = manifold3d.Manifold.cylinder(0.200, 0.030, 0.030, SECTIONS).rotate((0.0, 90.0, 0.0))
    barrel = barrel.translate((-0.060, 0.0, 0.200))
    return _from_manifold(battery + handle + barrel)


def _standing(mesh):
    """``mesh`` moved so that its base's centre is the origin (its lowest point at z = 0)."""
    low, high = mesh.bounds
    mesh.apply_translation([-(low[0] + high[0]) / 2, -(low[1] + high[1]) / 2, -low[2]])
    return mesh


def write_shipped_pieces() -> list[str]:
    """Decompose the non-convex household objects afresh and store their pieces in ``SHIPPED`` (their file names)."""
    from bhgrasp.model import convex_decomposition as cd

    written = []
    for name, (_, concave) in HOUSEHOLD.items():
        if not concave:
            continue
        mesh = Mesh(household_mesh(name), mass=1.0)  # its vertices as the decomposition reads them (body frame)
        key = cd.decomposition_key(*mesh.mesh, mesh.scale, mesh.concavity)
        pieces = cd._decompose(np.array(mesh.vertices), np.array(mesh.faces, dtype=np.int32), mesh.concavity)
        cd.write_pieces(cd.SHIPPED / f"{key}.npz", pieces)
        written.append(f"{name}: {key}.npz")
    return written
