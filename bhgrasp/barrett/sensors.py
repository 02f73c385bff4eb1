"""The BH8-280's sensors as libbarrett reports them: encoders, fingertip torque sensors, tactile pads.

Encoders (libbarrett ``src/products/hand.cpp`` @109faf60, ``Hand::update``; ``MotorPuck`` 4096 counts/rev): each
puck (F1, F2, F3, SPREAD) counts its motor; each finger's secondary ("breakaway") encoder counts its inner link
through 50:1 (``J2_ENCODER_RATIO``).  libbarrett converts back with ``inner = secondary / 50`` and
``outer = primary (1/125 + 1/375) - inner`` (``J2_RATIO``, ``J3_RATIO``), spread ``primary / 17.5``.

A finger motor's angle is ``93.75 (q_proximal + q_distal)`` (1/125 + 1/375 = 1/93.75): armed, q_distal =
q_proximal / 3 gives 125 q_proximal; broken away, the proximal link holds and the motor turns the distal worm at
93.75:1.  Re-opening (TorqueSwitch mode 2) the real clutch slips, so the real motor angle drifts from this by the
slip and libbarrett's outer angle is off by the same; the simulator has no slip state, so the formula is kept.

Fingertip torque sensor (Barrett wiki ``Hand/280/SystemComponentList``): strain gauges on the distal "tendon"
measure "the torque externally applied about the distal joint over a range of +/- 1 N-m"; the raw SG value "can be
calibrated by the customer", so no documented conversion exists: readings are in N m only, positive closing the
fingertip (about +z of the distal link frame).  Tactile pads: :mod:`bhgrasp.barrett.tactile`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_array, as_positive, as_vector
from bhgrasp.barrett.tactile import TactilePad, finger_pad, pad_pressures, palm_pad
from bhgrasp.barrett.transmission import (
    DISTAL_ALONE_RATIO,
    DISTAL_RATIO,
    FINGERS,
    PROXIMAL_RATIO,
    SPREAD_RATIO,
    BarrettTransmission,
)
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand

COUNTS_PER_REV = 4096  # puck CTS (Robotnik pyHand_api.py sets CTS 4096; libbarrett rpc = 2 pi / cts)
SECONDARY_RATIO = 50.0  # inner link : secondary encoder shaft (libbarrett J2_ENCODER_RATIO)
PUCKS = (*FINGERS, "SPREAD")  # libbarrett's hand puck order (SPREAD_INDEX = 3)
RADIANS_PER_COUNT = 2 * np.pi / COUNTS_PER_REV


def motor_angles(q_proximal: np.ndarray, q_distal: np.ndarray, q_spread: float) -> np.ndarray:
    """(4,) motor shaft angles [rad] of the pucks F1, F2, F3, SPREAD from joint angles [rad] (module docstring)."""
    return np.append(DISTAL_ALONE_RATIO * (np.asarray(q_proximal) + q_distal), SPREAD_RATIO * q_spread)


def encoder_counts(q_proximal: np.ndarray, q_distal: np.ndarray, q_spread: float) -> tuple[np.ndarray, np.ndarray]:
    """Primary counts (4,) per puck and secondary counts (3,) per finger, rounded to integers [counts]."""
    primary = np.rint(motor_angles(q_proximal, q_distal, q_spread) / RADIANS_PER_COUNT).astype(np.int64)
    secondary = np.rint(SECONDARY_RATIO * np.asarray(q_proximal) / RADIANS_PER_COUNT).astype(np.int64)
    return primary, secondary


def link_positions(primary: np.ndarray, secondary: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The (inner, outer) link positions libbarrett computes (4,) [rad] from encoder counts; index 3 is the spread.

    Without ``secondary`` (libbarrett's ``enableBreakawayEncoders(false)``) inner = primary / 125 and outer =
    inner / 3, "only valid before breakaway".
    """
    motor = np.asarray(primary, dtype=float) * RADIANS_PER_COUNT
    if secondary is None:
        inner = motor[:3] / PROXIMAL_RATIO
        outer = inner * PROXIMAL_RATIO / DISTAL_RATIO
    else:
        inner = np.asarray(secondary, dtype=float) * RADIANS_PER_COUNT / SECONDARY_RATIO
        outer = motor[:3] * (1.0 / PROXIMAL_RATIO + 1.0 / DISTAL_RATIO) - inner
    spread = motor[3] / SPREAD_RATIO
    return np.append(inner, spread), np.append(outer, spread)


