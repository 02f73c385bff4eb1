"""What a controller's sensors get wrong: Gaussian noise on each reading and a measurement delay.

:class:`SensorModel` names the errors (standard deviations in SI units, a delay in seconds); :class:`Sensors` applies
them to the true :class:`~bhgrasp.data.state.State` a simulator hands its controller, so the controller sees what a
real hand's encoders, an object tracker and fingertip force sensors would report:

- joint positions [rad] and velocities [rad/s] (encoders), each coordinate independently;
- the object's position [m] and orientation (a rotation vector of independent N(0, sigma) components [rad], applied
  in the world frame: R' = exp(n) R), and its linear [m/s] and angular [rad/s] velocity (world);
- contact forces [N], each world component independently;
- ``delay`` [s]: every reading is the state of ``delay`` seconds before (the newest one at least that old; the
  start state until then), then the noise is drawn.  Time ``t`` passed to the controller stays the present: a
  delayed reading is what it is, a late picture of the world.
- ``tracker_rate`` [Hz] and ``tracker_latency`` [s]: the object's pose and twist come from a tracker that takes a
  frame every 1 / rate seconds (at 0, 1/rate, ...; rate 0: every control cycle) and delivers it ``latency`` later
  (after the bus's ``delay``): the reading is the newest frame delivered, the same frame (and noise) until the next
  one, with its capture time in :attr:`~bhgrasp.data.state.State.object_time`.

Draws come from one seeded generator, in a fixed order per reading (joint positions, joint velocities, then the
object's position, orientation, linear and angular velocity per object, then contact forces; a tracker's frame
keeps the noise drawn in the cycle it was taken), and a reading whose standard deviation is zero draws
nothing: the same model, seed and run give the same bits.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, fields, replace

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_real
from bhgrasp.data import State
from bhgrasp.errors import InputError

TIMING = ("delay", "tracker_rate", "tracker_latency")


@dataclass(frozen=True)
class SensorModel:
    """Standard deviations of the readings' Gaussian noise (SI units, world frame) and their delay [s].

    Attributes:
        joint_position: [rad]; joint_velocity: [rad/s].
        object_position: [m]; object_rotation: [rad] per rotation-vector component.
        object_velocity: [m/s]; object_angular_velocity: [rad/s].
        contact_force: [N] per force component.
        delay: [s] the age of every reading.
        tracker_rate: [Hz] the object tracker's frame rate (0: a frame every control cycle).
        tracker_latency: [s] the age of a tracker frame when it is delivered (on top of ``delay``).
    """

    joint_position: float = 0.0
    joint_velocity: float = 0.0
    object_position: float = 0.0
    object_rotation: float = 0.0
    object_velocity: float = 0.0
    object_angular_velocity: float = 0.0
    contact_force: float = 0.0
    delay: float = 0.0
    tracker_rate: float = 0.0
    tracker_latency: float = 0.0

    def __post_init__(self) -> None:
        for item in fields(self):
            object.__setattr__(self, item.name, as_real(getattr(self, item.name), item.name))

    @property
    def noisy(self) -> bool:
        """Whether any reading has noise (and so a run needs a seed)."""
        return any(getattr(self, item.name) > 0.0 for item in fields(self) if item.name not in TIMING)

    @property
    def tracked(self) -> bool:
        """Whether the object readings come from a tracker's frames (a frame rate or a latency)."""
        return self.tracker_rate > 0.0 or self.tracker_latency > 0.0

    @property
    def exact(self) -> bool:
        """Whether the sensors report the true state: no noise, no delay, no tracker frames."""
        return not self.noisy and self.delay == 0.0 and not self.tracked


