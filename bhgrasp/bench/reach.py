"""How a closing BH8-280 finger reaches an object placed in the hand frame: coal distances and touch angles.

:class:`Reach` closes every finger from a pre-shape (the distal at a third of the proximal, as before the
TorqueSwitch breaks away) and finds, by bisection on coal's distance between the finger's collision shapes and the
object, the proximal angle at which each first touches it, the link that does and where.  The benchmark's placement
(:mod:`~bhgrasp.bench.placement`) and height (:mod:`~bhgrasp.bench.height`) rules are built on it.
"""

from __future__ import annotations

import functools
import itertools

import coal
import numpy as np
import pinocchio as pin

import bhgrasp as bh
from bhgrasp._native import default_core
from bhgrasp.bench.objects import BenchObject
from bhgrasp.grasp.probes import coal_transform
from bhgrasp.sim.geometry_text import geometry_text

FLIP = pin.rpy.rpyToMatrix(np.pi, 0.0, 0.0)  # world <- palm-down hand: an upright object's axes in the hand frame
# world <- palm-sideways hand (bench.side): the palm's normal (hand z) along world +x, F3 (hand y) up, F1 -> F2
# (hand x) along world +y
SIDEWAYS = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
ORIENTATIONS = {"top": FLIP, "side": SIDEWAYS}  # a trial's approach -> world <- hand
UPRIGHT = {"top": FLIP, "side": SIDEWAYS.T}  # a trial's approach -> hand <- upright object (FLIP is its own inverse)


class Reach:
    """The proximal angle at which each finger first touches an object placed in the hand frame.

    ``approach``: ``"top"`` (the palm down, :data:`FLIP`) or ``"side"`` (:data:`SIDEWAYS`), the hand's orientation
    in the world, which stands the object upright in the hand frame.
    """

    def __init__(
        self, item: BenchObject, spread: float, opening: float, closed: float = 2.4, approach: str = "top"
    ) -> None:
        self.hand = bh.BarrettHand()
        hand = self.hand
        self._spread = [hand.joint_index(f"{f}_spread") for f in ("F1", "F2")]
        self._proximal = [hand.joint_index(f"{f}_proximal") for f in hand.fingers]
        self._distal = [hand.joint_index(f"{f}_distal") for f in hand.fingers]
        self._lower, self._upper = hand.lower, hand.upper
        self._request = coal.DistanceRequest()
        self._touches: dict[tuple, float] = {}
        self.geometry = self.hand.collision_model()
        self.data = pin.GeometryData(self.geometry)
        self.model_data = self.hand.model.createData()
        self.shape = item.body(0.8).geometry()
        self.spread, self.opening, self.closed = spread, opening, closed
        self.axes = UPRIGHT[approach]  # hand <- object
        self.shapes = {
            finger: [
                i
                for i, g in enumerate(self.geometry.geometryObjects)
                if g.name.startswith(finger) and "knuckle" not in g.name
            ]
            for finger in self.hand.fingers
        }
        objects = self.geometry.geometryObjects
        self._links = {
            f: [(i, objects[i].geometry, objects[i].name) for i in found] for f, found in self.shapes.items()
        }
        # configuration(): every joint but the fingers' at its place, and the angles that keep the fingers' in range
        self._template = hand.neutral()
        self._template[self._spread] = spread
        fingers = self._proximal + self._distal
        rest = np.setdiff1d(np.arange(hand.nq), fingers)
        self._template_in_range = bool(
            (self._template[rest] >= self._lower[rest]).all() and (self._template[rest] <= self._upper[rest]).all()
        )
        self._compiled = None  # the compiled touch search (False: none)
        self._finger_index = {finger: i for i, finger in enumerate(self.hand.fingers)}  # (an unknown one: KeyError)
        self._range = (
            float(self._lower[self._proximal].max()),
            float(self._upper[self._proximal].min()),
            float(self._lower[self._distal].max()),
            float(self._upper[self._distal].min()),
        )

    def distance(self, finger: str, angle: float, centre: np.ndarray, shape: coal.ShapeBase | None = None) -> float:
        """Distance [m] from the finger's links to the object at ``centre`` with every finger at ``angle``.

        ``shape``: another shape placed at ``centre`` (axes as the object's) instead of the object.
        """
        return self._gaps(finger, angle, centre, shape, point=False)[0]

    def nearest(
        self, finger: str, angle: float, centre: np.ndarray, shape: coal.ShapeBase | None = None
    ) -> tuple[float, str, np.ndarray]:
        """The finger's link nearest the object at ``angle`` (every finger there).

        (distance [m], the link's shape name, the nearest point on the object [m], hand frame).
        """
        return self._gaps(finger, angle, centre, shape, point=True)

    def _gaps(
        self, finger: str, angle: float, centre: np.ndarray, shape: coal.ShapeBase | None, point: bool
    ) -> tuple[float, str, np.ndarray]:
        """:meth:`nearest`; the point on the object is read only if ``point`` (else zeros)."""
        q = self.configuration(angle)
        pin.updateGeometryPlacements(self.hand.model, self.model_data, self.geometry, self.data, q)
        placement = coal.Transform3s(self.axes, centre)
        shape = self.shape if shape is None else shape
        least, nearest, where = np.inf, "", None
        placements = self.data.oMg
        for i, link, name in self._links[finger]:
            result = coal.DistanceResult()
            gap = coal.distance(link, coal_transform(placements[i]), shape, placement, self._request, result)
            if gap < least:
                least, nearest = gap, name
                where = np.asarray(result.getNearestPoint2()) if point else None
        return least, nearest, np.zeros(3) if where is None else where

    def open_distance(self, shape: coal.ShapeBase, where: coal.Transform3s) -> float:
        """The least distance [m] from the open hand (every finger at ``opening``) to ``shape`` at ``where``.

        Every collision shape of the hand; ``where`` in the hand frame.
        """
        q = self.configuration(self.opening)
        pin.updateGeometryPlacements(self.hand.model, self.model_data, self.geometry, self.data, q)
        return min(
            coal.distance(link.geometry, coal_transform(self.data.oMg[i]), shape, where, self._request, result)
            for i, link in enumerate(self.geometry.geometryObjects)
            for result in [coal.DistanceResult()]
        )

    def configuration(self, angle: float) -> np.ndarray:
        """Every finger at proximal ``angle`` [rad], the distal at a third, both spreads at ``spread``.

        As ``hand.configuration(...)`` builds it, without its per-joint checks (the search calls it ~10^5 times a
        trial); outside the joint limits it raises as that does.
        """
        if not (self._template_in_range and self._in_range(angle)):
            fingers = self.hand.fingers  # the checked call names the joint, raises
            return self.hand.configuration(
                F1_spread=self.spread,
                F2_spread=self.spread,
                **{f"{f}_proximal": angle for f in fingers},
                **{f"{f}_distal": angle / 3 for f in fingers},
            )
        q = self._template.copy()
        q[self._proximal] = angle
        q[self._distal] = angle / 3
        return q

    def _in_range(self, angle: float) -> bool:
        """Whether every finger at proximal ``angle`` [rad] (the distal at a third) is within its joints' limits."""
        low, high, distal_low, distal_high = self._range
        return low <= angle <= high and distal_low <= angle / 3 <= distal_high

    def first_touch(self, finger: str, centre: np.ndarray) -> tuple[str, np.ndarray] | None:
        """The link of ``finger`` that touches the object first, and where on the object (its frame [m]).

        ``None`` if the finger closes without touching it.
        """
        angle = self.touch(finger, centre)
        if angle >= self.closed:
            return None
        _, link, point = self.nearest(finger, angle, centre)
        return link, self.axes.T @ (point - centre)

    def touch(self, finger: str, centre: np.ndarray) -> float:
        """The first proximal angle [rad] at which ``finger`` touches (``closed`` if it never does), once per place.

        On the default engine the search runs in one compiled call (``src/touch_search.cpp``: the same Pinocchio and
        coal calls as :meth:`_touch`, its twin, so the same angle to the bit).
        """
        key = (finger, *map(float, centre))
        found = self._touches.get(key)
        if found is None:
            search = self._search()
            if search is None:
                found = self._touch(finger, centre)
            else:
                point = np.array([float(x) for x in centre])
                found = search.touch(self._finger_index[finger], point, self.opening, self.closed)
            self._touches[key] = found
        return found

    def _search(self):
        """The compiled touch search (built at the first touch), or ``None``.

        ``None``: the default engine is Python's, or an angle of the search is outside the joints' range (the twin
        raises there, naming the joint).
        """
        if self._compiled is None:
            core = default_core()
            inside = self._template_in_range and self._in_range(self.opening) and self._in_range(self.closed)
            if core is None or not inside:
                self._compiled = False
            else:
                scene = self.geometry.copy()  # the hand's shapes and the object's, on the universe
                index = scene.addGeometryObject(pin.GeometryObject("reach_object", 0, pin.SE3.Identity(), self.shape))
                self._compiled = core.TouchSearch(
                    model=self.hand.model.saveToString(),
                    geometry=geometry_text(scene),
                    object=index,
                    links=[self.shapes[finger] for finger in self.hand.fingers],
                    configuration=self._template,
                    proximal=self._proximal,
                    distal=self._distal,
                    axes=np.array(self.axes, dtype=float),
                )
        return self._compiled or None

    def _touch(self, finger: str, centre: np.ndarray) -> float:
        low, high = self.opening, self.closed
        if self.distance(finger, low, centre) <= 0.0:
            return low
        if self.distance(finger, high, centre) > 0.0:
            return high
        for _ in range(30):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if self.distance(finger, middle, centre) > 0.0 else (low, middle)
        return high