@dataclass(frozen=True)
class BarrettReading:
    """Everything the BH8-280's sensors report at one instant (libbarrett's names; arrays read-only).

    Attributes:
        t: Time [s].
        primary_encoder: (4,) motor counts of pucks F1, F2, F3, SPREAD [counts].
        secondary_encoder: (3,) inner-link counts of F1, F2, F3 [counts].
        inner_link_position: (4,) libbarrett's proximal angles from the counts, spread last [rad].
        outer_link_position: (4,) libbarrett's distal angles (relative to the inner link), spread last [rad].
        fingertip_torque: (3,) contact torque about each distal joint axis, positive closing [N m].
        tactile: (4, 24) cell pressures of the pads F1, F2, F3, palm [N/cm^2].
    """

    t: float
    primary_encoder: np.ndarray
    secondary_encoder: np.ndarray
    inner_link_position: np.ndarray
    outer_link_position: np.ndarray
    fingertip_torque: np.ndarray
    tactile: np.ndarray

    def __post_init__(self) -> None:
        for value in vars(self).values():
            if isinstance(value, np.ndarray):
                value.flags.writeable = False


class BarrettSensors:
    """Reads a :class:`~bhgrasp.data.state.State` as the BH8-280's sensors would (built once per hand)."""

    def __init__(self, hand: Hand, spread: float = 3e-3) -> None:
        """Locate the joints, the distal links and the pads on ``hand``.

        Args:
            hand: A Barrett hand (possibly mounted).
            spread: Half-width [m] of the square each contact point's force is spread over on a pad; larger than
                half the widest gap between cells (0.5 mm).
        """
        drive = BarrettTransmission(hand)  # checks the joints and indexes them
        self.hand = hand
        self.pads: tuple[TactilePad, ...] = (*(finger_pad(f) for f in FINGERS), palm_pad())
        self.spread = as_positive(spread, "spread")
        widest = max(pad.margin for pad in self.pads)
        if self.spread <= widest:
            raise InputError(f"`spread` must exceed {widest} m (half the widest gap between cells), got {spread}")
        self._spread_index = drive.spread[0]
        self._proximal, self._distal = drive.proximal, drive.distal
        model = hand.model
        self._body_of = {frame.name: frame.parentJoint for frame in reversed(model.frames)}  # first frame of a name
        self._distal_frames = [model.getFrameId(f"{f}_distal_link") for f in FINGERS]
        self._pad_frames = [model.getFrameId(pad.frame) for pad in self.pads]

    def read(self, state: State) -> BarrettReading:
        """All readings at ``state`` (its ``q`` and contacts; contacts on bodies other than hand links are ignored).

        Raises:
            InputError: ``state.q`` or the contact arrays have the wrong shape or are not finite.
        """
        hand = self.hand
        q = as_vector(state.q, "state.q", hand.nq)
        primary, secondary = encoder_counts(q[self._proximal], q[self._distal], q[self._spread_index])
        inner, outer = link_positions(primary, secondary)
        bodies = tuple(state.contact_bodies)
        m = len(bodies)
        points = as_array(state.contact_points, "state.contact_points", (m, 3))
        normals = as_array(state.contact_normals, "state.contact_normals", (m, 3))
        forces = as_array(state.contact_forces, "state.contact_forces", (m, 3))
        body = np.array([self._body_of.get(a, -1) for a, _ in bodies], dtype=int)
        pin.framesForwardKinematics(hand.model, hand.data, q)
        placements = {i: hand.base_placement * hand.data.oMf[i] for i in (*self._distal_frames, *self._pad_frames)}
        torque = np.zeros(3)
        for f, frame in enumerate(self._distal_frames):
            rows = body == hand.model.frames[frame].parentJoint
            placement = placements[frame]
            moments = np.cross(points[rows] - placement.translation, -forces[rows])  # on the hand
            torque[f] = moments.sum(axis=0) @ placement.rotation[:, 2]
        normal_forces = np.einsum("ij,ij->i", normals, forces)
        tactile = np.zeros((len(self.pads), len(self.pads[0].cells)))
        for p, (pad, frame) in enumerate(zip(self.pads, self._pad_frames)):
            rows = body == hand.model.frames[frame].parentJoint
            placement = placements[frame]
            local = (points[rows] - placement.translation) @ placement.rotation
            tactile[p] = pad_pressures(pad, local, normal_forces[rows], self.spread)
        return BarrettReading(float(state.t), primary, secondary, inner, outer, torque, tactile)


__all__ = [
    "COUNTS_PER_REV",
    "PUCKS",
    "SECONDARY_RATIO",
    "BarrettReading",
    "BarrettSensors",
    "encoder_counts",
    "link_positions",
    "motor_angles",
]
