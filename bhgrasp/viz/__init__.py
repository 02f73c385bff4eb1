"""MeshCat views of a scene: live display, overlays, animated replays and self-contained HTML export.

A thin layer over :class:`pinocchio.visualize.MeshcatVisualizer` (which loads the scene's hand, objects and fixed
environment from its collision geometry, all primitives for the packaged Barrett hand).  The MeshCat server runs
on 127.0.0.1 and no browser is opened unless asked (``open=True``).  The object is drawn translucent so that the
contact forces and cones inside it show; a light plate marks the ground (world z = 0); the camera frames the
first object.  Overlays:

- contact force arrows (force on the object, ``force_scale`` [m/N]), green while sticking, red while sliding;
- friction cones at the contacts (apex at the contact point, axis along the normal, half-angle atan(mu));
- the object's desired pose (a translucent ghost) from a grasp controller's logged ``object_error``;
- fingertip references (small spheres) from a joint controller's logged ``q_d``.

:meth:`SceneViewer.replay` turns a recorded :class:`~bhgrasp.data.trajectory.Trajectory` into a MeshCat animation
decimated to at most 60 frames per second that loops endlessly (in the live viewer and in the exported page alike);
:meth:`SceneViewer.save_html` writes the scene and its animation as one HTML file that works offline (meshcat's
``static_html``: the JavaScript is inlined).  ``bhgrasp.viz`` is not imported by ``import bhgrasp``.  Modules:
:mod:`~bhgrasp.viz.scene_viewer`, :mod:`~bhgrasp.viz.live_view`, :mod:`~bhgrasp.viz.drawing`,
:mod:`~bhgrasp.viz.parts_visualizer`.
"""

from bhgrasp.viz.drawing import MAX_FPS
from bhgrasp.viz.live_view import LiveView
from bhgrasp.viz.scene_viewer import SceneViewer, save_replay

__all__ = ["MAX_FPS", "LiveView", "SceneViewer", "save_replay"]
