"""What a path check finds (:mod:`bhgrasp.grasp.path_check`): gaps, drift, clearance, touches, a joint's limit."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bhgrasp.errors import UnreachableError

TOLERANCE = 2e-4  # [m] signed distance below which another geometry counts as meeting the object: a margin for
# what the path model leaves out (it holds each pad's gap at its start, while the pads sink further as their forces
# change: 0.1 mm per newton at the chapter-5 scene's 10 kN/m).  Chosen between two measurements in that scene: a
# 0.15 rad turn of the synthesised ball grasp about y kept 0.036 mm here and F1's distal link body touched the ball
# (0.27 N, sliding); the closest path that then ran clean kept 0.30 mm.  A stiffer scene may take less
# (GraspSupervisor(planning=Planning(path_tolerance=...)))


@dataclass(frozen=True)
class PathTouch:
    """Where a hand geometry other than a planned contact first comes within the tolerance of the object.

    Attributes:
        fraction: Path blend b in [0, 1] (the minimum-jerk blend, not time) of the first touching step.
        angle: Object rotation [rad] reached there, b |dtheta|.
        geometry: The hand collision geometry's name (e.g. ``F3_distal_link_0``: the distal link's body).
        link: The frame it hangs on.
        face: The object's face it meets (``"+y"``: the box face normal to its +y axis; "" for another shape).
        distance: Its signed distance [m] to the object there (negative: penetration).
        point: (3,) the witness point on the hand geometry [m], world, at that step.
        spacing: Distance [m] from that point to the nearest planned contact on the same joint (inf if none).
    """

    fraction: float
    angle: float
    geometry: str
    link: str
    face: str
    distance: float
    point: np.ndarray
    spacing: float

    def __repr__(self) -> str:
        where = f"{self.geometry} on {self.face or 'the object'} at b={self.fraction:.3f} ({self.angle:.3f} rad)"
        return f"PathTouch({where}, {1e3 * self.distance:.2f} mm, {1e3 * self.spacing:.1f} mm from its pad)"


@dataclass(frozen=True)
class PathContacts:
    """The fingers along an object motion with rolling, non-slipping contacts, and what they meet (world frame).

    Attributes:
        fractions: (k,) path blends b of the steps, 0 to 1.
        q: (k, nq) joint positions [rad] at each step.
        gaps: (k, n) each planned contact's signed gap [m] (held at its start value).
        drift: (k, n) per contact, the accumulated |J dq - demand| [m]: the sliding the joints leave (second order).
        clearance: (k, m) signed distance [m] of each other hand geometry to the object.
        geometries: The m other geometries' names (every hand geometry but the planned contacts').
        touches: Where each geometry first comes within ``tolerance`` of the object (:class:`PathTouch`), in path
            order.
        limit: (fraction, joint) where a joint first leaves its limits, ``None`` if none does.
        offset: The motion (dx [m], dtheta [rad]), world; contacts: a name per contact.
        tolerance: The signed distance [m] below which a geometry counted as meeting the object.
    """

    fractions: np.ndarray
    q: np.ndarray
    gaps: np.ndarray
    drift: np.ndarray
    clearance: np.ndarray
    geometries: tuple[str, ...]
    touches: tuple[PathTouch, ...]
    limit: tuple[float, str] | None
    offset: np.ndarray
    contacts: tuple[str, ...]
    tolerance: float = TOLERANCE

    @property
    def touch(self) -> PathTouch | None:
        """The first new contact along the path, ``None`` if the path keeps to the planned ones."""
        return self.touches[0] if self.touches else None

    @property
    def ok(self) -> bool:
        """Whether the path keeps to the planned contacts and inside the joint limits."""
        return not self.touches and self.limit is None

    def __repr__(self) -> str:
        drift = 1e3 * float(self.drift.max(initial=0.0))
        return f"PathContacts(ok={self.ok}, touch={self.touch!r}, limit={self.limit}, max drift {drift:.3f} mm)"

    def check(self) -> None:
        """Refuse the motion if a link comes near the object off its planned contacts, or a joint leaves its limits.

        Near: within ``tolerance``.

        Raises:
            UnreachableError: The message names the geometry, its link and the object's face (or the joint), where
                along the path (blend and angle) and how deep at the end; ``result`` is this :class:`PathContacts`.
        """
        motion = f"the motion {np.round(self.offset, 6).tolist()} (dx [m], dtheta [rad])"
        if self.touches:
            t, column = self.touches[0], self.geometries.index(self.touches[0].geometry)
            end = self.clearance[-1, column]
            ending = f"{1e3 * -end:.2f} mm into it" if end < 0.0 else f"{1e3 * end:.2f} mm from it"
            raise UnreachableError(
                f"{motion}: {t.geometry} ({t.link}) comes within {1e3 * self.tolerance:g} mm of the object's "
                f"{t.face or ''} face {1e3 * t.spacing:.1f} mm from its pad at {100 * t.fraction:.0f} % of the path "
                f"({t.angle:.3f} rad) and ends {ending} (second order, contacts rolling without slip)",
                self,
            )
        if self.limit is not None:
            raise UnreachableError(
                f"{motion}: joint {self.limit[1]} leaves its limits at {100 * self.limit[0]:.0f} % of the path "
                "(second order, contacts rolling without slip)",
                self,
            )


__all__ = ["TOLERANCE", "PathContacts", "PathTouch"]
