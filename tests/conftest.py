"""Shared fixtures: the packaged Barrett hand and the Allegro hand of example-robot-data."""

from __future__ import annotations

import os

import pytest

import bhgrasp as bh
from bhgrasp._native import core_loads

ALLEGRO = "allegro_hand_description/urdf/allegro_right_hand.urdf"


def pytest_sessionstart(session: pytest.Session) -> None:
    """With ``BHGRASP_REQUIRE_CORE=1`` (CI) a missing compiled core fails the run: its twin tests never skip."""
    if os.environ.get("BHGRASP_REQUIRE_CORE") == "1" and not core_loads():
        raise pytest.UsageError("BHGRASP_REQUIRE_CORE=1 but bhgrasp._core does not load (rebuild: pip install -e .)")


@pytest.fixture(scope="module")
def barrett() -> bh.Hand:
    return bh.BarrettHand()


@pytest.fixture(scope="module")
def allegro() -> bh.Hand:
    return bh.Hand.from_urdf(bh.example_robot_data_urdf(ALLEGRO))
