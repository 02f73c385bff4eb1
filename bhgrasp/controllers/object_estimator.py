"""The held object's pose and twist from the fingers' encoders, fused with an external tracker: a Kalman filter.

Rigid-grasp model.  When at least three fingers touch the object (their contact points not on one line), each
touching finger's contact point is *anchored* on its link: fixed in the link's frame where the encoders put the
link at that instant.  From then on the encoders alone say how the grasp moves: the rigid transform
D(q) = (dR, dt) that best carries the anchors from where they were to where the joint readings now put them
(:func:`rigid_fit`, least squares), and the object is taken to move with it.  A tracker's reading corrects what the
rigid model leaves out (rolling, the contacts' compliance, slip) and what the anchors were fixed with.

The estimate is the object's pose (p, R) (world, centre of mass) and the covariance P (6 x 6) of its error
e = (p_true - p, log(R_true R^T)) (world, position first).  Each control cycle of length h [s]:

- **Predict** with the grasp's motion since the last cycle, D_k D_(k-1)^-1 = (A, b):
  p <- A p + b, R <- A R, P <- B P B^T + Q h with B = diag(A, A).  Exact for a rigid grasp: the true pose moves
  the same way, so its error turns by A.  Q = diag(q_p I, q_r I) [m^2/s, rad^2/s] is the random walk the model
  leaves out (:attr:`EstimatorSettings.drift`); before a hold (nothing anchored) the object is taken at rest with the
  larger :attr:`EstimatorSettings.free_drift`.
- **Update** with a tracker reading (p_z, R_z) whose noise is N(0, sigma_p^2 I) on the position and R_z = exp(n) R,
  n ~ N(0, sigma_r^2 I): innovation v = (p_z - p, log(R_z R^T)), S = P + N, K = P S^-1, d = K v, p <- p + d[:3],
  R <- exp(d[3:]) R, P <- (I - K) P (I - K)^T + K N K^T (Joseph form, symmetric and positive by construction).
  Only a new tracker frame updates (:attr:`~bhgrasp.data.state.State.object_time` changed).  A frame taken L [s]
  before now is first carried by the grasp's motion since it was taken, C(t) C(t - L)^-1 (C: the predictions'
  product; the identity before a hold), and its noise grows by Q L: a slow, late tracker costs no lag.  (That drift
  is also in P, so the two are not independent as the update takes them: P comes out smaller by 2 K (1 - K) Q L,
  at most about 5 % of the tracker's variance before a hold, negligible during one.)  A frame older than
  :data:`HORIZON` is skipped.
- **Twist**: during a hold, from the anchors' velocities J_i(q) v (the encoders' rates): the least-squares
  (v_o, w) of a_dot_i = v_o - skew(a_i - p) w, at the estimated centre of mass; before one, the tracker's twist.

For a still object with a still hand the filter is the scalar random-walk Kalman filter on each axis, whose
steady-state variance is closed form (:func:`steady_variance`; tests/test_object_estimator.py checks both the
filter's P and the spread of its estimates against it).  Left out: the contact forces as the process input (the
object's dynamics), a rolling model of the contacts, and a prediction over the bus's delay (every reading alike).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_vector
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.grasp.rigid_fit import rigid_fit, span
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.hand import Hand

MIN_SPAN = 5e-3  # [m] the anchors' least distance from the line through two of them: below it, no hold
HORIZON = 1.0  # [s] how long the grasp's motion is remembered to carry a late tracker frame


@dataclass(frozen=True)
class EstimatorSettings:
    """The filter's noise model (standard deviations, SI units, world frame).

    Attributes:
        tracker: (sigma [m], sigma [rad]) of the tracker's position and rotation-vector noise, per component.
        drift: (sqrt(q_p) [m/sqrt(s)], sqrt(q_r) [rad/sqrt(s)]): the random walk of the object relative to the
            rigid grasp (rolling, compliance, slip) while held.
        free_drift: The same before a hold (the object pushed by the closing fingers, not yet carried).

    The defaults are the geometric means of what :func:`~bhgrasp.scenarios.estimation.rigid_model_drift` measures
    on the grasp demo with exact sensing (boxes of 0.2, 0.6 and 1.0 kg; not the noisy robustness runs): over 1 s
    the rigid model's residual walks at 0.7-1.4e-4 m/sqrt(s) and 0.7-2.3e-3 rad/sqrt(s) (most of it while the box
    turns: the fingertips roll on it); before the hold the box moves at up to 5e-4 m/sqrt(s) (50 ms apart) and
    hardly turns.
    """

    tracker: tuple[float, float] = (5e-4, 5e-3)
    drift: tuple[float, float] = (1e-4, 1.3e-3)
    free_drift: tuple[float, float] = (5e-4, 1.3e-3)

    def __post_init__(self) -> None:
        for name in ("tracker", "drift", "free_drift"):
            values = as_vector(getattr(self, name), name, 2)
            if not (values > 0.0).all():
                raise InputError(f"`{name}` standard deviations must be > 0, got {values.tolist()}")
            object.__setattr__(self, name, (float(values[0]), float(values[1])))


def steady_variance(process: float, measurement: float) -> tuple[float, float]:
    """Steady-state (predicted, corrected) variance of a scalar random walk seen by a noisy reading each step.

    ``process``: the walk's variance per step; ``measurement``: the reading's.  P- solves
    P- = P- r / (P- + r) + q, so P- = (q + sqrt(q^2 + 4 q r)) / 2 and P+ = P- r / (P- + r).
    """
    q, r = float(process), float(measurement)
    predicted = 0.5 * (q + np.sqrt(q * q + 4.0 * q * r))
    return predicted, predicted * r / (predicted + r)


class HeldObjectEstimator:
    """The Kalman filter of the module docstring for one object held by ``hand``.

    Call :meth:`reset` with the first reading, then :meth:`step` once per control cycle with the sensed state
    (encoders, contacts, and the tracker's pose and twist of the object).
    """

    def __init__(
        self, hand: Hand, settings: EstimatorSettings | None = None, index: int = 0, body: str | None = None
    ) -> None:
        """Estimate object ``index`` of the states (its pose in ``state.object_poses[index]``).

        ``body``: the object's name in ``state.contact_bodies`` (a simulator's scene names it
        ``scene.object_names[index]``); only the fingers touching it anchor.  ``None``: contacts with any body.
        """
        if not isinstance(hand, Hand):
            raise InputError(f"`hand` must be a bhgrasp Hand, got {type(hand).__name__}")
        settings = EstimatorSettings() if settings is None else settings
        if not isinstance(settings, EstimatorSettings):
            raise InputError(f"`settings` must be EstimatorSettings, got {type(settings).__name__}")
        self.hand, self.settings, self.index, self.body = hand, settings, int(index), body
        self.sensing = ContactSensing(hand)
        self.position = np.zeros(3)
        self.rotation = np.eye(3)
        self.covariance = np.eye(6)
        self.twist = np.zeros(6)
        self.anchors: list[tuple[str, np.ndarray]] = []  # (link frame, point in the link frame [m])
        self._points = np.zeros((0, 3))  # the anchors in the world at the last cycle
        self._time: float | None = None

    @property
    def holding(self) -> bool:
        """Whether the anchors are set (the rigid-grasp model drives the prediction)."""
        return bool(self.anchors)

    @property
    def pose(self) -> pin.SE3:
        """The estimated pose (world <- object centre of mass)."""
        return pin.SE3(self.rotation.copy(), self.position.copy())

    def reset(self, state: State, covariance: np.ndarray | None = None) -> None:
        """Start from the tracker's reading of ``state``, anchored if three fingers already hold the object.

        ``covariance`` (6 x 6, position [m^2] then rotation [rad^2]): the start's uncertainty (default the
        tracker's noise).
        """
        pose = self._reading(state)
        sigma_p, sigma_r = self.settings.tracker
        start = np.diag([sigma_p**2] * 3 + [sigma_r**2] * 3) if covariance is None else np.array(covariance, float)
        if start.shape != (6, 6) or not np.all(np.isfinite(start)) or np.any(np.linalg.eigvalsh(start) <= 0.0):
            raise InputError(f"`covariance` must be a 6 x 6 positive definite matrix, got {covariance!r}")
        self.position, self.rotation = pose.translation.copy(), pose.rotation.copy()
        self.covariance = 0.5 * (start + start.T)
        self.twist = np.array(state.object_twists[self.index], dtype=float)
        self.anchors, self._points, self._time = [], np.zeros((0, 3)), float(state.t)
        self._carry: deque[tuple[float, pin.SE3]] = deque([(float(state.t), pin.SE3.Identity())])
        self._start = float(state.t)
        self._frame = _frame_time(state)
        self.anchor(state)

    def step(self, state: State) -> tuple[pin.SE3, np.ndarray]:
        """Predict to ``state.t`` from the encoders, correct with the tracker; the (pose, twist) estimate."""
        if self._time is None:
            self.reset(state)
        h = float(state.t) - self._time
        if h < 0.0:
            raise InputError(f"time went backwards: t = {state.t} after {self._time}; call reset() to restart")
        self._time = float(state.t)
        motion = pin.SE3.Identity()
        if self.anchors:  # carried as the grasp was, before a finger that let go is dropped (none of h is lost)
            motion = self._predict_held(state, h)
        else:
            self._spread(np.eye(3), h, self.settings.free_drift)
            self.twist = np.array(state.object_twists[self.index], dtype=float)
        fingers = self._fingers(state)
        if self.anchors and not all(fingers[self.sensing.finger_of(link)].touching for link, _ in self.anchors):
            self.anchors, self._points = [], np.zeros((0, 3))  # a finger let go: the grasp no longer carries it
        if not self.anchors:
            self.anchor(state, fingers)
        carry = self._carry
        carry.append((self._time, motion * carry[-1][1]))
        while len(carry) > 1 and carry[1][0] <= self._time - HORIZON:
            carry.popleft()
        frame = _frame_time(state)
        if frame != self._frame:  # a new tracker frame
            self._frame = frame
            self._update(self._reading(state), frame)
        return self.pose, self.twist.copy()

    def _fingers(self, state: State) -> dict:
        """Per finger, its contacts with the object (with any body when ``body`` is ``None``)."""
        return self.sensing.fingers(state, self.body)

    def _reading(self, state: State) -> pin.SE3:
        if len(state.object_poses) <= self.index:
            raise InputError(f"the state has no object {self.index} (it has {len(state.object_poses)})")
        return state.object_poses[self.index]

    def anchor(self, state: State, fingers: dict | None = None) -> bool:
        """Anchor each touching finger's contact point on its link if three or more span a plane; whether it did.

        The points are fixed in their links' frames where the encoders of ``state`` put the links (the contact
        locations as a tactile pad reads them).  ``fingers``: the state's :meth:`ContactSensing.fingers`, if read.
        """
        fingers = self._fingers(state) if fingers is None else fingers
        touching = [contact for contact in fingers.values() if contact.touching]
        points = np.array([contact.point for contact in touching]).reshape(-1, 3)
        if len(touching) < 3 or span(points) < MIN_SPAN:
            return False
        hand = self.hand
        self.anchors = [
            (contact.link, hand.frame_placement(state.q, contact.link).actInv(contact.point)) for contact in touching
        ]
        self._points = self.anchor_points(state.q)
        return True

    def anchor_points(self, q: np.ndarray) -> np.ndarray:
        """The anchors in the world [m], (n, 3), where the encoders ``q`` put their links (one kinematics pass)."""
        hand = self.hand
        pin.framesForwardKinematics(hand.model, hand.data, hand.check_q(q))
        base = hand.base.placement
        return np.array([(base * hand.data.oMf[hand.frame_id(link)]).act(point) for link, point in self.anchors])

    def _predict_held(self, state: State, h: float) -> pin.SE3:
        """Carry the estimate with the anchors' rigid motion since the last cycle; that motion."""
        points = self.anchor_points(state.q)
        turn, shift = rigid_fit(self._points, points)
        self._points = points
        self.position = turn @ self.position + shift
        self.rotation = turn @ self.rotation
        links = [link for link, _ in self.anchors]
        velocities = np.einsum("nij,j->ni", self.hand.point_jacobians(state.q, links, points), state.v)
        arms = points - self.position
        rows = np.zeros((len(points), 3, 6))
        rows[:, :, :3] = np.eye(3)
        rows[:, 0, 4], rows[:, 0, 5] = arms[:, 2], -arms[:, 1]  # -skew(arm): a_dot = v_o + w x arm
        rows[:, 1, 3], rows[:, 1, 5] = -arms[:, 2], arms[:, 0]
        rows[:, 2, 3], rows[:, 2, 4] = arms[:, 1], -arms[:, 0]
        self.twist = np.linalg.lstsq(rows.reshape(-1, 6), velocities.ravel(), rcond=None)[0]
        self._spread(turn, h, self.settings.drift)
        return pin.SE3(turn, shift)

    def _spread(self, turn: np.ndarray, h: float, drift: tuple[float, float]) -> None:
        """P <- B P B^T + Q h, B = diag(turn, turn)."""
        block = np.zeros((6, 6))
        block[:3, :3] = block[3:, 3:] = turn
        walk = np.diag([drift[0] ** 2] * 3 + [drift[1] ** 2] * 3) * h
        covariance = block @ self.covariance @ block.T + walk
        self.covariance = 0.5 * (covariance + covariance.T)

    def _update(self, reading: pin.SE3, frame: float) -> None:
        """Correct with a tracker frame taken at ``frame`` [s], carried to now by the grasp's motion since."""
        carry = self._carry
        if frame < carry[0][0] - 1e-12 and carry[0][0] > self._start:
            return  # older than the grasp's remembered motion (HORIZON): it cannot be carried to now
        then = next((motion for t, motion in reversed(carry) if t <= frame + 1e-12), carry[0][1])
        reading = carry[-1][1] * then.inverse() * reading
        age = max(self._time - frame, 0.0)
        drift = self.settings.drift if self.anchors else self.settings.free_drift
        sigma_p, sigma_r = self.settings.tracker
        noise = np.diag([sigma_p**2 + drift[0] ** 2 * age] * 3 + [sigma_r**2 + drift[1] ** 2 * age] * 3)
        innovation = np.concatenate((reading.translation - self.position, pin.log3(reading.rotation @ self.rotation.T)))
        gain = np.linalg.solve(self.covariance + noise, self.covariance).T  # P S^-1 (P, S symmetric)
        correction = gain @ innovation
        if not np.all(np.isfinite(correction)):
            raise InputError(f"the object estimate's correction is not finite: {correction}")
        self.position = self.position + correction[:3]
        self.rotation = pin.exp3(correction[3:]) @ self.rotation
        keep = np.eye(6) - gain
        covariance = keep @ self.covariance @ keep.T + gain @ noise @ gain.T
        self.covariance = 0.5 * (covariance + covariance.T)


def _frame_time(state: State) -> float:
    """When the state's object readings were taken [s] (its tracker frame's time, else the state's)."""
    return float(state.t if state.object_time is None else state.object_time)


__all__ = ["HORIZON", "MIN_SPAN", "EstimatorSettings", "HeldObjectEstimator", "steady_variance"]
