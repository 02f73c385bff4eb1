"""A reference that can be stopped where it is.

The grasp benchmark's guarded place: the wrist stops where the stand takes the object's weight.
"""

from __future__ import annotations

import numpy as np

from bhgrasp.motion.trajectories import Reference, Sample


class HeldReference(Reference):
    """A reference that can be stopped: from :meth:`hold` on, it stays where it was then, at rest."""

    def __init__(self, reference: Reference) -> None:
        self.reference, self.held = reference, None

    @property
    def size(self) -> int:
        """The wrapped reference's size."""
        return self.reference.size

    def hold(self, t: float) -> None:
        """Stop at ``t`` [s]."""
        self.held = float(t)

    def release(self) -> None:
        """Follow the reference again."""
        self.held = None

    def __call__(self, t: float) -> Sample:
        """The reference at ``t``, or where it stopped (zero rates)."""
        if self.held is None or t < self.held:
            return self.reference(t)
        position, rate, _ = self.reference(self.held)
        return position, np.zeros_like(rate), np.zeros_like(rate)


__all__ = ["HeldReference"]
