"""Pinocchio's MeshCat visualizer as the scene viewer uses it: it loads and names the nodes, and places nothing itself.

:class:`~bhgrasp.viz.scene_viewer.SceneViewer` sets every node's placement from the scene's parts
(:mod:`~bhgrasp.sim.scene_parts`); Pinocchio's visualizer would keep a data of the whole scene model for its own
placements, whose size grows as nv^3 (1.9 GB for 64 free objects).  :class:`NodeLoader` gives it a data of an empty
model and loads the nodes where a fresh data would put them: each geometry at its placement on its joint (a plane
moved along its normal by its offset, a mesh scaled by its scale, as Pinocchio's visualizer does).
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
from pinocchio.visualize import MeshcatVisualizer


class NodeLoader(MeshcatVisualizer):
    """A MeshCat visualizer that loads a scene's geometry nodes.

    Its ``display`` refuses: the scene viewer places the nodes.
    """

    def __init__(self, model: pin.Model, geometry: pin.GeometryModel) -> None:
        super().__init__(model, geometry, geometry, data=pin.Model().createData())

    def updatePlacements(self, geometry_type: pin.GeometryType) -> None:  # noqa: N802 (Pinocchio's name)
        """Each node at its geometry's placement on its joint (what Pinocchio's own gives with a fresh data)."""
        visual = geometry_type == pin.GeometryType.VISUAL
        model = self.visual_model if visual else self.collision_model
        for item in model.geometryObjects:
            placement = item.placement.copy()
            if isinstance(item.geometry, coal.Plane | coal.Halfspace):
                placement.translation += placement.rotation @ (item.geometry.d * item.geometry.n)
            transform = placement.homogeneous
            transform[:3, :3] = transform[:3, :3] @ np.diag(item.meshScale)
            self.viewer[self.getViewerNodeName(item, geometry_type)].set_transform(transform)

    def display(self, q: np.ndarray | None = None) -> None:
        """Not for use: :meth:`SceneViewer.display <bhgrasp.viz.scene_viewer.SceneViewer.display>` places the nodes."""
        raise NotImplementedError("SceneViewer.display places the nodes; this loader only loads them")


__all__ = ["NodeLoader"]