class Sensors:
    """A :class:`SensorModel` at work during one run: its random generator and its memory of past true states."""

    def __init__(self, model: SensorModel, seed: int | None) -> None:
        """Read through ``model``; ``seed`` seeds the noise (required when the model has any)."""
        if not isinstance(model, SensorModel):
            raise InputError(f"`sensors` must be a SensorModel, got {type(model).__name__}")
        if model.noisy and seed is None:
            raise InputError("sensor noise needs a `seed` (runs are deterministic)")
        self.model = model
        self._exact = model.exact  # (a SensorModel is frozen: asked once, not at every reading)
        self.rng = np.random.default_rng(seed)
        self._past: deque[State] = deque()
        self._frames: deque[State] = deque()  # the bus's readings a tracker frame may still be taken from
        self._frame: tuple[float, tuple, np.ndarray] | None = None  # the delivered frame: time, poses, twists
        self._start: float | None = None

    def read(self, state: State) -> State:
        """The state the controller sees at ``state.t``: the delayed true state, with noise."""
        if self._exact:
            return state
        model = self.model
        seen = self._delayed(state) if model.delay > 0.0 else state
        seen = self._noisy(seen) if model.noisy else seen
        return self._tracked(seen) if model.tracked else seen

    def _tracked(self, seen: State) -> State:
        """``seen`` with the object readings of the newest tracker frame delivered by ``seen.t``."""
        model, frames = self.model, self._frames
        if self._start is None:
            self._start = seen.t  # frames are taken at start, start + 1 / rate, ...
        frames.append(seen)
        start = self._start
        ready = seen.t - model.tracker_latency + 1e-12
        if model.tracker_rate > 0.0:
            period = 1.0 / model.tracker_rate
            ready = start + np.floor((ready - start) / period) * period + 1e-12
        while len(frames) > 1 and frames[1].t <= ready:
            frames.popleft()
        taken = frames[0]
        if self._frame is None or self._frame[0] != taken.t:  # a new frame: its noisy readings, drawn once
            self._frame = (taken.t, taken.object_poses, np.array(taken.object_twists))
        _, poses, twists = self._frame
        return replace(seen, object_poses=poses, object_twists=twists, object_time=self._frame[0])

    def _delayed(self, state: State) -> State:
        """The newest remembered state at least ``delay`` old (the oldest one until there is such a state)."""
        past = self._past
        past.append(state)
        cutoff = state.t - self.model.delay + 1e-12
        while len(past) > 1 and past[1].t <= cutoff:
            past.popleft()
        return past[0]

    def _noisy(self, state: State) -> State:
        model, rng = self.model, self.rng
        changes: dict = {}
        if model.joint_position > 0.0:
            changes["q"] = state.q + rng.normal(scale=model.joint_position, size=state.q.shape)
        if model.joint_velocity > 0.0:
            changes["v"] = state.v + rng.normal(scale=model.joint_velocity, size=state.v.shape)
        if state.object_poses and (model.object_position > 0.0 or model.object_rotation > 0.0):
            changes["object_poses"] = tuple(self._pose(pose) for pose in state.object_poses)
        twist_sigmas = ((slice(0, 3), model.object_velocity), (slice(3, 6), model.object_angular_velocity))
        if len(state.object_twists) and any(sigma > 0.0 for _, sigma in twist_sigmas):
            twists = np.array(state.object_twists, dtype=float)
            for row in twists:
                for part, sigma in twist_sigmas:
                    if sigma > 0.0:
                        row[part] += rng.normal(scale=sigma, size=3)
            changes["object_twists"] = twists
        if model.contact_force > 0.0 and len(state.contact_forces):
            forces = state.contact_forces
            changes["contact_forces"] = forces + rng.normal(scale=model.contact_force, size=forces.shape)
        return replace(state, **changes) if changes else state

    def _pose(self, pose: pin.SE3) -> pin.SE3:
        model, rng = self.model, self.rng
        translation = pose.translation.copy()
        rotation = pose.rotation.copy()
        if model.object_position > 0.0:
            translation += rng.normal(scale=model.object_position, size=3)
        if model.object_rotation > 0.0:
            rotation = pin.exp3(rng.normal(scale=model.object_rotation, size=3)) @ rotation
        return pin.SE3(rotation, translation)


__all__ = ["SensorModel", "Sensors"]
