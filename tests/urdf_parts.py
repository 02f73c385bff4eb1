"""URDF pieces the tests write their own hands from (a gripper's finger links)."""

from __future__ import annotations


def rod(name: str, length: float, lever: tuple[float, float] = (0.0, 0.0)) -> str:
    """A 50 g, 8 mm-radius cylinder link along z from its joint, centre of mass at ``lever`` (x, y [m]) off its axis."""
    side, end = 0.05 * (3 * 0.008**2 + length**2) / 12, 0.05 * 0.008**2 / 2
    shape = f'<origin xyz="0 0 {length / 2}"/><geometry><cylinder radius="0.008" length="{length}"/></geometry>'
    return (
        f'<link name="{name}"><inertial><origin xyz="{lever[0]:g} {lever[1]:g} {length / 2}"/><mass value="0.05"/>'
        f'<inertia ixx="{side}" iyy="{side}" izz="{end}" ixy="0" ixz="0" iyz="0"/></inertial>'
        f"<visual>{shape}</visual><collision>{shape}</collision></link>"
    )
