"""A collision geometry as text for the compiled engine, convex shapes included.

Pinocchio 4.1 serialises a ``pin.GeometryModel`` with its primitive shapes but not a ``coal.Convex`` (a mesh object's
hull: "unregistered class").  :func:`geometry_text` writes each convex shape's points (hexadecimal floats, exact) and
triangles ahead of the model's own text, with a small sphere in its place there; ``src/convex_shapes.cpp`` reads
them back and puts each shape back in its place, so both engines collide the same hull, bit for bit.
"""

from __future__ import annotations

import coal
import pinocchio as pin

HEADER = "bhgrasp-convex-shapes 1"
PLACEHOLDER_RADIUS = 1e-3  # [m] the sphere in each convex shape's place (src/convex_shapes.hpp checks it)


def geometry_text(geometry: pin.GeometryModel) -> str:
    """``geometry`` as text for ``bhgrasp._core`` (its own ``saveToString()`` when it holds no convex shape)."""
    convex = [(i, item.geometry) for i, item in enumerate(geometry.geometryObjects)]
    convex = [(i, shape) for i, shape in convex if isinstance(shape, coal.Convex)]
    if not convex:
        return geometry.saveToString()
    placeholder = geometry.copy()  # its objects are copies: the scene's own shapes stay
    lines = [f"{HEADER} {len(convex)}"]
    for index, shape in convex:
        placeholder.geometryObjects[index].geometry = coal.Sphere(PLACEHOLDER_RADIUS)
        points = shape.points()
        triangles = [shape.polygons(t) for t in range(shape.num_polygons)]
        lines.append(f"{index} {len(points)} {len(triangles)}")
        lines += [" ".join(float(x).hex() for x in point) for point in points]
        lines += [f"{t[0]} {t[1]} {t[2]}" for t in triangles]
    return "\n".join(lines) + "\n" + placeholder.saveToString()


__all__ = ["HEADER", "PLACEHOLDER_RADIUS", "geometry_text"]
