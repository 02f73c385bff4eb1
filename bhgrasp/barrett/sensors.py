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
measure "the torque externally applied about the distal joint over a range of +/- 1 N-m".  libbarrett's
``Hand::getFingertipTorque()`` returns the pucks' raw SG property, "a number between 0 and 4095" that reads "around
2000" unloaded, rises as a closing finger presses on something (HSG 3000 stops a close at "~1 kg") and falls under a
push on the finger's back; the firmware's self-preservation acts at "1.14 Nm (SG < 667 or SG > 3460)" (wiki
``Hand/280/KinematicsJointRangesConversionFactors``).  That last pair is the only calibration published in N m, so
the nominal line is SG = 2063.5 - 1225 tau (tau [N m] positive closing the fingertip, about +z of the distal link
frame): 0.82 mN m per count, saturating at -1.66 and +1.68 N m.  Barrett's own "0 to 4095 ... roughly -2 to +2 kg"
agrees to a factor 1.6 (it implies a lever of about 8 cm, where the tip is 5 cm out), and the real hands are
calibrated by their users ("can be calibrated by the customer").

Contacts count on whichever side of a pair the hand link is: an object's (hand link = body a, force on the hand
= -force) and the environment's (a table, stand or wall stops a link: hand link = body b, force on the hand = force).
Tactile pads: :mod:`bhgrasp.barrett.tactile`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_array, as_positive, as_vector
from bhgrasp.barrett.tactile import (
    TACTILE_FULL_SCALE,
    TactilePad,
    digitise_pressures,
    finger_pad,
    pad_pressures,
    palm_pad,
)
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
STRAIN_MAX_COUNTS = 4095  # SG "a number between 0 and 4095"
STRAIN_ZERO = 0.5 * (667 + 3460)  # [counts] unloaded, from the self-preservation thresholds at -/+1.14 N m
STRAIN_PER_NM = (3460 - 667) / (2 * 1.14)  # [counts per N m] 1225, rising as the fingertip is pushed open


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


def strain_counts(torques: np.ndarray) -> np.ndarray:
    """SG counts (int, 0..4095) of fingertip torques [N m] (positive closing): the nominal line, rounded, clipped."""
    counts = np.rint(STRAIN_ZERO - STRAIN_PER_NM * np.asarray(torques, dtype=float))
    return np.clip(counts, 0, STRAIN_MAX_COUNTS).astype(np.int64)


def strain_torques(counts: np.ndarray) -> np.ndarray:
    """Fingertip torques [N m] (positive closing) from SG counts by the nominal line (module docstring)."""
    return (STRAIN_ZERO - np.asarray(counts, dtype=float)) / STRAIN_PER_NM


@dataclass(frozen=True)
class SensorLoads:
    """What the fingertip torque sensors and the pads are subjected to, before their range and resolution.

    Attributes:
        fingertip_torque: (3,) contact torque about each distal joint axis, positive closing [N m].
        tactile: (4, 24) cell pressures of the pads F1, F2, F3, palm [N/cm^2].
    """

    fingertip_torque: np.ndarray
    tactile: np.ndarray


