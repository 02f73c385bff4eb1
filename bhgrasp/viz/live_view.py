"""The live view: a controller wrapped so that the viewer shows its run as it goes, in real time."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from bhgrasp.controllers.base import Controller
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.viz.drawing import checked_fps
from bhgrasp.viz.scene_viewer import SceneViewer


class LiveView(Controller):
    """Wrap a controller so that the viewer shows the run as it goes, in real time.

    Use it in place of the controller: ``sim.run(LiveView(controller, viewer), ...)``. A frame is shown at most
    ``fps`` times per simulated second (looked at every ``every`` control calls). With ``realtime`` the run is paced
    to the wall clock: a run faster than real time waits before each frame, and a frame that falls behind real time
    by more than a frame period is skipped (but at least four frames are shown per second of wall time), so the view
    keeps real time even when drawing a frame costs more than its period. ``fps=None`` shows every ``every``-th call.
    """

    MIN_WALL_RATE = 4.0  # [frames/s of wall time] shown even when the run falls behind real time

    def __init__(
        self,
        controller: Callable[[float, State], Any],
        viewer: SceneViewer,
        every: int = 1,
        fps: float | None = 30.0,
        realtime: bool = True,
    ) -> None:
        """Wrap ``controller`` for ``viewer``.

        Args:
            controller: The controller to run.
            viewer: Where the frames go.
            every: Control calls between two looks at whether a frame is due.
            fps: Frames per simulated second, at most 60; ``None``: every look shows a frame.
            realtime: Pace the run to the wall clock (and skip frames that fall behind it).
        """
        super().__init__()
        if not isinstance(viewer, SceneViewer):
            raise InputError(f"`viewer` must be a SceneViewer, got {type(viewer).__name__}")
        if int(every) < 1:
            raise InputError(f"`every` must be a positive integer, got {every}")
        fps = None if fps is None else checked_fps(fps)
        self.controller, self.viewer, self.every, self.fps = controller, viewer, int(every), fps
        self.realtime = bool(realtime)
        self.log = getattr(controller, "log", {})
        self.shown = self.skipped = 0  # frames shown, and frames skipped to keep real time
        self._calls = 0
        self._start: tuple[float, float] | None = None  # (wall clock, simulated time) of the first frame
        self._next = -np.inf  # simulated time of the next frame
        self._last_wall = -np.inf  # wall clock of the last frame shown
        self._behind = False  # a frame was dropped to keep real time: look at every call until one is shown

    def reset(self, state: State) -> None:
        """Reset the wrapped controller and the pacing (the next call shows a frame)."""
        self._calls, self._start, self._next, self._last_wall, self._behind = 0, None, -np.inf, -np.inf, False
        if hasattr(self.controller, "reset"):
            self.controller.reset(state)

    def __call__(self, t: float, state: State) -> np.ndarray:
        """The wrapped controller's command; shows the state when a frame is due."""
        if self._calls % self.every == 0 and self._frame_due(t):
            self.viewer.display(state)
            self._last_wall = time.perf_counter()
            self.shown += 1
        self._calls += 1
        return self.controller(t, state)

    def _frame_due(self, t: float) -> bool:
        if self.fps is None:
            return True
        due = t >= self._next  # a frame's time has come (each counted once)
        if not (due or self._behind):
            return False
        period = 1.0 / self.fps
        if due:
            self._next = t + period
        if not self.realtime:
            return True
        now = time.perf_counter()
        if self._start is None:
            self._start = (now, t)
        behind = (now - self._start[0]) - (t - self._start[1])  # [s] wall time past the simulated time
        if behind < 0.0:
            time.sleep(-behind)  # ahead of real time: wait for the wall clock
        elif behind > period and now - self._last_wall < 1.0 / self.MIN_WALL_RATE:
            self.skipped += due  # behind: drop this frame and look again at the next call
            self._behind = True
            return False
        self._behind = False
        return True


__all__ = ["LiveView"]
