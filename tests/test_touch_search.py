"""The benchmark's touch search compiled (src/touch_search.cpp) against its Python twin, Reach._touch.

The twin places the hand's shapes with Pinocchio and measures them with coal at each of 32 angles of a bisection;
the compiled search makes the same calls of the same libraries in the same order, so every touch angle must be the
same to the bit: primitives, meshes, from above and from the side, every finger, centres where the finger touches at
once, part way and never.
"""

from __future__ import annotations

import numpy as np
import pytest

from bhgrasp.bench.objects import DEVELOPMENT_SET, MESH_SET
from bhgrasp.bench.reach import Reach


@pytest.mark.parametrize(("approach", "spread"), [("top", 0.0), ("top", 1.0472), ("side", 0.0)])
def test_every_touch_angle_is_the_twins_to_the_bit(approach: str, spread: float) -> None:
    rng = np.random.default_rng(11)
    outcomes = set()
    for item in (*DEVELOPMENT_SET, MESH_SET[-1]):
        reach = Reach(item, spread, 0.8, approach=approach)
        assert reach._search() is not None
        for _ in range(6):
            centre = rng.normal(size=3) * np.array([0.02, 0.02, 0.03]) + np.array([0.0, 0.0, 0.09])
            for finger in reach.hand.fingers:
                compiled, twin = reach.touch(finger, centre), reach._touch(finger, centre)
                assert np.float64(compiled).tobytes() == np.float64(twin).tobytes()
                outcomes.add("at once" if twin == reach.opening else "never" if twin == reach.closed else "part way")
    assert outcomes == {"at once", "part way", "never"}


def test_a_touch_is_searched_once_per_place() -> None:
    reach = Reach(DEVELOPMENT_SET[0], 0.0, 0.8)
    centre = np.array([0.0, 0.01, 0.09])
    angle = reach.touch("F2", centre)
    assert reach.opening < angle < reach.closed
    assert reach._touches[("F2", *centre)] == angle and reach.touch("F2", centre.tolist()) == angle
