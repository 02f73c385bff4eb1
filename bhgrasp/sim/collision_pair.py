"""One collision pair of a scene: its geometries, the joints that carry them, and its friction."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class CollisionPair:
    """Two geometries that may touch: forces act on ``b`` along the contact normal (from ``a`` to ``b``).

    Attributes:
        index: Index in the scene's pairs (:attr:`Scene.pairs <bhgrasp.sim.scene.Scene.pairs>`).
        geom_a: Geometry index of body a (a hand link, the environment, or the first object).
        geom_b: Geometry index of body b (an object, or a hand link that the environment stops).
        joint_a: Pinocchio joint carrying body a (0 = fixed: environment or palm).
        joint_b: Joint carrying body b.
        body_a: Display name of body a (link, environment or object name).
        body_b: Display name of body b.
        friction_a: Coulomb coefficient of surface a; ``None`` for a hand link (the contact law's pad value).
        friction_b: Coulomb coefficient of surface b; ``None`` for a hand link.
    """

    index: int
    geom_a: int
    geom_b: int
    joint_a: int
    joint_b: int
    body_a: str
    body_b: str
    friction_a: float | None
    friction_b: float | None

    def friction(self, hand_friction: float) -> float:
        """Coefficient of the pair: the smaller of the two surfaces' (hand pads have ``hand_friction``)."""
        first = hand_friction if self.friction_a is None else self.friction_a
        second = hand_friction if self.friction_b is None else self.friction_b
        return min(first, second)


__all__ = ["CollisionPair"]
