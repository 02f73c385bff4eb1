"""Shared fixtures: the packaged Barrett hand and the Allegro hand of example-robot-data."""

from __future__ import annotations

import pytest

import bhgrasp as bh

ALLEGRO = "allegro_hand_description/urdf/allegro_right_hand.urdf"


@pytest.fixture(scope="module")
def barrett() -> bh.Hand:
    return bh.BarrettHand()


@pytest.fixture(scope="module")
def allegro() -> bh.Hand:
    return bh.Hand.from_urdf(bh.example_robot_data_urdf(ALLEGRO))