def placed_corners(shape: coal.CollisionGeometry, placement: pin.SE3) -> np.ndarray:
    """(8, 3) the corners [m] of a shape's local bounding box, placed by ``placement``."""
    shape.computeLocalAABB()
    box = shape.aabb_local
    return np.array([placement.act(np.array(corner)) for corner in itertools.product(*zip(box.min_, box.max_))])


@functools.lru_cache(maxsize=64)
def reach_of(item: BenchObject, spread: float, opening: float, approach: str = "top") -> Reach:
    """The :class:`Reach` of ``item`` at ``spread`` and ``opening``, built once per process (its touches kept)."""
    return Reach(item, spread, opening, approach=approach)


@functools.lru_cache(maxsize=64)
def hand_depth(spread: float, opening: float) -> float:
    """How far [m] below the hand base (hand frame z) its lowest non-finger shape reaches.

    That is the knuckle housings (0.091 m), 11 mm beyond the palm surface; the benchmark's clearances start there.
    """
    reach = reach_of(BenchObject("sphere", (0.01,), 0.1), spread, opening)
    q = reach.hand.configuration(F1_spread=spread, F2_spread=spread)
    pin.updateGeometryPlacements(reach.hand.model, reach.model_data, reach.geometry, reach.data, q)
    shapes = reach.geometry.geometryObjects
    return max(
        float(placed_corners(item.geometry, reach.data.oMg[i])[:, 2].max())
        for i, item in enumerate(shapes)
        if not any(part in item.name for part in ("proximal", "distal"))
    )


__all__ = ["FLIP", "ORIENTATIONS", "SIDEWAYS", "UPRIGHT", "Reach", "hand_depth", "placed_corners", "reach_of"]
