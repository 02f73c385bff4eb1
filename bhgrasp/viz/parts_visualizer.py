"""Pinocchio's MeshCat visualizer placing a scene's nodes from the scene's parts, with no data of the whole model.

Pinocchio's visualizer keeps a data of the whole scene model for its placements, whose size grows as nv^3 (1.9 GB for
64 free objects).  :class:`PartsVisualizer` places the nodes from the scene's parts (:mod:`~bhgrasp.sim.scene_parts`)
instead: before any ``display`` where a fresh data would put them (each joint at the world's origin), then at the
configuration displayed; a plane moved along its normal by its offset and a mesh scaled by its scale, as Pinocchio's
visualizer does.  :class:`~bhgrasp.viz.scene_viewer.SceneViewer` loads and names its nodes through it.
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
from pinocchio.visualize import MeshcatVisualizer

from bhgrasp.sim.scene_parts import SceneParts


class PartsVisualizer(MeshcatVisualizer):
    """A MeshCat visualizer of a scene's geometry whose placements come from the scene's parts."""

    def __init__(self, model: pin.Model, geometry: pin.GeometryModel, parts: SceneParts) -> None:
        super().__init__(model, geometry, geometry, data=pin.Model().createData())
        self._parts = parts

    def display(self, q: np.ndarray | None = None) -> None:
        """Place the nodes at scene configuration ``q`` (default: as last placed)."""
        if q is not None:
            self._parts.forward_kinematics(np.asarray(q, dtype=float))
        self.updatePlacements(pin.GeometryType.VISUAL)

    def updatePlacements(self, geometry_type: pin.GeometryType) -> None:  # noqa: N802 (Pinocchio's name)
        """Each node at its geometry's placement from the parts' last kinematics."""
        visual = geometry_type == pin.GeometryType.VISUAL
        model, data = (self.visual_model, self.visual_data) if visual else (self.collision_model, self.collision_data)
        self._parts.update_geometry_placements(model, data)
        for index, item in enumerate(model.geometryObjects):
            placement = data.oMg[index].copy()
            if isinstance(item.geometry, coal.Plane | coal.Halfspace):
                placement.translation += placement.rotation @ (item.geometry.d * item.geometry.n)
            transform = placement.homogeneous
            transform[:3, :3] = transform[:3, :3] @ np.diag(item.meshScale)
            self.viewer[self.getViewerNodeName(item, geometry_type)].set_transform(transform)


__all__ = ["PartsVisualizer"]