@dataclass(frozen=True)
class BarrettReading:
    """Everything the BH8-280's sensors report at one instant (libbarrett's names and units; arrays read-only).

    Attributes:
        t: Time [s].
        primary_encoder: (4,) motor counts of pucks F1, F2, F3, SPREAD [counts].
        secondary_encoder: (3,) inner-link counts of F1, F2, F3 [counts].
        inner_link_position: (4,) libbarrett's proximal angles from the counts, spread last [rad].
        outer_link_position: (4,) libbarrett's distal angles (relative to the inner link), spread last [rad].
        fingertip_torque: (3,) raw SG counts, 0..4095, as ``Hand::getFingertipTorque()`` returns them [counts].
        fingertip_torque_nm: (3,) the same counts through the nominal line, positive closing [N m].
        tactile: (4, 24) cell pressures of the pads F1, F2, F3, palm, in steps of 1/256 up to 16.0 [N/cm^2].
    """

    t: float
    primary_encoder: np.ndarray
    secondary_encoder: np.ndarray
    inner_link_position: np.ndarray
    outer_link_position: np.ndarray
    fingertip_torque: np.ndarray
    fingertip_torque_nm: np.ndarray
    tactile: np.ndarray

    def __post_init__(self) -> None:
        for value in vars(self).values():
            if isinstance(value, np.ndarray):
                value.flags.writeable = False

    @property
    def strain_saturated(self) -> np.ndarray:
        """(3,) whether each SG count sits at an end of its range (0 or 4095): the torque is beyond it."""
        return (self.fingertip_torque <= 0) | (self.fingertip_torque >= STRAIN_MAX_COUNTS)

    @property
    def tactile_saturated(self) -> np.ndarray:
        """(4, 24) whether each cell reads its full scale (16.0 N/cm^2): the pressure may be higher."""
        return self.tactile >= TACTILE_FULL_SCALE


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
        """All readings at ``state`` as the hardware reports them: encoder counts, SG counts, quantised pads.

        Raises:
            InputError: ``state.q`` or the contact arrays have the wrong shape or are not finite.
        """
        q = as_vector(state.q, "state.q", self.hand.nq)
        primary, secondary = encoder_counts(q[self._proximal], q[self._distal], q[self._spread_index])
        inner, outer = link_positions(primary, secondary)
        loads = self.loads(state)
        strain = strain_counts(loads.fingertip_torque)
        pads = digitise_pressures(loads.tactile)
        return BarrettReading(float(state.t), primary, secondary, inner, outer, strain, strain_torques(strain), pads)

    def loads(self, state: State) -> SensorLoads:
        """The fingertip torques and pad pressures the contacts of ``state`` apply (module docstring).

        Contacts between bodies that are not hand links (object on object) are ignored.

        Raises:
            InputError: ``state.q`` or the contact arrays have the wrong shape or are not finite.
        """
        hand = self.hand
        q = as_vector(state.q, "state.q", hand.nq)
        bodies = tuple(state.contact_bodies)
        m = len(bodies)
        points = as_array(state.contact_points, "state.contact_points", (m, 3))
        normals = as_array(state.contact_normals, "state.contact_normals", (m, 3))
        forces = as_array(state.contact_forces, "state.contact_forces", (m, 3))
        on_a = np.array([self._body_of.get(a, -1) for a, _ in bodies], dtype=int)
        on_b = np.array([self._body_of.get(b, -1) for _, b in bodies], dtype=int)
        hand_is_b = (on_a < 0) & (on_b >= 0)  # the environment stopping a link
        body = np.where(hand_is_b, on_b, on_a)
        on_hand = np.where(hand_is_b[:, None], forces, -forces)  # the force on the hand's link [N]
        pin.framesForwardKinematics(hand.model, hand.data, q)
        placements = {i: hand.base_placement * hand.data.oMf[i] for i in (*self._distal_frames, *self._pad_frames)}
        torque = np.zeros(3)
        for f, frame in enumerate(self._distal_frames):
            rows = body == hand.model.frames[frame].parentJoint
            placement = placements[frame]
            moments = np.cross(points[rows] - placement.translation, on_hand[rows])
            torque[f] = moments.sum(axis=0) @ placement.rotation[:, 2]
        pressing = np.einsum("ij,ij->i", normals, forces)  # along the normal from a to b: pressing on both sides
        tactile = np.zeros((len(self.pads), len(self.pads[0].cells)))
        for p, (pad, frame) in enumerate(zip(self.pads, self._pad_frames)):
            rows = body == hand.model.frames[frame].parentJoint
            placement = placements[frame]
            local = (points[rows] - placement.translation) @ placement.rotation
            tactile[p] = pad_pressures(pad, local, pressing[rows], self.spread)
        return SensorLoads(torque, tactile)


__all__ = [
    "COUNTS_PER_REV",
    "PUCKS",
    "SECONDARY_RATIO",
    "STRAIN_MAX_COUNTS",
    "STRAIN_PER_NM",
    "STRAIN_ZERO",
    "BarrettReading",
    "BarrettSensors",
    "SensorLoads",
    "encoder_counts",
    "link_positions",
    "motor_angles",
    "strain_counts",
    "strain_torques",
]
