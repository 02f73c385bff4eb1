"""The scene viewer: a scene in MeshCat, its states displayed, its recorded runs replayed and saved as HTML."""

from __future__ import annotations

import contextlib
import html
import io
from pathlib import Path
from typing import Any

import meshcat
import meshcat.geometry as mg
import numpy as np
import pinocchio as pin
from meshcat.animation import Animation

from bhgrasp._validation import as_positive
from bhgrasp.data import State, Trajectory
from bhgrasp.errors import InputError
from bhgrasp.model.mesh_object import Mesh
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.scene_parts import SceneParts
from bhgrasp.viz import drawing
from bhgrasp.viz.parts_visualizer import PartsVisualizer

STICK, SLIP, CONE, GHOST, TIP = 0x22AA44, 0xDD2222, 0x3377FF, 0xFFAA33, 0xAA33FF
GROUND, GROUND_SIZE = 0xD8D8D0, 0.4  # colour, edge [m] of the ground plate
CAMERA_TARGET = (0.0, 0.0, 0.15)  # [m] between the Barrett hand's fingers (a scene without objects)
CAMERA_OFFSET = (0.12, -0.17, 0.09)  # [m] camera position relative to its target: the grasp fills the frame


class SceneViewer:
    """A MeshCat view of a :class:`~bhgrasp.sim.scene.Scene` (hand, free objects, environment)."""

    def __init__(
        self,
        scene: Scene,
        viewer: meshcat.Visualizer | None = None,
        open: bool = False,
        zmq_url: str | None = None,
        max_contacts: int = 24,
        quiet: bool = False,
    ) -> None:
        """Load the scene into a (new, localhost) MeshCat server.

        Args:
            scene: What to show.
            viewer: An existing ``meshcat.Visualizer`` to draw into (default: start a server on 127.0.0.1).
            open: Open a browser tab on the viewer.
            zmq_url: Connect to a running ``meshcat-server`` instead of starting one.
            max_contacts: Contact overlay slots (contacts beyond this many in one frame are not drawn).
            quiet: Do not print the server's address (e.g. for an HTML export whose server ends with the program).
        """
        if not isinstance(scene, Scene):
            raise InputError(f"`scene` must be a bhgrasp Scene, got {type(scene).__name__}")
        self.scene = scene
        self.max_contacts = int(max_contacts)
        geometry = scene.geometry.copy()
        for index, geometry_object in enumerate(geometry.geometryObjects):
            geometry_object.meshColor = np.array(self._colour(index))
        _draw_meshes_whole(scene, geometry)
        self._geometry = geometry
        self._geometry_data = pin.GeometryData(geometry)
        self._parts = SceneParts(scene.hand_model, scene.model)
        self._visualizer = PartsVisualizer(scene.model, geometry, self._parts)  # loads and names the nodes
        with contextlib.redirect_stdout(io.StringIO()) if quiet else contextlib.nullcontext():
            self._visualizer.initViewer(viewer=viewer, open=open, zmq_url=zmq_url)  # meshcat prints its address
        self._visualizer.loadViewerModel(rootNodeName=drawing.ROOT)
        self.viewer: meshcat.Visualizer = self._visualizer.viewer
        self._overlays_loaded = False
        self._overlay_visible: dict[str, bool] = {}  # what display() last set of each contact overlay
        self.viewer["/Grid"].set_property("visible", False)
        self.viewer["/Axes"].set_property("visible", False)
        # a ground reference: a light plate at world z = 0 (the hand's base)
        ground = self.viewer[f"{drawing.ROOT}/ground"]
        plate = mg.MeshLambertMaterial(color=GROUND, opacity=0.7, transparent=True)
        ground.set_object(mg.Box([GROUND_SIZE, GROUND_SIZE, 0.001]), plate)
        ground.set_transform(drawing.translation([0.0, 0.0, -0.0005]))
        first = scene.objects[0] if scene.objects else None
        first = getattr(first, "body", first)  # a spring-mounted object's rest pose is its body's
        target = np.asarray(CAMERA_TARGET if first is None else first.pose.translation, dtype=float)
        self.look_at(target, target + CAMERA_OFFSET)

    def look_at(self, target: Any, position: Any) -> None:
        """Point the camera from ``position`` to ``target`` (world, z up) [m].

        MeshCat's orbit controls always turn about the viewer's origin, so the scene (everything under the
        ``bhgrasp`` node) is shifted by -target instead of moving the camera's target.
        """
        target = np.asarray(target, dtype=float)
        offset = np.asarray(position, dtype=float) - target
        self.viewer[drawing.ROOT].set_transform(drawing.translation(-target))
        # the camera node's frame is three.js's (y up): world (x, y, z) is (x, z, -y) there
        self.viewer["/Cameras/default/rotated/<object>"].set_property("position", [offset[0], offset[2], -offset[1]])

    def _colour(self, index: int) -> tuple[float, float, float, float]:
        if index in self.scene.object_geometries:
            return drawing.OBJECT_RGBA
        if index in self.scene.environment_geometries:
            return drawing.ENVIRONMENT_RGBA
        return drawing.HAND_RGBA

    @property
    def url(self) -> str:
        """The viewer's address (http://127.0.0.1:...)."""
        return self.viewer.url()

    def node(self, geometry_index: int) -> str:
        """MeshCat path of a geometry object of the scene."""
        geometry_object = self._geometry.geometryObjects[geometry_index]
        return self._visualizer.getViewerNodeName(geometry_object, pin.GeometryType.VISUAL)

    def placements(self, q_hand: Any, object_poses: Any = ()) -> list[np.ndarray]:
        """4 x 4 world placement of every geometry object for hand joints ``q_hand`` and object poses (SE3)."""
        scene = self.scene
        q = pin.neutral(scene.model)
        q[: scene.nq_hand] = np.asarray(q_hand, dtype=float)
        self._parts.forward_kinematics(q)
        self._parts.update_geometry_placements(self._geometry, self._geometry_data)
        result = [placement.homogeneous for placement in self._geometry_data.oMg]
        for geometries, pose in zip(scene.object_geometry_sets, object_poses):
            for index in geometries:
                result[index] = (pose * self._geometry.geometryObjects[index].placement).homogeneous
        return result

    def display(self, state: State) -> None:
        """Show a state (hand joints and object poses) and its contacts."""
        for index, transform in enumerate(self.placements(state.q, state.object_poses)):
            self.viewer[self.node(index)].set_transform(transform)
        self._load_overlays()
        mu = self._friction()
        contacts = list(zip(state.contact_points, state.contact_normals, state.contact_forces))
        for slot in range(self.max_contacts):
            if slot < len(contacts):
                point, normal, force = contacts[slot]
                normal_force = float(force @ normal)
                sliding = np.linalg.norm(force - normal_force * normal) >= 0.999 * mu * normal_force
                overlays = drawing.contact_overlays(point, normal, force, not sliding, drawing.DISPLAY_FORCE_SCALE, mu)
            else:
                overlays = drawing.hidden_overlays()
            for name, (transform, scale, visible) in overlays.items():
                path = f"{drawing.ROOT}/contacts/{slot}/{name}"
                shown = self._overlay_visible.get(path)  # None: not known (after a replay)
                if not visible and shown is False:
                    continue  # hidden and still hidden: nothing to send (a message costs ~1 ms)
                node = self.viewer[path]
                if visible:
                    node.set_transform(transform @ np.diag((*scale, 1.0)))
                if shown is not bool(visible):
                    node.set_property("visible", bool(visible))
                    self._overlay_visible[path] = bool(visible)

    def _friction(self) -> float:
        return self.scene.objects[0].friction if self.scene.objects else 0.8

    def _load_overlays(self) -> None:
        if self._overlays_loaded:
            return
        for slot in range(self.max_contacts):
            base = self.viewer[f"{drawing.ROOT}/contacts/{slot}"]
            arrow = mg.Cylinder(1.0, 0.0015)
            base["stick"].set_object(arrow, mg.MeshLambertMaterial(color=STICK))
            base["slip"].set_object(arrow, mg.MeshLambertMaterial(color=SLIP))
            cone = mg.Cylinder(1.0, radiusTop=1.0, radiusBottom=0.0)
            base["cone"].set_object(cone, mg.MeshLambertMaterial(color=CONE, opacity=0.25, transparent=True))
            for name in ("stick", "slip", "cone"):
                base[name].set_property("visible", False)
                self._overlay_visible[f"{drawing.ROOT}/contacts/{slot}/{name}"] = False
        self._overlays_loaded = True

    def replay(
        self,
        traj: Trajectory,
        fps: float = 30.0,
        force_scale: float = 0.005,
        mu: float | None = None,
        cones: bool = True,
        play: bool = True,
    ) -> Animation:
        """Animate a recorded run in the viewer, decimated to ``fps`` (<= 60) frames per second of sim time.

        Args:
            traj: The run (hand joints, object poses, contacts and the controller log).
            fps: Frames per simulated second, at most 60.
            force_scale: Arrow length per newton [m/N].
            mu: Friction coefficient of the drawn cones (default: the first object's friction).
            cones: Draw friction cones at the contacts.
            play: Start playing at once (otherwise the viewer's Animations/play control starts it); either way the
                replay loops: clip time t shows the run at ``traj.t[0] + t`` and wraps to 0 after the last frame.
        """
        fps = drawing.checked_fps(fps)
        force_scale = as_positive(force_scale, "force_scale")
        if len(traj) < 1:
            raise InputError("`traj` has no samples")
        mu = self._friction() if mu is None else as_positive(mu, "mu")
        frames = drawing.frame_samples(traj.t, fps)
        self._load_overlays()
        ghost = self._load_ghost(traj)
        tips = self._load_tips(traj)
        animation = Animation(default_framerate=fps)
        nodes = [self.node(index) for index in range(self._geometry.ngeoms)]
        for frame, k in enumerate(frames):
            with animation.at_frame(self.viewer, frame) as view:
                poses = drawing.object_poses(traj, k)
                for node, transform in zip(nodes, self.placements(traj.q[k], poses)):
                    view[node].set_transform(transform)
                self._animate_contacts(view, traj, k, force_scale, mu, cones)
                if ghost:
                    drawing.animate_ghost(view, traj, k, poses)
                if tips:
                    self._animate_tips(view, traj, k)
        # three.js LoopRepeat with `repetitions` passes through the clip's end: Infinity loops for ever (a finite
        # count, 0 included, stops at the end and meshcat's animator then pauses and rewinds to the first frame)
        self.viewer.set_animation(animation, play=play, repetitions=drawing.LOOP_FOREVER)
        self._overlay_visible.clear()  # the animation sets the overlays' visibility: display() sends it anew
        return animation

    def _animate_contacts(self, view, traj: Trajectory, k: int, force_scale: float, mu: float, cones: bool) -> None:
        contacts = traj.contacts_at(k)
        count = min(len(contacts["point"]), self.max_contacts)
        for slot in range(self.max_contacts):
            if slot < count:
                point, force = contacts["point"][slot], contacts["force"][slot]
                normal, sticking = contacts["normal"][slot], bool(contacts["sticking"][slot])
                overlays = drawing.contact_overlays(point, normal, force, sticking, force_scale, mu)
            else:
                overlays = drawing.hidden_overlays()
            for name, (transform, scale, visible) in overlays.items():
                node = view[f"{drawing.ROOT}/contacts/{slot}/{name}"]
                node.set_transform(transform)  # animation tracks carry position and rotation; scale on its own
                node.set_property("scale", "vector3", list(scale))
                node.set_property("visible", "boolean", bool(visible and (cones or name != "cone")))

    def _load_ghost(self, traj: Trajectory) -> bool:
        if "object_error" not in traj.log or not self.scene.objects:
            return False
        shape = drawing.meshcat_shape(self.scene.objects[0])
        if shape is None:
            return False
        material = mg.MeshLambertMaterial(color=GHOST, opacity=0.3, transparent=True)
        self.viewer[f"{drawing.ROOT}/desired_pose"].set_object(shape, material)
        return True

    def _load_tips(self, traj: Trajectory) -> bool:
        if "q_d" not in traj.log or traj.log["q_d"].shape[1] != self.scene.hand.nv:
            return False
        for finger in self.scene.hand.fingers:
            self.viewer[f"{drawing.ROOT}/tip_references/{finger}"].set_object(
                mg.Sphere(0.004), mg.MeshLambertMaterial(color=TIP)
            )
        return True

    def _animate_tips(self, view, traj: Trajectory, k: int) -> None:
        q_d = traj.log["q_d"][k]
        visible = bool(np.all(np.isfinite(q_d)))
        tips = self.scene.hand.fingertip_positions(q_d) if visible else np.zeros((len(self.scene.hand.fingers), 3))
        for finger, tip in zip(self.scene.hand.fingers, tips):
            node = view[f"{drawing.ROOT}/tip_references/{finger}"]
            node.set_transform(drawing.translation(tip))
            node.set_property("visible", "boolean", visible)

    def static_html(self) -> str:
        """The scene (and its animation, after :meth:`replay`) as one self-contained HTML page."""
        return self.viewer.static_html()

    def iframe(self, height: int = 450) -> str:
        """:meth:`static_html` in an ``<iframe srcdoc=...>``, for ``IPython.display.HTML`` in a notebook."""
        page = html.escape(self.static_html(), quote=True)
        return f'<iframe srcdoc="{page}" style="width: 100%; height: {int(height)}px; border: none"></iframe>'

    def save_html(self, path: str | Path) -> Path:
        """Write :meth:`static_html` to ``path``; it opens offline in any WebGL browser."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(self.static_html())
        return path

    def close(self) -> None:
        """Stop the MeshCat server this viewer started (a viewer passed in or reached by ``zmq_url`` keeps running)."""
        process = getattr(self.viewer.window, "server_proc", None)
        if process is not None:
            process.kill()
            process.wait()


def save_replay(scene: Scene, trajectory: Trajectory, path: str | Path) -> Path:
    """Write ``trajectory`` on ``scene`` as one self-contained HTML replay at ``path``; returns the path.

    A viewer is started for it on localhost, and stopped.
    """
    viewer = SceneViewer(scene, quiet=True)  # its server ends with this call: no address to print
    try:
        viewer.replay(trajectory)
        return viewer.save_html(path)
    finally:
        viewer.close()


def _draw_meshes_whole(scene: Scene, geometry: pin.GeometryModel) -> None:
    """A mesh object is drawn as its own surface on its first geometry, its other convex pieces hidden (alpha 0)."""
    for item, geometries in zip(scene.objects, scene.object_geometry_sets):
        if isinstance(item, Mesh):
            geometry.geometryObjects[geometries[0]].geometry = item.surface()
            for index in geometries[1:]:
                geometry.geometryObjects[index].meshColor = np.array([0.0, 0.0, 0.0, 0.0])


__all__ = ["CAMERA_OFFSET", "CAMERA_TARGET", "SceneViewer", "save_replay"]
